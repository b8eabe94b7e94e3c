#!/usr/bin/env bash
# The SWIFT table of docs/performance.md: swift-side-by-side at 30/40/50 with ours
# (Sedov's defaults: `gas`, block steps), then ours alone at smaller sizes, 2 threads, one run
# at a time. Options after the two binaries go to every sphexa run (e.g. --scheme best).
# Usage: swift_table.sh SWIFT_BIN OURS_BIN [sphexa options] (SEDOV_SOLUTION set; PYTHON with h5py).
set -u
export PYTHON=${PYTHON:-python3}
SW=$(realpath "${1:?usage: swift_table.sh SWIFT_BIN OURS_BIN [sphexa options]}"); OURS=$(realpath "${2:?usage: swift_table.sh SWIFT_BIN OURS_BIN [sphexa options]}")
shift 2
export SEDOV_SOLUTION=${SEDOV_SOLUTION:?set SEDOV_SOLUTION to the C++ sedov_solution tool (README.md)}
SBS=$(cd "$(dirname "$0")" && pwd)/swift-side-by-side
lscpu | grep "Model name"; date
for n in 30 40 50; do $OURS run sedov -n $n --steps 1 -q --out /tmp/warm$n >/dev/null 2>&1; done
for n in 30 40 50; do
  bash $SBS $SW $OURS sedov $n "$@"
done
ours() { # n, label, options...
  n=$1; label=$2; shift 2
  $OURS run sedov -n $n --steps 1 -q --out /tmp/warm$n >/dev/null 2>&1
  /usr/bin/time -v -o /tmp/ot.txt $OURS run sedov -n $n --end-time 0.05 --threads 2 -q --out /tmp/ours-$label-$n "$@" >/dev/null 2>&1 || { echo "$label $n failed"; return; }
  python3 - /tmp/ours-$label-$n/summary.json /tmp/ot.txt $label $n <<'PY'
import json,sys,re
d=json.load(open(sys.argv[1])); t=open(sys.argv[2]).read()
w=re.search(r'Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)',t).group(1).split(':')
s=0.0
for x in w: s=s*60+float(x)
rss=int(re.search(r'Maximum resident set size \(kbytes\): (\d+)',t).group(1))/1024
l=d['l1']
print(f"ours {sys.argv[3]:12s} {sys.argv[4]}^3: L1 {l['rho']:.4f} / {l['p']:.4f} / {l['v']:.4f}, wall {s:.2f} s, {d['steps']} steps, {d['particle_updates']/1e6:.3f} M updates, RSS {rss:.0f} MiB")
PY
}
opts=("$@")
for n in 20 22 24 26 28 30 34 40 46; do ours $n default "${opts[@]}"; done
date
