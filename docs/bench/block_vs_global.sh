#!/usr/bin/env bash
# Sedov to t = 0.05 under the global step and under block time steps, from
# the same start (--first-step criteria), one run at a time; prints steps,
# particle updates, wall, L1 rho / P / |v|, energy drift, wall and peak RSS
# (KB) from /usr/bin/time.
#   docs/bench/block_vs_global.sh SIDE [more sphexa run options]
# Needs target/release/sphexa (cargo build --release -p sph-apps) and
# python3; writes under target/block-vs-global/.
set -euo pipefail
n=$1; shift
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=$root/target/release/sphexa
out=$root/target/block-vs-global
mkdir -p "$out"
for ts in global block; do
  dir=$out/sedov${n}_$ts
  /usr/bin/time -f "%e %M" -o "$dir.time" "$bin" run sedov -n "$n" --first-step criteria \
    --time-steps "$ts" --out "$dir" -q "$@" > /dev/null
  python3 - "$dir" "$ts" <<'PY'
import json, sys
d, ts = sys.argv[1], sys.argv[2]
s = json.load(open(d + "/summary.json")); l = s["l1"]
t = open(d + ".time").read().split()
print("%-6s %4d steps %3d syncs updates %9d (%.1f full) wall %.2f s  L1 %.4f %.4f %.4f  dE %.2e  rss %s KB"
      % (ts, s["steps"], s["domain_syncs"], s["particle_updates"], s["full_step_equivalents"],
         s["wall_s"], l["rho"], l["p"], l["v"], s["energy_rel_drift"], t[1]))
PY
done
