#!/usr/bin/env python3
"""`zwidth boundary --velocity-filter-* --hand` checked from outside (issue 16).

Reference built here from nothing of zwidth's: G(s) of eq. (1) as factor state
spaces in series (scipy.signal.tf2ss, as region_crosscheck.py); with a hand,
G/(1 + G Z_h) from the transfer-function polynomials (numpy.polymul: N/(D + N Z_h),
only on devices with at most one mode, where that expansion keeps its digits);
SciPy's cont2discrete (ZOH); the filter F(z) by tf2ss of its coefficients; the
loop u = -z^-D (K y + B F (y_k - y_{k-1})/T) as one matrix and its eigenvalues.
Points: 40 B values x ~70 K values per device, classified by the CSV's intervals
and by the eigenvalues; they must agree wherever the eigenvalues' verdict is the
same at K (1 +- 1e-6).
The CSV's K_passive (issue 16 item 3) against Colgate and Schenkel's condition
evaluated here in its own form, b > (T/2)/(1 - cos wT) Re{(1 - e^{-jwT}) H},
H = z^-D (K + B F (1 - z^-1)/T), F by scipy.signal.freqz: affine in K, so the
largest passive K is the minimum over w of (b - q)/p where p > 0 (2e5
frequencies, then 2000 sub-points around the minimum); within 1e-6.
Exit 77 (skipped) when NumPy/SciPy are missing.
"""
import json, os, shutil, subprocess, sys, tempfile
try:
    import numpy as np
    import scipy.signal as ss
except ImportError as e:
    print(f"skipped: {e}")
    sys.exit(77)

zw = sys.argv[1]
T = 1e-3
rng = np.random.default_rng(16)
cases = []
for k in range(5):
    m = 10 ** rng.uniform(-3.5, -1)
    nm = [0, 1, 2, 1, 0][k]
    modes = []
    for i in range(nm):
        w = 2 * np.pi * rng.uniform(30, 400)
        v = w * rng.uniform(0.7, 1.3)
        modes.append({"omega": w, "c": 2 * w * 10 ** rng.uniform(-2.7, -0.5), "v": v,
                      "d": 2 * v * 10 ** rng.uniform(-2.7, -0.5)})
    model = {"m": m, "b": m * 10 ** rng.uniform(0.3, 1.5), "modes": modes}
    fc = 5 * 50 ** rng.uniform()
    a = np.exp(-2 * np.pi * fc * T)
    filt = ([1 - a], [1.0, -a]) if k % 2 == 0 else ([(1 - a) / 2, (1 - a) / 2], [1.0, -a])
    hand = None
    if nm <= 1 and k >= 3:
        M = 0.5 * m
        hand = (M, 2 * model["b"], (2 * np.pi * 4) ** 2 * (m + M))
    cases.append((model, int(rng.integers(0, 21)), filt, hand))

tmp = tempfile.mkdtemp()
failures = total = 0
for n, (model, d, (fb, fa), hand) in enumerate(cases):
    path, csv = (os.path.join(tmp, f"{x}{n}") for x in ("m.json", "b.csv"))
    json.dump(model, open(path, "w"))
    coeffs = "b:" + ",".join(repr(x) for x in fb) + ";a:" + ",".join(repr(x) for x in fa)
    cmd = [zw, "boundary", path, "--delays", str(d), "--b-points", "40", "-o", csv, "--velocity-filter-coeffs", coeffs]
    if hand:
        cmd += ["--hand", ",".join(repr(x) for x in hand)]
    subprocess.run(cmd, check=True, capture_output=True)
    if hand is None:
        factors = [([1.0], [model["m"], model["b"], 0.0])]
        for md in model["modes"]:
            w, c, v, dd = md["omega"], md["c"], md["v"], md["d"]
            factors.append((np.array([1.0, dd, v * v]) * w * w / (v * v), [1.0, c, w * w]))
        A = np.zeros((0, 0)); Bs = np.zeros((0, 1)); C = np.zeros((1, 0)); Dd = np.zeros((1, 1)); first = True
        for num, den in factors:
            a2, b2, c2, d2 = ss.tf2ss(num, den)
            if first:
                A, Bs, C, Dd, first = a2, b2, c2, d2, False
                continue
            n1, n2 = A.shape[0], a2.shape[0]
            A = np.block([[A, np.zeros((n1, n2))], [b2 @ C, a2]])
            Bs = np.vstack([Bs, b2 @ Dd])
            C = np.hstack([d2 @ C, c2])
            Dd = d2 @ Dd
    else:
        num, den = np.array([1.0]), np.array([model["m"], model["b"], 0.0])
        for md in model["modes"]:
            w, c, v, dd = md["omega"], md["c"], md["v"], md["d"]
            num = np.polymul(num, np.array([1.0, dd, v * v]) * w * w / (v * v))
            den = np.polymul(den, [1.0, c, w * w])
        den = np.polyadd(den, np.polymul(num, list(hand)))
        A, Bs, C, Dd = ss.tf2ss(num, den)
    Ad, Bd, Cd, _, _ = ss.cont2discrete((A, Bs, C, Dd), T, method="zoh")
    nx = Ad.shape[0]
    L = max(len(fb), len(fa)) - 1
    fbp = list(fb) + [0.0] * (L + 1 - len(fb))
    fap = list(fa) + [0.0] * (L + 1 - len(fa))
    Af, Bf, Cf, Df = ss.tf2ss(fbp, fap)  # F as a discrete state space (descending powers of z)
    N = nx + 1 + L + d

    def stable(K, B):
        # states: x, y_{k-1}, filter, delay line of f; f = K y + B v, v = F w, w = (y - y_prev)/T
        y = np.zeros(N); y[:nx] = Cd[0]
        w = y / T; w[nx] -= 1 / T
        v = Df[0, 0] * w
        v[nx + 1:nx + 1 + L] += Cf[0]
        f = K * y + B * v
        Mx = np.zeros((N, N))
        Mx[:nx, :nx] = Ad
        if d == 0:
            Mx[:nx, :] -= np.outer(Bd[:, 0], f)
        else:
            Mx[:nx, nx + 1 + L + d - 1] -= Bd[:, 0]
            Mx[nx + 1 + L, :] = f
            for i in range(1, d):
                Mx[nx + 1 + L + i, nx + 1 + L + i - 1] = 1.0
        Mx[nx, :] = y
        for i in range(L):
            Mx[nx + 1 + i, :] += Bf[i, 0] * w
            Mx[nx + 1 + i, nx + 1:nx + 1 + L] += Af[i]
        return np.max(np.abs(np.linalg.eigvals(Mx))) < 1.0

    rows = np.genfromtxt(csv, delimiter=",", names=True)
    def k_passive(B, th):
        zi = np.exp(-1j * th)
        _, F = ss.freqz(fb, fa, worN=th)
        sh = np.sin(th / 2)  # 1 - e^{-jt} = 2j sin(t/2) e^{-jt/2}, 1 - cos t = 2 sin^2(t/2): digits kept near 0
        g = T / 2 / (2 * sh * sh)
        diff = 2j * sh * np.exp(-0.5j * th)
        p = g * np.real(diff * zi ** d)
        q = g * np.real(diff * zi ** d * B * F * diff / T)
        ratio = np.where(p > 0, (model["b"] - q) / np.where(p > 0, p, 1), np.inf)
        if np.any((p <= 0) & (q >= model["b"])):
            return 0.0, None
        return ratio.min(), th[np.argmin(ratio)]

    worst_p = 0.0
    bs = sorted(set(rows["B"]))
    b_pass = [B for B in bs if rows["K_passive"][rows["B"] == B][0] > 0]
    checked_b = positive_b = 0
    # every passive B (K_passive > 0) and every fourth of the others
    for B in b_pass + [B for B in bs[::4] if B not in b_pass]:
        kp_csv = rows["K_passive"][rows["B"] == B][0]
        th = np.pi * np.arange(1, 200001) / 200000
        kp, t0 = k_passive(B, th)
        if t0 is not None:
            kp2, _ = k_passive(B, np.linspace(max(t0 - 2 * np.pi / 200000, 1e-9), min(t0 + 2 * np.pi / 200000, np.pi), 2001))
            kp = min(kp, kp2)
        kp = max(kp, 0.0)
        checked_b += 1
        positive_b += kp > 0
        err = abs(kp_csv - kp) / max(kp, 1e-300) if kp > 0 else abs(kp_csv)
        worst_p = max(worst_p, err)
        if err > 1e-6:
            failures += 1
            print(f"FAIL case {n} d={d} B={B}: K_passive {kp_csv}, Colgate-Schenkel evaluated here {kp}")
    print(f"case {n}: K_passive at {checked_b} B values ({positive_b} with passive K), worst relative difference "
          f"{worst_p:.1e}")
    if positive_b == 0:
        failures += 1
        print(f"FAIL case {n}: no B value with passive K was checked")
    by_b = {}
    for r in rows:
        by_b.setdefault(r["B"], [])
        if r["interval"] >= 0:
            by_b[r["B"]].append((r["K_lo"], r["K_hi"]))
    kmax = max([hi for iv in by_b.values() for lo, hi in iv if np.isfinite(hi)] + [1.0])
    bad = npts = 0
    for B, iv in by_b.items():
        ks = list(np.geomspace(1e-5 * kmax, 2 * kmax, 60))
        for lo, hi in iv:
            a0 = lo if lo > 0 else 1e-3 * hi
            ks += list(np.geomspace(a0, hi if np.isfinite(hi) else 10 * a0, 12)[1:-1])
        for K in ks:
            mine = any(lo < K < hi for lo, hi in iv)
            ref = stable(K, B)
            npts += 1
            if mine != ref and stable(K * (1 + 1e-6), B) == ref and stable(K * (1 - 1e-6), B) == ref:
                bad += 1
                if bad <= 3:
                    print(f"FAIL case {n} d={d} B={B} K={K}: intervals {iv} say {mine}, eigenvalues say {ref}")
    print(f"case {n} ({len(model['modes'])} modes, d={d}, filter {fb}/{fa}, hand {hand}): {npts} points, "
          f"{bad} disagreements")
    total += npts
    failures += bad
print(f"{total} (K, B) points")
shutil.rmtree(tmp, ignore_errors=True)
sys.exit(1 if failures else 0)
