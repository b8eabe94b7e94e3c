#!/usr/bin/env python3
"""turbulence_spectra.py WORK OURS_BIN [T0 T1]

After `turbulence-side-by-side` (its WORK folder): the velocity power spectrum of every dump
of both codes in [T0, T1] (default 5, 10), each computed by one program, `sphexa spectrum`
(TSC deposit, window deconvolved, grid = N); per run the time mean over its dumps; per code
and shell k the seed mean and seed-to-seed std; the seed-scatter test
|mean_ours - mean_cpp| <= 2 sqrt(s_ours^2/n + s_cpp^2/n) at k = 2..8; and per run the
least-squares slope of ln E over k = 3..8 of its time-mean spectrum. Writes WORK/spectra.json.
Needs numpy and h5py (Debian's python3-h5py: /usr/bin/python3). BOX='--box LO:HI' for dumps
without a box attribute.
"""
import sys, os, glob, subprocess, csv, json
import numpy as np, h5py
work, ours = sys.argv[1], sys.argv[2]
T0 = float(sys.argv[3]) if len(sys.argv) > 3 else 5.0
T1 = float(sys.argv[4]) if len(sys.argv) > 4 else 10.0
tol = 0.02 * 0.8333
BOX = os.environ.get('BOX', '').split() # e.g. '--box -0.5:0.5' for dumps without a box attribute

def spectrum(path, k, out):
    if not os.path.exists(f'{out}/spectrum.csv'):
        subprocess.run([ours, 'spectrum', f'{path}:{k}', '--out', out] + BOX, check=True, capture_output=True)
    rows = list(csv.DictReader(open(f'{out}/spectrum.csv')))
    return np.array([float(r['k']) for r in rows]), np.array([float(r['E']) for r in rows])

res = {}
for d in sorted(glob.glob(f'{work}/stats/*_s*')):
    name = os.path.basename(d)
    code = name.split('_')[0]
    files = [f'{d}/cpp.h5'] if code == 'cpp' else sorted(glob.glob(f'{d}/out/snapshots/*.h5'))
    spectra, times = [], []
    for fn in files:
        with h5py.File(fn, 'r') as f:
            steps = sorted((int(s.split('#')[1]) for s in f.keys() if s.startswith('Step#')))
            tk = [(k, float(np.ravel(f[f'Step#{k}'].attrs['time'])[0])) for k in steps]
        for k, t in tk:
            if T0 - tol <= t <= T1 + tol:
                kk, e = spectrum(fn, k, f'{d}/spectra/{os.path.basename(fn)}_{k}')
                spectra.append(e); times.append(t)
    if not spectra:
        continue
    E = np.mean(spectra, axis=0)
    res[name] = dict(code=code, k=kk.tolist(), E=E.tolist(), times=times)
    print(f'{name}: {len(spectra)} dumps at t = {", ".join(f"{t:.2f}" for t in times)}')

def slope(k, E, lo=3, hi=8):
    m = (k >= lo) & (k <= hi)
    return float(np.polyfit(np.log(k[m]), np.log(E[m]), 1)[0])

out = {}
for code in ('cpp', 'ours'):
    runs = [v for n, v in res.items() if v['code'] == code]
    if not runs:
        continue
    k = np.array(runs[0]['k']); Es = np.array([r['E'] for r in runs])
    lnE = np.log(np.maximum(Es, 1e-300))
    out[code] = dict(n=len(runs), k=k.tolist(), mean=Es.mean(0).tolist(),
                     std=(Es.std(0, ddof=1) if len(runs) > 1 else 0 * Es[0]).tolist(),
                     ln_mean=lnE.mean(0).tolist(),
                     ln_std=(lnE.std(0, ddof=1) if len(runs) > 1 else 0 * lnE[0]).tolist(),
                     slopes=[slope(k, e) for e in Es])
if 'cpp' in out and 'ours' in out:
    k = np.array(out['cpp']['k']); n = min(out['cpp']['n'], out['ours']['n'])
    print(f'\n k   E C++ (mean +- std)        E ours (mean +- std)       ours/C++  |diff|/bound  test')
    allok = True
    rows = []
    for i, kv in enumerate(k):
        if not 1 <= kv <= 10:
            continue
        mc, sc = out['cpp']['mean'][i], out['cpp']['std'][i]
        mo, so = out['ours']['mean'][i], out['ours']['std'][i]
        b = 2 * np.sqrt(so**2 / n + sc**2 / n)
        ok = abs(mo - mc) <= b
        if 2 <= kv <= 8:
            allok &= ok
        rows.append(dict(k=kv, cpp=mc, cpp_std=sc, ours=mo, ours_std=so, bound=b, ok=bool(ok)))
        print(f'{kv:3.0f}  {mc:.4e} +- {sc:.2e}   {mo:.4e} +- {so:.2e}   {mo/mc:7.3f}  {abs(mo-mc)/b:8.2f}  '
              f'{"PASS" if ok else "FAIL"}{"" if 2 <= kv <= 8 else " (outside 2..8)"}')
    print(f'k = 2..8 all within 2 sqrt(s_o^2/n + s_c^2/n): {"PASS" if allok else "FAIL"}')
    # The same test on ln E (the plan's form: a ratio scale, every shell alike).
    ln_ok = True
    ln_rows = []
    for i, kv in enumerate(k):
        if not 2 <= kv <= 8:
            continue
        mc, sc = out['cpp']['ln_mean'][i], out['cpp']['ln_std'][i]
        mo, so = out['ours']['ln_mean'][i], out['ours']['ln_std'][i]
        b = 2 * np.sqrt(so**2 / n + sc**2 / n)
        ok = abs(mo - mc) <= b
        ln_ok &= ok
        ln_rows.append(dict(k=kv, diff=mo - mc, bound=b, ok=bool(ok)))
    print('ln E, k = 2..8: diff / bound ' + ', '.join(f'{r["k"]:.0f}: {abs(r["diff"]) / r["bound"]:.2f}' for r in ln_rows)
          + f': {"PASS" if ln_ok else "FAIL"}')
    out['ln_table'] = ln_rows; out['ln_pass_2_8'] = bool(ln_ok)
    for code in ('cpp', 'ours'):
        s = out[code]['slopes']
        print(f'{code}: slope of ln E over k = 3..8 per seed {", ".join(f"{x:.2f}" for x in s)}; '
              f'mean {np.mean(s):.2f} +- {np.std(s, ddof=1) if len(s) > 1 else 0:.2f}')
    out['table'] = rows; out['pass_2_8'] = bool(allok)
json.dump(dict(runs=res, summary=out), open(f'{work}/spectra.json', 'w'), indent=1)
print(f'wrote {work}/spectra.json')
