# Builds /work/x/swift-cases.md from the kept work folders of swift-side-by-side.
import glob, json, os, re, subprocess, sys
import h5py, numpy as np
S = "/work/main/docs/bench/swift_side.py"
PY = "/usr/bin/python3"
root = sys.argv[1] if len(sys.argv) > 1 else "/work/x/swift-cases"
# other batches: their wall times only (CASE-N folders looked up in each, first found)
others = [a.split("+") for a in sys.argv[2:]]


def other_walls(case, n, sub):
    out = []
    for roots in others:
        for r in roots:
            f = f"{r}/{case}-{n}/{sub}.time"
            if os.path.exists(f):
                out.append(f"{timev(f)[0]:.1f}")
                break
        else:
            out.append("-")
    return out


def timev(path):
    t = open(path).read()
    w = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", t).group(1).split(":")
    s = 0.0
    for x in w:
        s = s * 60 + float(x)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) / 1024
    return s, rss


def metric(case, d, m):
    e = m["l1"]
    if case == "noh":
        return (f"plateau {m['plateau_density']:.1f} ({m['plateau_density'] / m['plateau_density_ref']:.3f} x {m['plateau_density_ref']:.1f}), "
                f"shock {m['shock_radius']:.4f} (ref {m['shock_radius_ref']:.4f}); L1 {e['rho']:.2f} / {e['p']:.3f} / {e['v']:.4f}")
    if case == "sod":
        return (f"L1 {e['rho']:.4f} / {e['p']:.4f} / {e['v']:.4f}; shock {m['shock_radius']:.4f} (ref {m['shock_radius_ref']:.4f}), "
                f"plateau {m['plateau_density']:.4f} (ref {m['plateau_density_ref']:.4f})")
    return f"L1 v_phi {e['v']:.4f} (rho {e['rho']:.4f}, P {e['p']:.4f})"


def run_json(args):
    return json.loads(subprocess.check_output([PY, S] + args + ["--json"]).decode())


rows = []
for case, n in [("noh", 30), ("noh", 37), ("sod", 40), ("sod", 80), ("gresho", 24), ("gresho", 50)]:
    w = f"{root}/{case}-{n}"
    if not os.path.exists(f"{w}/r/summary.json"):
        rows.append(f"| {case} | {n} | | not measured | | | | | |")
        continue
    s1 = json.load(open(f"{w}/r/summary.json"))
    npart = s1["particles"]
    rmax1 = 200 * float(open(f"{w}/r/profile.csv").readlines()[1].split(",")[0])
    out = sorted(glob.glob(f"{w}/sw/out_*.hdf5"))[-1]
    if case == "noh":
        shift = "0.5"
    else:
        snap = sorted(glob.glob(f"{w}/ic/snapshots/*.h5"))[0]
        f = h5py.File(snap, "r")
        g = f[sorted(k for k in f if k.startswith("Step#"))[-1]]
        b = np.ravel(g.attrs["box"])
        shift = ",".join(repr(-x + 0.0) for x in b[0::2])
    extra = [str(n), "--rmax", repr(rmax1)] if case == "noh" else []
    msw = run_json([case, out, shift] + extra)
    ts = np.loadtxt(glob.glob(f"{w}/sw/timesteps*.txt")[0], comments="#")
    sw_steps, sw_upd = int(ts[-1, 0]), float(ts[:, 7].sum())
    wall, rss = timev(f"{w}/sw.time")
    ws = " / ".join([f"{wall:.1f}"] + other_walls(case, n, "sw"))
    rows.append(f"| {case} | {n} | {npart} | SWIFT (SPHENIX) | {metric(case, None, msw)} | {ws} | {sw_steps} | {sw_upd / 1e6:.2f} M | {rss:.0f} |")
    for sub, label in (("r", "ours, case default"), ("r2", "ours, best + AV cleaning")):
        if not os.path.exists(f"{w}/{sub}/summary.json"):
            continue
        m = run_json(["summary", f"{w}/{sub}/summary.json", "--profile", f"{w}/{sub}/profile.csv"])
        s = json.load(open(f"{w}/{sub}/summary.json"))
        wall, rss = timev(f"{w}/{sub}.time")
        note = ""
        if case == "noh" and abs(m["rmax"] - rmax1) > 1e-6:
            msw2 = run_json([case, out, shift, str(n), "--rmax", repr(m["rmax"])])
            note = f" (SWIFT in these bins: shock {msw2['shock_radius']:.4f})"
        ws = " / ".join([f"{wall:.1f}"] + other_walls(case, n, sub))
        rows.append(f"| | | | {label} | {metric(case, None, m)}{note} | {ws} | {s['steps']} | {s['particle_updates'] / 1e6:.2f} M | {rss:.0f} |")
print("| case | N | particles | code | error vs exact | wall s | steps | particle updates | peak RSS MiB |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
print("\n".join(rows))
