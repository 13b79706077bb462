#!/usr/bin/env python3
"""The Z-width and the relay, checked from outside, run by ctest.

The reference is built here from nothing of zwidth's: SciPy's cont2discrete
(ZOH) of Table I's G(s) as a cascade of small state spaces, then the closed loop
of eq. (2) as one matrix (tests/reference_model.py: cascade_zoh,
loop_eigenvalues), whose eigenvalues decide stability. (The roots of the
multiplied-out polynomial z^(d+1) D(z) + (B/T)(z - 1) N(z) + K z N(z), used
before, are ill-conditioned: how well numpy.roots resolves them depends on the
LAPACK selected.) K_cr is found by scanning K on a
geometric grid for the first unstable value and bisecting to 1e-11.

1. `zwidth boundary` at d = 1..10, B = 0:0.01:0.4 (410 points): K_cr within
   1e-6 relative of the reference where K_cr > 0, f_cr within 1e-5, and K_cr = 0
   exactly where the reference is unstable at K = 0+.
2. `zwidth relay --json` at d = 1, 2, 4, 8 and B = 0, 0.6, 0.9 of B_t: K_cr and
   f_cr within 1e-3 of the reference (the issue asks 5 % and 3 %); past B_max it
   reports divergence and K_cr = 0; a crossing below what a 2 s record resolves
   is flagged, not guessed.
Exit 77 (skipped) when NumPy/SciPy are missing.
"""
import json, os, subprocess, sys, tempfile
try:
    import numpy as np
    import scipy.signal as ss
except ImportError as e:
    print(f"skipped: {e}")
    sys.exit(77)
from reference_model import cascade_zoh, loop_eigenvalues

zw, src = sys.argv[1], sys.argv[2]
model_path = os.path.join(src, "datasets/phantom/table1.json")
T = 1e-3
failures = 0


def fail(msg):
    global failures
    failures += 1
    print("FAIL:", msg)


model = json.load(open(model_path))
Ad, Bd, Cd = cascade_zoh(model, T)


def max_root(K, B, d):
    return np.max(np.abs(loop_eigenvalues(Ad, Bd, Cd, K, B, d, T)))


def reference(B, d):
    """(K_cr, f_cr) of the first unstable K; (0, nan) if unstable at K = 0+."""
    ks = np.geomspace(1e-7, 1e4, 400)
    if max_root(ks[0], B, d) > 1.0:
        return 0.0, float("nan")
    prev = ks[0]
    for k in ks[1:]:
        if max_root(k, B, d) > 1.0:
            lo, hi = prev, k
            while hi / lo - 1.0 > 1e-11:
                mid = 0.5 * (lo + hi)
                if max_root(mid, B, d) > 1.0:
                    hi = mid
                else:
                    lo = mid
            r = loop_eigenvalues(Ad, Bd, Cd, hi, B, d, T)
            z = r[np.argmin(np.abs(np.abs(r) - 1.0))]
            return lo, abs(np.angle(z)) / (2 * np.pi * T)
        prev = k
    return float("inf"), float("nan")


tmp = tempfile.mkdtemp()
csv, summary = os.path.join(tmp, "b.csv"), os.path.join(tmp, "s.json")
subprocess.run([zw, "boundary", model_path, "--delays", "1,2,3,4,5,6,7,8,9,10", "--b-max", "0.4",
                "--b-step", "0.01", "-o", csv, "--summary", summary], check=True,
               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
rows = np.genfromtxt(csv, delimiter=",", names=True)
rows = rows[rows["interval"] <= 0]  # one line per (delay, B): K_cr repeats on every interval line
worst_k = worst_f = 0.0
for row in rows:
    d, B, K, f = int(row["delay_samples"]), row["B"], row["K_cr"], row["f_cr_hz"]
    K_ref, f_ref = reference(B, d)
    if K_ref == 0.0:
        if K != 0.0:
            fail(f"d={d} B={B}: reference unstable at K=0+, zwidth K_cr={K}")
        continue
    ek, ef = abs(K / K_ref - 1), abs(f / f_ref - 1)
    worst_k, worst_f = max(worst_k, ek), max(worst_f, ef)
    if ek > 1e-6 or ef > 1e-5:
        fail(f"d={d} B={B}: zwidth K_cr={K} f={f}, reference {K_ref} {f_ref}")
print(f"boundary: {len(rows)} points, worst relative error K_cr {worst_k:.1e}, f_cr {worst_f:.1e}")

bt = {e["delay_samples"]: e["B_t"] for e in json.load(open(summary))["delays"]}
worst = 0.0
for d in (1, 2, 4, 8):
    for frac in (0.0, 0.6, 0.9):
        B = frac * bt[d]
        out = subprocess.run([zw, "relay", model_path, "--delay", str(d), "--damping", repr(B), "--json"],
                             check=True, capture_output=True, text=True).stdout
        j = json.loads(out)
        K_ref, f_ref = reference(B, d)
        ek, ef = abs(j["K_cr"] / K_ref - 1), abs(j["f_cr_hz"] / f_ref - 1)
        worst = max(worst, ek, ef)
        if ek > 1e-3 or ef > 1e-3:
            fail(f"relay d={d} B={B}: K_cr={j['K_cr']} f={j['f_cr_hz']}, reference {K_ref} {f_ref}")
print(f"relay: 12 points, worst relative error {worst:.1e}")

# Past B_max the loop diverges (K_cr = 0, as the reference says); a record too
# short for d = 10's crossing near 3.4 Hz says so instead of guessing.
# B_max_from_zero: where K -> 0+ turns unstable (B_max, the largest B with some
# stable K, is the same here: Table I has no reopened band).
b_max = {e["delay_samples"]: e["B_max_from_zero"] for e in json.load(open(summary))["delays"]}
p = subprocess.run([zw, "relay", model_path, "--delay", "2", "--damping", repr(1.01 * b_max[2]), "--json"],
                   check=True, capture_output=True, text=True)
j = json.loads(p.stdout)
if not (j["diverged"] and j["K_cr"] == 0.0 and reference(1.01 * b_max[2], 2)[0] == 0.0):
    fail(f"relay past B_max: {j}")
p = subprocess.run([zw, "relay", model_path, "--delay", "10", "--damping", "0", "--seconds", "2", "--json"],
                   check=True, capture_output=True, text=True)
j = json.loads(p.stdout)
if not (j["below_band"] and not j["refined"] and "below it" in p.stderr and reference(0.0, 10)[1] < j["band_low_hz"]):
    fail(f"relay, crossing below the band: {j} / {p.stderr}")
sys.exit(1 if failures else 0)
