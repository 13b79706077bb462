#!/usr/bin/env python3
"""The stable K intervals of `zwidth boundary` checked from outside (issue 13).

Reference built here from nothing of zwidth's: each factor of G(s) (rigid body,
then every section) as its own small state space (scipy.signal.tf2ss), joined
by the series-connection rule, SciPy's cont2discrete (ZOH), then the closed loop
of eq. (2) as one matrix over [x_k, v_{k-1} .. v_{k-d}, y_{k-1}] (v the
controller output K y + (B/T)(y_k - y_{k-1}) negated, delayed d samples) and its
eigenvalues. (numpy.roots of the expanded transfer function is not accurate
enough here: with a lightly damped zero it misplaces roots at |z| ~ 1 - 3e-5 by
4e-5.) For the
issue's two devices with reopened bands and three seeded random devices, 40 B
values from 0 to 1.05 B_max x 60 K values (geometric, plus points inside every
interval) are classified by the CSV's intervals and by the roots; they must
agree wherever the roots' verdict is the same at K (1 +- 1e-6).
Exit 77 (skipped) when NumPy/SciPy are missing.
"""
import json, os, shutil, subprocess, sys, tempfile
try:
    import numpy as np
    import scipy.signal as ss
except ImportError as e:
    print(f"skipped: {e}")
    sys.exit(77)
import scipy.linalg as sl
from reference_model import cascade_zoh, loop_eigenvalues

zw = sys.argv[1]
T = 1e-3
rng = np.random.default_rng(13)
devices = [
    ({"m": 2e-3, "b": 0.008, "delay_samples": 1, "modes": [
        {"omega": 439.82, "c": 70.4, "v": 389.56, "d": 46.7}, {"omega": 942.48, "c": 150.8, "v": 848.23, "d": 101.8},
        {"omega": 1633.63, "c": 261.4, "v": 1507.96, "d": 181.0}]}, 4),
    ({"m": 1.53e-3, "b": 6.609e-3, "modes": [
        {"omega": 745.28, "c": 0.15689, "v": 626.46, "d": 0.36921},
        {"omega": 1026.0, "c": 1.8126, "v": 827.44, "d": 0.45092}]}, 5),
]
for k in range(3):
    m = 10 ** rng.uniform(-3.5, -1)
    modes = []
    for i in range(k + 1):
        w = 2 * np.pi * rng.uniform(30, 400)
        v = w * rng.uniform(0.7, 1.3)
        modes.append({"omega": w, "c": 2 * w * 10 ** rng.uniform(-2.7, -0.5), "v": v,
                      "d": 2 * v * 10 ** rng.uniform(-2.7, -0.5)})
    devices.append(({"m": m, "b": m * 10 ** rng.uniform(0.3, 1.5), "modes": modes}, int(rng.integers(0, 21))))

tmp = tempfile.mkdtemp()
failures = total = in_band = 0
for n, (model, d) in enumerate(devices):
    path, csv, summ = (os.path.join(tmp, f"{x}{n}") for x in ("m.json", "b.csv", "s.json"))
    json.dump(model, open(path, "w"))
    subprocess.run([zw, "boundary", path, "--delays", str(d), "--b-points", "40", "-o", csv, "--summary", summ],
                   check=True, capture_output=True)
    dt = d + model.get("delay_samples", 0)
    Ad, Bd, Cd = cascade_zoh(model, T)

    def stable(K, B):
        return np.max(np.abs(loop_eigenvalues(Ad, Bd, Cd, K, B, dt, T))) < 1.0

    rows = np.genfromtxt(csv, delimiter=",", names=True)
    by_b = {}
    for r in rows:
        by_b.setdefault(r["B"], [])
        if r["interval"] >= 0:
            by_b[r["B"]].append((r["K_lo"], r["K_hi"]))
    kmax = max([hi for iv in by_b.values() for lo, hi in iv if np.isfinite(hi)] + [1.0])
    bad = 0
    for B, iv in by_b.items():
        ks = list(np.geomspace(1e-5 * kmax, 2 * kmax, 60))
        for lo, hi in iv:
            a = lo if lo > 0 else 1e-3 * hi
            ks += list(np.geomspace(a, hi, 12)[1:-1])
        for K in ks:
            mine = any(lo < K < hi for lo, hi in iv)
            in_band += mine and any(lo > 0 and lo < K < hi for lo, hi in iv)
            ref = stable(K, B)
            total += 1
            if mine != ref and stable(K * (1 + 1e-6), B) == ref and stable(K * (1 - 1e-6), B) == ref:
                bad += 1
                if bad <= 3:
                    print(f"FAIL device {n} d={d} B={B} K={K}: intervals {iv} say {mine}, roots say {ref}")
    s = json.load(open(summ))["delays"][0]
    print(f"device {n} ({len(model['modes'])} modes, d={d}): B_max_from_zero {s['B_max_from_zero']:.5g}, "
          f"B_max {s['B_max']:.5g}, {len(s['reopened_bands'])} reopened band(s), {bad} disagreements")
    failures += bad
print(f"{total} (K, B) points, {in_band} inside intervals that start above K = 0")
shutil.rmtree(tmp, ignore_errors=True)
sys.exit(1 if failures else 0)
