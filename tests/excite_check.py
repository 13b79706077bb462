#!/usr/bin/env python3
"""zwidth excite checked with NumPy: the printed crest factor and in-band power
fraction against max|x|/rms and a numpy.fft periodogram of the file; the rms;
the multisine's whole number of identical periods and its lines; the noise's
seed. Usage: excite_check.py ZWIDTH SRC. Exit 77 without NumPy."""
import os, re, subprocess, sys, tempfile
try:
    import numpy as np
except ImportError:
    print("skipped: numpy missing"); sys.exit(77)

zw = sys.argv[1]
fails = []
def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok: fails.append(what)

with tempfile.TemporaryDirectory() as d:
    def run(kind, *extra, name=None, rms="0.04", fmin="2", fmax="80"):
        out = os.path.join(d, name or kind + ".txt")
        p = subprocess.run([zw, "excite", "-o", out, "--kind", kind, "--seconds", "20", "--rate", "1000",
                            "--rms", rms, "--fmin", fmin, "--fmax", fmax, *extra], capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        x = np.loadtxt(out, comments="#", skiprows=2)
        crest = float(re.search(r"crest factor ([0-9.]+)", p.stdout).group(1))
        frac = float(re.search(r"([0-9.]+) of the power", p.stdout).group(1))
        return x, crest, frac, p.stdout
    for kind, min_frac, max_crest in (("noise", 0.999999, 6.0), ("multisine", 0.999999, 2.0), ("chirp", 0.95, 1.5)):
        x, crest, frac, text = run(kind)
        rms = np.sqrt(np.mean(x ** 2))
        X = np.fft.rfft(x)
        f = np.fft.rfftfreq(len(x), 1e-3)
        band = (f >= 2 - 1e-9) & (f <= 80 + 1e-9)
        p = np.abs(X) ** 2
        frac_np = p[band].sum() / p.sum()
        crest_np = np.max(np.abs(x)) / rms
        print(f"{kind}: rms {rms:.6g}, crest {crest_np:.4f} (printed {crest}), in band {frac_np:.6f} (printed {frac})")
        check(abs(rms - 0.04) < 1e-6 * 0.04, f"{kind}: rms is the requested 0.04")
        check(abs(crest_np - crest) < 1e-3, f"{kind}: printed crest factor matches max|x|/rms")
        check(abs(frac_np - frac) < 2e-6, f"{kind}: printed in-band power matches the numpy periodogram")
        check(frac_np >= min_frac, f"{kind}: in-band power fraction {frac_np:.6f} >= {min_frac}")
        check(crest_np <= max_crest, f"{kind}: crest factor {crest_np:.3f} <= {max_crest}")
        if kind == "multisine":
            P = int(re.search(r"periods of (\d+) samples", text).group(1))
            n_per = int(re.search(r"(\d+) periods", text).group(1))
            check(len(x) == P * n_per and n_per >= 2, f"multisine: {n_per} whole periods of {P} samples")
            seg = x.reshape(n_per, P)
            check(np.max(np.abs(seg - seg[0])) < 1e-12, "multisine: every period identical")
            lines = np.nonzero(np.abs(np.fft.rfft(seg[0])) > 1e-6 * np.abs(np.fft.rfft(seg[0])).max())[0]
            fl = lines * 1000.0 / P
            check(fl.min() >= 2 - 1e-9 and fl.max() <= 80 + 1e-9 and len(lines) == int(re.search(r"(\d+) lines", text).group(1)),
                  f"multisine: {len(lines)} lines from {fl.min():.3g} to {fl.max():.3g} Hz")
            amps = np.abs(np.fft.rfft(seg[0]))[lines]
            check(np.ptp(amps) < 1e-9 * amps.max(), "multisine: flat amplitude spectrum")
            # Schroeder phases against random phases, same lines (seeded): lower crest.
            rng = np.random.default_rng(1)
            crests = []
            for _ in range(20):
                S = np.zeros(P // 2 + 1, complex); S[lines] = np.exp(2j * np.pi * rng.random(len(lines)))
                y = np.fft.irfft(S, P); crests.append(np.max(np.abs(y)) / np.sqrt(np.mean(y ** 2)))
            check(crest_np < min(crests), f"multisine: crest {crest_np:.3f} below all of 20 random-phase ones (min {min(crests):.3f})")
    # A multisine played into a resonant system (scipy.signal.lfilter, seeded
    # output noise); the first period dropped (transient). --whole-record
    # --period-samples: one segment per period, H against freqz at the lines,
    # errors normalised by the between-period std.
    try:
        from scipy import signal
        x, _, _, text = run("multisine", name="ms.txt")
        P = int(re.search(r"periods of (\d+) samples", text).group(1))
        bz, az = signal.cheby1(2, 1.0, 0.06)   # a 2nd-order resonant low-pass, 1 dB ripple
        y = signal.lfilter(bz, az, np.tile(x, 2))[len(x):]  # steady state: one repeat of the whole signal first
        y = y + 2e-4 * np.random.default_rng(9).standard_normal(len(y))
        log = os.path.join(d, "ms_log.csv")
        np.savetxt(log, np.column_stack([np.arange(len(x)) / 1000.0, x, y]), delimiter=",", header="t,torque,position",
                   comments="", fmt="%.17g")
        frf = os.path.join(d, "ms_frf.csv")
        p = subprocess.run([zw, "estimate", log, "--whole-record", "--period-samples", str(P), "--fmin", "2", "--fmax", "80",
                            "--detrend", "none", "-o", frf], capture_output=True, text=True)
        check(p.returncode == 0, "estimate --whole-record --period-samples runs: " + p.stderr.strip().splitlines()[-1])
        rows = np.genfromtxt(frf, delimiter=",", names=True, comments="#")
        _, g = signal.freqz(bz, az, worN=rows["f_hz"], fs=1000.0)
        H = rows["H_re"] + 1j * rows["H_im"]
        z2 = np.abs(H - g) ** 2 / (2 * rows["H_std"] ** 2)
        rel = np.max(np.abs(H - g) / np.abs(g))
        print(f"periodic estimate: {len(H)} lines, worst |H - G|/|G| {rel:.2e}, mean z^2 {z2.mean():.3f}")
        check(rel < 1e-2, f"periodic estimate within 1 % of freqz (worst {rel:.2e})")
        check(0.6 < z2.mean() < 1.6, f"between-period std matches the error: mean z^2 {z2.mean():.3f}")
        # A rigid body + one resonance/antiresonance section (eq. 1: m 0.01, b 0.2,
        # poles 60 Hz zeta 0.05, zeros 40 Hz zeta 0.05), sampled with scipy's exact
        # ZOH (cont2discrete), driven by a 1..450 Hz multisine (seed 1) in steady
        # state, output noise 1e-9 (seed 5). --whole-record --period-samples with
        # no --detrend must match freqz of the ZOH model (the default was a linear
        # detrend per period, median error ~10x); --detrend linear is warned about.
        x, _, _, text = run("multisine", "--seed", "1", rms="0.03", fmin="1", fmax="450", name="ms_rb.txt")
        P = int(re.search(r"periods of (\d+) samples", text).group(1))
        w0, v0 = 2 * np.pi * 60, 2 * np.pi * 40
        num = np.array([1.0, 2 * 0.05 * v0, v0 * v0]) * (w0 * w0) / (v0 * v0)
        den = np.polymul([0.01, 0.2, 0.0], [1.0, 2 * 0.05 * w0, w0 * w0])
        nd, dd, _ = signal.cont2discrete((num, den), 1e-3, method="zoh")
        nd = np.ravel(nd)
        y = signal.lfilter(nd, dd, np.tile(x, 2))[len(x):] + 1e-9 * np.random.default_rng(5).standard_normal(len(x))
        log = os.path.join(d, "ms_rb_log.csv")
        np.savetxt(log, np.column_stack([np.arange(len(x)) / 1000.0, x, y]), delimiter=",", header="t,torque,position",
                   comments="", fmt="%.17g")
        def periodic(*extra):
            frf = os.path.join(d, "ms_rb_frf.csv")
            p = subprocess.run([zw, "estimate", log, "--whole-record", "--period-samples", str(P), "--fmax", "450",
                                *extra, "-o", frf], capture_output=True, text=True)
            assert p.returncode == 0, p.stderr
            rows = np.genfromtxt(frf, delimiter=",", names=True, comments="#")
            _, g = signal.freqz(nd, dd, worN=rows["f_hz"], fs=1000.0)
            H = rows["H_re"] + 1j * rows["H_im"]
            return np.median(np.abs(H / g - 1)), np.max(np.abs(H / g - 1)), p.stderr
        med, worst, err = periodic()
        print(f"rigid body + mode, whole record, default detrend: median |H/G - 1| {med:.2e}, worst {worst:.2e}")
        check(med < 1e-3 and worst < 1e-2, f"whole-record default detrend matches the exact ZOH response (median {med:.2e})")
        check("warning" not in err, "whole-record default detrend: no warning")
        med, _, err = periodic("--detrend", "linear")
        print(f"same with --detrend linear: median |H/G - 1| {med:.2e}")
        check(med > 1e-1 and "--detrend linear with --whole-record" in err,
              f"--detrend linear with --whole-record is biased (median {med:.2e}) and warned about")
    except ImportError:
        print("scipy missing: periodic estimate not checked")
    a, _, _, _ = run("noise", "--seed", "3", name="a.txt")
    b, _, _, _ = run("noise", "--seed", "3", name="b.txt")
    c, _, _, _ = run("noise", "--seed", "4", name="c.txt")
    check(np.array_equal(a, b) and not np.array_equal(a, c), "noise: same seed same signal, another seed another")
    p = subprocess.run([zw, "excite", "-o", os.path.join(d, "bad.txt"), "--kind", "chirp", "--fmin", "0"], capture_output=True, text=True)
    check(p.returncode == 2 and "fmin must be > 0" in p.stderr and not os.path.exists(os.path.join(d, "bad.txt")),
          "chirp with fmin 0 refused (exit 2, nothing written)")
    p = subprocess.run([zw, "excite", "-o", os.path.join(d, "bad.txt"), "--fmax", "600"], capture_output=True, text=True)
    check(p.returncode == 2 and "Nyquist" in p.stderr, "fmax above Nyquist refused")

print(f"{0 if fails else 1} passed, {len(fails)} failed")
sys.exit(1 if fails else 0)
