#!/usr/bin/env python3
"""Python call overhead of the zwidth module against the C++ time of the same work.

Usage: PYTHONPATH=build/python python3 bench/python_overhead.py [REPEATS] [ZWIDTH_EXE]

Inputs are fixed: the shipped log datasets/phantom/phantom_30s.h5 (fit: 2 modes, delay 0) and
Table I at d = 2, T = 1 ms over B = 0, 1e-4, ..., 0.0999 (1000 values; the sweep). Each call is timed twice
at once: in Python around the call (argument conversion, GIL release, result arrays and objects
included) and in C++ around the library work inside that same call
(zwidth._zwidth._last_cpp_seconds()), so both see the same load on the machine; the overhead is
their difference. The error column is the largest relative difference from the CLI's result for the same work
(`zwidth fit` parameters; `zwidth boundary` K_CR, written with 15 digits).
"""
import json, os, statistics, subprocess, sys, tempfile, time

import numpy as np
import zwidth

repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 15
src = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
frf = zwidth.estimate(zwidth.read_log(os.path.join(src, "datasets/phantom/phantom_30s.h5")))
z = zwidth.ZWidth(zwidth.Model.table1(), 1e-3, 2)
B = 0.0 + np.arange(1000) * 1e-4  # as `zwidth boundary --b-step 1e-4` forms them


def timed(f):
    t = time.perf_counter()
    r = f()
    return time.perf_counter() - t, r


py_fit, cpp_fit, py_sweep, cpp_sweep = [], [], [], []
for _ in range(repeats):
    t, res = timed(lambda: zwidth.fit(frf, modes=2))
    py_fit.append(t)
    cpp_fit.append(zwidth._zwidth._last_cpp_seconds())
    t, (K, _) = timed(lambda: z.critical(B))
    py_sweep.append(t)
    cpp_sweep.append(zwidth._zwidth._last_cpp_seconds())

exe = sys.argv[2] if len(sys.argv) > 2 else os.path.join(src, "build/bin/zwidth")
with tempfile.TemporaryDirectory() as tmp:
    subprocess.run([exe, "fit", os.path.join(src, "datasets/phantom/phantom_30s.h5"), "-o", f"{tmp}/m.json"],
                   check=True, capture_output=True)
    ref = zwidth.Model.load(f"{tmp}/m.json")
    got = np.array([res.model.m, res.model.b, *np.ravel(res.model.modes)])
    want = np.array([ref.m, ref.b, *np.ravel(ref.modes)])
    fit_err = np.max(np.abs(got - want) / np.abs(want))
    json.dump(json.loads(zwidth.Model.table1().to_json()), open(f"{tmp}/t1.json", "w"))
    subprocess.run([exe, "boundary", f"{tmp}/t1.json", "--delays", "2", "--b-step", "1e-4", "--b-max", "0.09995",
                    "-o", f"{tmp}/b.csv"], check=True, capture_output=True)
    k_cli = np.genfromtxt(f"{tmp}/b.csv", delimiter=",", names=True)["K_cr"]
    sweep_err = np.max(np.abs(K - k_cli) / np.maximum(np.abs(k_cli), 1e-300)) if len(k_cli) == len(K) else np.nan
print(f"{'work':31s} {'stat':6s} {'C++ [ms]':>9s} {'Python [ms]':>11s} {'overhead':>9s} {'rel. diff':>9s}")
for name, cpp, py, err in (("fit (2 modes, 1226 bins)", cpp_fit, py_fit, fit_err),
                           ("Z-width sweep (1000 B, d = 2)", cpp_sweep, py_sweep, sweep_err)):
    over = [100 * (p - c) / c for c, p in zip(cpp, py)]
    print(f"{name:31s} {'median':6s} {1e3 * statistics.median(cpp):9.3f} {1e3 * statistics.median(py):11.3f} "
          f"{statistics.median(over):8.2f}% {err:9.1e}")
    print(f"{'':31s} {'max':6s} {'':9s} {'':11s} {max(over):8.2f}%")
print(f"({repeats} calls each; overhead = Python time / C++ time of the same call - 1)")
