#!/usr/bin/env python3
"""The examples/ folder, built and run against the build tree, run by ctest.

Usage: examples_check.py ZWIDTH_EXE BIN_DIR PYTHONPATH SOURCE_DIR

Inputs: Table I (datasets/phantom/table1.json) and two 30 s logs simulated by
`zwidth simulate` from it (white-noise torque at 1 kHz, seeds 1 and 2, text
CSV). References, none of them an example's own code:
1. model_zwidth on Table I: K_CR at B = 0 for d = 1, 2 against a brute force
   built here from SciPy's ZOH (tests/reference_model.py: cascade_zoh, the
   closed loop of eq. (2) as one matrix; bisection on K to 1e-11), within 1e-6
   relative; every number against `zwidth boundary --summary` (the CLI's
   pipeline, analysis::AnalysePlantStability), to the 9 digits printed.
2. scene_check: objects at 0.5 and 1.5 of the brute-force K_CR at B = 0 and one
   inside the reopened band are stable/unstable as the brute force's
   eigenvalues say; exit 3 when one is unstable.
3. log_to_zwidth (C++) on a log: its model file equals `zwidth fit`'s
   plant to 1e-9 relative (the same fit through the CLI); its Z-width numbers
   equal `zwidth boundary --summary` on the model it wrote.
4. log_to_zwidth.py: the same numbers as the C++ example on the same log.
5. batch_of_logs.py on the two logs: two rows, status ok, d2_K_cr_at_zero_B
   equal to the CLI's summary of `zwidth fit` + `zwidth boundary` of each log
   to 6 digits.
Exit 77 (skipped) when NumPy/SciPy are missing.
"""
import json, os, re, subprocess, sys, tempfile
try:
    import numpy as np
    import scipy.signal  # noqa: F401 (reference_model's ZOH)
except ImportError as e:
    print(f"skipped: {e}")
    sys.exit(77)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reference_model import cascade_zoh, first_unstable_k, loop_eigenvalues

zw, bindir, pypath, src = sys.argv[1:5]
table1 = os.path.join(src, "datasets/phantom/table1.json")
T = 1e-3
tmp = tempfile.mkdtemp()
failures = 0


def fail(msg):
    global failures
    failures += 1
    print("FAIL:", msg)


def run(args, ok=(0,), env=None):
    p = subprocess.run(args, capture_output=True, text=True, env=env)
    if p.returncode not in ok:
        print(p.stdout, p.stderr)
        raise SystemExit(f"FAIL: {' '.join(args)} exited {p.returncode}")
    return p


def numbers(text):
    """{(delay, key): value} of the examples' 'delay d: key value ...' lines."""
    out = {}
    for line in text.splitlines():
        m = re.match(r"delay (\d+): (.*)", line)
        if m:
            parts = m.group(2).split()
            for k, v in zip(parts[::2], parts[1::2]):
                out[(int(m.group(1)), k)] = float(v)
    return out


def cli_summary(model, delays):
    s = os.path.join(tmp, "s.json")
    run([zw, "boundary", model, "--delays", ",".join(map(str, delays)), "-o", os.path.join(tmp, "b.csv"),
         "--summary", s])
    return {d["delay_samples"]: d for d in json.load(open(s))["delays"]}


def same(a, b, rel):
    return (np.isinf(a) and np.isinf(b)) or abs(a - b) <= rel * max(abs(a), abs(b))


def compare_with_cli(nums, summary, what):
    n = 0
    for (d, key), v in nums.items():
        if key in summary[d]:
            ref = summary[d][key]
            ref = float("inf") if ref is None else float(ref)
            if not same(v, ref, 5e-9):
                fail(f"{what}: delay {d} {key} = {v!r}, zwidth boundary says {ref!r}")
            n += 1
    return n


model = json.load(open(table1))
Ad, Bd, Cd = cascade_zoh(model, T)


def max_root(K, B, d):
    return np.max(np.abs(loop_eigenvalues(Ad, Bd, Cd, K, B, d, T)))


def kcr_brute(B, d):
    bracket = first_unstable_k(max_root, B, d)
    return 0.0 if bracket is None else bracket[0]


# 1. model_zwidth
p = run([os.path.join(bindir, "example_model_zwidth"), table1, "1", "2"])
nums = numbers(p.stdout)
for d in (1, 2):
    ref = kcr_brute(0.0, d)
    got = nums[(d, "K_cr_at_zero_B")]
    if not same(got, ref, 1e-6):
        fail(f"model_zwidth: delay {d} K_cr(0) = {got}, brute force {ref}")
    print(f"model_zwidth: d = {d}: K_cr(0) = {got:.9g}, brute force (SciPy ZOH, eigenvalues) {ref:.9g}")
n = compare_with_cli(nums, cli_summary(table1, [1, 2]), "model_zwidth")
print(f"model_zwidth: {n} numbers equal zwidth boundary --summary's")
if n < 8:
    fail(f"model_zwidth: only {n} numbers compared")

# 2. scene_check
k0 = kcr_brute(0.0, 2)
objects = [{"name": "soft", "K": 0.5 * k0, "B": 0.0}, {"name": "hard", "K": 1.5 * k0, "B": 0.0},
           {"name": "damped", "K": 20.0, "B": 0.05}]
scene = os.path.join(tmp, "scene.json")
json.dump({"objects": objects}, open(scene, "w"))
p = run([os.path.join(bindir, "example_scene_check"), table1, scene, "2"], ok=(3,))
for o in objects:
    expect = "stable" if max_root(o["K"], o["B"], 2) < 1.0 else "unstable"
    m = re.search(rf"^{o['name']} .*: (\w+) ", p.stdout, re.M)
    if not m or m.group(1) != expect:
        fail(f"scene_check: {o['name']} (K {o['K']:.4g}, B {o['B']}): {m.group(1) if m else p.stdout!r}, "
             f"the eigenvalues say {expect}")
print(f"scene_check: {len(objects)} objects as the brute force's eigenvalues say, exit 3")

# 3. log_to_zwidth (C++)
logs = []
for seed in (1, 2):
    log = os.path.join(tmp, f"log{seed}.csv")
    run([zw, "simulate", "--model", table1, "--seconds", "30", "--seed", str(seed), "-o", log])
    logs.append(log)
cxx_model = os.path.join(tmp, "cxx_model.json")
p = run([os.path.join(bindir, "example_log_to_zwidth"), logs[0], cxx_model], ok=(0, 1))
cxx = numbers(p.stdout)
cli_model = os.path.join(tmp, "cli_model.json")
run([zw, "fit", logs[0], "--modes", "2", "-o", cli_model], ok=(0, 1))
a, b = json.load(open(cxx_model)), json.load(open(cli_model))
for key in ("m", "b"):
    if not same(a[key], b[key], 1e-9):
        fail(f"log_to_zwidth: {key} = {a[key]}, zwidth fit says {b[key]}")
for ma, mb in zip(a["modes"], b["modes"]):
    for key in ("omega", "c", "v", "d"):
        if not same(ma[key], mb[key], 1e-9):
            fail(f"log_to_zwidth: mode {key} = {ma[key]}, zwidth fit says {mb[key]}")
n = compare_with_cli(cxx, cli_summary(cxx_model, [1, 2]), "log_to_zwidth")
print(f"log_to_zwidth: the model equals zwidth fit's; {n} numbers equal zwidth boundary's")

# 4. log_to_zwidth.py
env = dict(os.environ, PYTHONPATH=pypath, ZWIDTH_EXE=zw)
p = run([sys.executable, os.path.join(src, "examples/python/log_to_zwidth.py"), logs[0],
         os.path.join(tmp, "py_model.json")], ok=(0, 1), env=env)
py = numbers(p.stdout)
if py != cxx or len(py) < 6:
    fail(f"log_to_zwidth.py: {py} differs from the C++ example's {cxx}")
print(f"log_to_zwidth.py: the C++ example's {len(py)} numbers, digit for digit")

# 5. batch_of_logs.py
table = os.path.join(tmp, "fleet.csv")
p = run([sys.executable, os.path.join(src, "examples/python/batch_of_logs.py"), table] + logs, ok=(0, 1), env=env)
rows = [line.split() for line in p.stdout.splitlines() if line.startswith(tmp)]
if len(rows) != 2:
    fail(f"batch_of_logs.py: {len(rows)} rows, expected 2: {p.stdout}")
for log, row in zip(logs, rows):
    m = os.path.join(tmp, "m.json")
    run([zw, "fit", log, "-o", m], ok=(0, 1))
    ref = cli_summary(m, [2])[2]["K_cr_at_zero_B"]
    got = float(row[row.index("d2_K_cr_at_zero_B") + 1]) if "d2_K_cr_at_zero_B" in row else float("nan")
    if row[1] != "ok" or not same(got, ref, 1e-6):
        fail(f"batch_of_logs.py: {row}, zwidth fit + boundary say d2_K_cr_at_zero_B = {ref}")
print(f"batch_of_logs.py: {len(rows)} rows ok, K_cr(0) as zwidth fit + boundary of each log")
sys.exit(1 if failures else 0)
