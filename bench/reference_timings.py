#!/usr/bin/env python3
"""The same work as bench/zwidth_benchmark.cc in SciPy and GNU Octave, on the
same inputs (Table I; the shipped 30 s log, made with seed 1 like the
benchmark's), timed on this machine. Prints a Markdown table.
Usage: reference_timings.py ZWIDTH SRC"""
import json, os, shutil, subprocess, sys, tempfile, time
import numpy as np, scipy.signal as ss
from scipy.optimize import least_squares
import h5py

zw, src = sys.argv[1], sys.argv[2]
rows = []
def best_of(fn, n):
    t = []
    for _ in range(n):
        t0 = time.perf_counter(); out = fn(); t.append(time.perf_counter() - t0)
    return min(t), out

with h5py.File(os.path.join(src, "datasets/phantom/phantom_30s.h5")) as f:
    u, y = f["/input/torque"][:], f["/output/position"][:]
mj = json.load(open(os.path.join(src, "datasets/phantom/table1.json")))
T = 1e-3

def tf_of(p):
    num, den = np.array([1.0]), np.array([p[0], p[1], 0.0])
    for w, c, v, d in zip(*[iter(p[2:])] * 4):
        num = np.polymul(num, w**2 / v**2 * np.array([1, d, v**2]))
        den = np.polymul(den, [1, c, w**2])
    return num, den

def zoh_resp(p, f):
    num, den = tf_of(p)
    nd, dd, _ = ss.cont2discrete((num, den), T, method="zoh")
    _, h = ss.freqz(nd.ravel(), dd, worN=2 * np.pi * f * T)
    return h

truth = [mj["m"], mj["b"]] + [x for md in mj["modes"] for x in (md["omega"], md["c"], md["v"], md["d"])]

# 1. Welch: csd + welch + coherence, Hann 4096, 50%, linear detrend.
kw = dict(fs=1000, window="hann", nperseg=4096, noverlap=2048, detrend="linear")
def welch():
    f, Puy = ss.csd(u, y, **kw); _, Puu = ss.welch(u, **kw); _, Pyy = ss.welch(y, **kw)
    return f, Puy / Puu, np.abs(Puy) ** 2 / (Puu * Pyy)
t, (f, H, C) = best_of(welch, 20)
sel = (f >= 0.7) & (f <= 300)
g = zoh_resp(truth, f[sel])
good = C[sel] > 0.99
err = np.percentile(np.abs(H[sel][good] - g[good]) / np.abs(g[good]), 95)
rows.append(("estimate (Welch H1 + coherence)", "SciPy csd/welch", t * 1e3, f"p95 rel err {err:.4f}"))

# 2. Fit: SciPy least_squares on the same weighted complex residual, one start (Table I x 1.1).
frf = os.path.join(tempfile.mkdtemp(), "frf.csv")
subprocess.run([zw, "estimate", os.path.join(src, "datasets/phantom/phantom_30s.h5"), "-o", frf], check=True,
               stderr=subprocess.DEVNULL)
r = np.genfromtxt(frf, delimiter=",", names=True)
Hm = r["H_re"] + 1j * r["H_im"]; s = np.maximum(r["H_std"], 1e-3 * np.abs(Hm))
def resid(x):
    e = (Hm - zoh_resp(np.exp(x), r["f_hz"])) / s
    return np.concatenate([e.real, e.imag])
x0 = np.log(np.array(truth) * 1.1)
t, sol = best_of(lambda: least_squares(resid, x0, method="lm"), 3)
p = np.exp(sol.x)
perr = max(abs(p[i] / truth[i] - 1) for i in (0, 1, 2, 4, 6, 8))
rows.append(("fit (10 parameters, ZOH residual)", "SciPy least_squares, 1 start", t * 1e3, f"max rel err m, b, freqs {perr:.4f}"))

# 3. The paper's margin() loop, eq. (4) as its README reads it (the appendix's
# parenthesis corrected): margin(T/((T z^d)/Gz + B (z-1)/z)), i.e. the gain
# margin of Gz/(z^d + B (z-1)/(T z) Gz), B = 0:0.001:0.099, d = 2.
octave = shutil.which("octave-cli") or shutil.which("octave")
if octave:
    script = """pkg load control;
G=tf(856,[1 5 0])*tf(2296*[1 80 174400],1744*[1 83 229600])*tf(13440*[1 90 298800],2988*[1 352 1344000]);
T=0.001; z=tf([1 0],1,T); Gz=c2d(G,T); v=0:0.001:0.099; K=v*0; tic;
for n=1:numel(v), B=v(n); K(n)=margin(Gz/(z^2 + B*(z-1)/(T*z)*Gz)); end
printf('%.6f\\n', toc); printf('%.12g\\n', K);"""
    out = subprocess.run([octave, "--no-gui", "--quiet", "--eval", script], capture_output=True, text=True)
    vals = out.stdout.split()
    if out.returncode == 0 and len(vals) == 101:
        secs = float(vals[0]); K = np.array([float(v) for v in vals[1:]])
        q = subprocess.run([zw, "boundary", os.path.join(src, "datasets/phantom/table1.json"), "--delays", "2",
                            "--b-max", "0.099", "--b-step", "0.001", "-o", frf], capture_output=True, check=True)
        b = np.genfromtxt(frf, delimiter=",", names=True)
        exact = b["K_cr"]
        rel = np.abs(K - exact) / np.where(exact > 0, exact, np.nan)
        wrong = int(np.sum(~(rel < 1e-3)))
        rows.append(("boundary, 100-point sweep at d = 2", "GNU Octave margin() loop", secs * 1e3,
                     f"{wrong} of 100 values off the exact K_CR by > 0.1%"))
    else:
        rows.append(("boundary, 100-point sweep at d = 2", "GNU Octave margin() loop", float("nan"), "Octave failed: " + out.stderr[:80]))
else:
    rows.append(("boundary, 100-point sweep at d = 2", "GNU Octave margin() loop", float("nan"), "Octave not installed"))

# 4. The whole job as a user waits for it, whole processes (start-up, reading,
# writing included): `zwidth run --no-figures` (estimate, order search, std,
# 1000 B x 3 delays, passivity) against a Python process doing Welch plus the
# one-start SciPy fit above and an Octave process doing margin() over 100 B at
# d = 2, 4, 8 (eq. (4) as above). Medians of 5 runs, alternated.
def whole(cmd):
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True)
    return time.perf_counter() - t0, out.returncode
work = tempfile.mkdtemp()
fit_py = os.path.join(work, "scipy_fit.py")
with open(fit_py, "w") as fh:
    fh.write(f"""import json, numpy as np, scipy.signal as ss, h5py
from scipy.optimize import least_squares
T = 1e-3
with h5py.File({os.path.join(src, "datasets/phantom/phantom_30s.h5")!r}) as f:
    u, y = f["/input/torque"][:], f["/output/position"][:]
kw = dict(fs=1000, window="hann", nperseg=4096, noverlap=2048, detrend="linear")
f, Puy = ss.csd(u, y, **kw); _, Puu = ss.welch(u, **kw); _, Pyy = ss.welch(y, **kw)
sel = (f >= 0.7) & (f <= 300); f, H = f[sel], (Puy / Puu)[sel]
def resp(p):
    num, den = np.array([1.0]), np.array([p[0], p[1], 0.0])
    for w, c, v, d in zip(*[iter(p[2:])] * 4):
        num = np.polymul(num, w**2 / v**2 * np.array([1, d, v**2])); den = np.polymul(den, [1, c, w**2])
    nd, dd, _ = ss.cont2discrete((num, den), T, method="zoh")
    return ss.freqz(nd.ravel(), dd, worN=2 * np.pi * f * T)[1]
def resid(x):
    e = (H - resp(np.exp(x))) / np.abs(H)
    return np.concatenate([e.real, e.imag])
x0 = np.log(np.array({truth!r}) * 1.1)
print(json.dumps(list(np.exp(least_squares(resid, x0, method="lm").x))))
""")
margin_m = os.path.join(work, "margin_sweep.m")
with open(margin_m, "w") as fh:
    fh.write("""pkg load control;
G=tf(856,[1 5 0])*tf(2296*[1 80 174400],1744*[1 83 229600])*tf(13440*[1 90 298800],2988*[1 352 1344000]);
T=0.001; z=tf([1 0],1,T); Gz=c2d(G,T); v=linspace(0,0.099,100);
for d=[2 4 8], for n=1:numel(v), B=v(n); K=margin(Gz/(z^d + B*(z-1)/(T*z)*Gz)); end, end
""")
log_csv = os.path.join(src, "datasets/phantom/phantom_30s.csv")
runs = {"zwidth": [], "scipy": [], "octave": []}
for i in range(5):
    out_dir = os.path.join(work, f"run{i}")
    runs["zwidth"].append(whole([zw, "run", log_csv, "-o", out_dir, "--no-figures"]))
    runs["scipy"].append(whole(["/usr/bin/python3", fit_py]))
    if octave:
        runs["octave"].append(whole([octave, "--no-gui", "--quiet", margin_m]))
med = {k: float(np.median([t for t, rc in v])) if v and all(rc == 0 for _, rc in v) else float("nan")
       for k, v in runs.items()}
anchor = med["scipy"] + med["octave"]
rows.append(("whole job: `zwidth run --no-figures` (process)", "zwidth", med["zwidth"] * 1e3, "median of 5"))
rows.append(("whole job: Welch + 1-start fit (process)", "SciPy", med["scipy"] * 1e3, "median of 5"))
rows.append(("whole job: margin() over 100 B at d = 2, 4, 8 (process)", "GNU Octave", med["octave"] * 1e3,
             "median of 5" if octave else "Octave not installed"))
shutil.rmtree(work, ignore_errors=True)

print("| stage | reference | time [ms] | error |\n|---|---|---|---|")
for st, ref, ms, e in rows:
    print(f"| {st} | {ref} | {ms:.2f} | {e} |")
print(f"\nwhole job, whole processes: (SciPy + Octave) / zwidth run = {anchor:.3f} s / {med['zwidth']:.3f} s = "
      f"{anchor / med['zwidth']:.1f}x")
