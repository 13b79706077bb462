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

# 3. The paper's margin() loop, eq. (4) with the parenthesis corrected, B = 0:0.001:0.099, d = 2.
octave = shutil.which("octave-cli") or shutil.which("octave")
if octave:
    script = """pkg load control;
G=tf(856,[1 5 0])*tf(2296*[1 80 174400],1744*[1 83 229600])*tf(13440*[1 90 298800],2988*[1 352 1344000]);
T=0.001; z=tf([1 0],1,T); Gz=c2d(G,T); v=0:0.001:0.099; K=v*0; tic;
for n=1:numel(v), B=v(n); K(n)=margin(Gz/(z^2 + B*(z-1)/z*Gz)); end
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

print("| stage | reference | time [ms] | error |\n|---|---|---|---|")
for st, ref, ms, e in rows:
    print(f"| {st} | {ref} | {ms:.2f} | {e} |")
