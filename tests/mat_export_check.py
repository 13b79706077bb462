#!/usr/bin/env python3
"""MATLAB/Octave both ways (issue 26, item 4), checked in GNU Octave and h5py.

- export --format mat (v5) with --response: Octave's load gives the parameters, their std, the
  log covariance (and its parameter names), the delay, the period and the measured response
  (f, H, H_std, coherence, averages) equal to model.json and frf.csv to 1e-12 relative.
- export --format mat73 (v7.3, an HDF5 file): the same values read with h5py.
- a response saved by Octave (save -v7) with f, H, coherence and the averages but no std fits
  to the same model as the log it came from, within the model's std, and fit says that it
  derived the std; the std it derived equals Bendat and Piersol's formula computed here.
- a CSV with f, H_re, H_im, coherence and num_averages (no H_std) fits to the same model too.
- a .mat log holding one matrix `data` with its column names `columns` (a cell array or a char
  matrix) estimates the same response as the CSV log it was made from (1e-12).
- the .m and .py exports define std_* and covariance equal to model.json's.
Exit 77 (skipped) without octave, numpy or h5py.
"""
import csv, json, os, shutil, subprocess, sys, tempfile
try:
    import numpy as np
    import h5py
except ImportError as e:
    print(f"skipped: {e}"); sys.exit(77)
if not shutil.which("octave"):
    print("skipped: no octave"); sys.exit(77)

zw, src = sys.argv[1], sys.argv[2]
tmp = tempfile.mkdtemp()
log = os.path.join(src, "datasets/phantom/phantom_30s.csv")
failed = 0


def report(name, ok, detail=""):
    global failed
    print(("ok   " if ok else "FAIL ") + name + (": " + detail if detail else ""))
    failed += not ok


def zwidth(*args):
    p = subprocess.run([zw, *args], capture_output=True, text=True)
    if p.returncode != 0:
        print(p.stdout, p.stderr)
        raise SystemExit(f"FAIL zwidth {' '.join(args)} exited {p.returncode}")
    return p


def octave(script):
    path = os.path.join(tmp, "check.m")
    with open(path, "w") as f:
        f.write("1;\n" + script)
    p = subprocess.run(["octave", "--no-gui", "--no-window-system", "-q", path], capture_output=True, text=True, cwd=tmp)
    if p.returncode != 0:
        print(p.stdout, p.stderr)
        raise SystemExit("FAIL octave exited %d" % p.returncode)
    return p.stdout


def rel(a, b):
    a, b = np.asarray(a, float).ravel(), np.asarray(b, float).ravel()
    if a.shape != b.shape:
        return np.inf
    scale = np.maximum(np.abs(b), 1e-300)
    return float(np.max(np.abs(a - b) / scale)) if a.size else 0.0


def flat(mj, key):  # m, b, omega, c, v, d of a model.json (or its std)
    p = mj if key is None else mj[key]
    return {"m": [p["m"]], "b": [p["b"]], **{k: [md[k] for md in p["modes"]] for k in ("omega", "c", "v", "d")}}


model = os.path.join(tmp, "model.json")
frf = os.path.join(tmp, "frf.csv")
zwidth("fit", log, "-o", model)
zwidth("estimate", log, "-o", frf)
mj = json.load(open(model))
rows = list(csv.DictReader(open(frf)))
col = lambda name: np.array([float(r[name]) for r in rows])
H = col("H_re") + 1j * col("H_im")
cov = np.array(mj["covariance"]["matrix"])

# --- v5 in Octave -----------------------------------------------------------
mat5 = os.path.join(tmp, "m5.mat")
zwidth("export", model, "--format", "mat", "--response", frf, "--period", "0.001", "-o", mat5)
out = octave("""
load('m5.mat');
function put(name, x)
  fprintf('%s', name); fprintf(' %.17g', double(x(:))); fprintf('\\n');
end
names = {'m','b','omega','c','v','d','std_m','std_b','std_omega','std_c','std_v','std_d', ...
         'delay_samples','period_s','covariance','f','H_std','coherence','num_averages','effective_averages'};
for i = 1:numel(names)
  put(names{i}, eval(names{i}));
end
put('H_re', real(H)); put('H_im', imag(H));
p = cellstr(covariance_parameters);
fprintf('params %s\\n', strjoin(p', ','));
""")
got = {}
for line in out.splitlines():
    k, _, v = line.partition(" ")
    got[k] = v.split(" ") if k == "params" else np.array([float(x) for x in v.split()])
for k, v in flat(mj, None).items():
    report(f"v5 {k}", rel(got[k], v) <= 1e-12, f"rel {rel(got[k], v):.1e}")
for k, v in flat(mj, "std").items():
    report(f"v5 std_{k}", rel(got["std_" + k], v) <= 1e-12, f"rel {rel(got['std_' + k], v):.1e}")
report("v5 covariance", rel(got["covariance"].reshape(cov.shape).T, cov) <= 1e-12, f"rel {rel(got['covariance'].reshape(cov.shape).T, cov):.1e}")
report("v5 covariance_parameters", got["params"][0].split(",") == mj["covariance"]["parameters"], got["params"][0][:60])
report("v5 delay and period", got["delay_samples"][0] == mj["delay_samples"] and got["period_s"][0] == 0.001)
for k, v in [("f", col("f_hz")), ("H_re", H.real), ("H_im", H.imag), ("H_std", col("H_std")),
             ("coherence", col("coherence")), ("num_averages", col("num_averages")[:1]),
             ("effective_averages", col("effective_averages")[:1])]:
    report(f"v5 response {k}", rel(got[k], v) <= 1e-12, f"rel {rel(got[k], v):.1e} over {len(v)} bins")

# --- v7.3 with h5py ---------------------------------------------------------
mat73 = os.path.join(tmp, "m73.mat")
zwidth("export", model, "--format", "mat73", "--response", frf, "-o", mat73)
with h5py.File(mat73, "r") as h:
    for k, v in flat(mj, None).items():
        report(f"v7.3 {k}", rel(np.array(h[k]).ravel(), v) <= 1e-12)
    c73 = np.array(h["covariance"]).T  # h5py gives MATLAB's column-major matrices transposed
    report("v7.3 covariance", rel(c73, cov) <= 1e-12, f"rel {rel(c73, cov):.1e}")
    z = np.array(h["H"]).ravel()
    report("v7.3 H", rel(z["real"], H.real) <= 1e-12 and rel(z["imag"], H.imag) <= 1e-12)
    report("v7.3 f", rel(np.array(h["f"]).ravel(), col("f_hz")) <= 1e-12)

# --- a response from Octave fits to the log's model ----------------------------
octave("load('m5.mat'); save('-v7', 'resp.mat', 'f', 'H', 'coherence', 'num_averages', 'effective_averages', 'sample_rate_hz');")
from_oct = os.path.join(tmp, "from_octave.json")
p = zwidth("fit", os.path.join(tmp, "resp.mat"), "-o", from_oct)
report("fit of the Octave response says the std is derived", "H_std derived from the coherence" in p.stderr, p.stderr.strip()[:160])


def same_model(name, path):
    fj = json.load(open(path))
    if len(fj["modes"]) != len(mj["modes"]):
        report(name, False, f"{len(fj['modes'])} sections, the log's model has {len(mj['modes'])}")
        return
    worst = 0.0
    for k, v in flat(fj, None).items():
        s = np.array(flat(mj, "std")[k])
        worst = max(worst, float(np.max(np.abs(np.array(v) - flat(mj, None)[k]) / s)))
    report(name, worst <= 1.0, f"largest |difference| {worst:.2e} std")


same_model("Octave response fits to the log's model (within 1 std)", from_oct)

# The derived std, exported again: Bendat and Piersol's formula computed here.
resp_csv = os.path.join(tmp, "resp.csv")
with open(resp_csv, "w") as f:
    f.write("f,H_re,H_im,coherence,num_averages,fs\n")
    for k in range(len(rows)):
        f.write(f"{rows[k]['f_hz']},{rows[k]['H_re']},{rows[k]['H_im']},{rows[k]['coherence']},{rows[k]['num_averages']},{rows[k]['sample_rate_hz']}\n")
from_csv = os.path.join(tmp, "from_csv.json")
p = zwidth("fit", resp_csv, "-o", from_csv)
report("fit of a CSV with coherence says the std is derived", "H_std derived from the coherence" in p.stderr, p.stderr.strip()[:160])
same_model("CSV response with coherence fits to the log's model (within 1 std)", from_csv)
mat_d = os.path.join(tmp, "derived.mat")
zwidth("export", model, "--format", "mat73", "--response", resp_csv, "-o", mat_d)
coh, n = col("coherence"), col("num_averages")[0]
expected = np.abs(H) * np.sqrt((1 - coh) / (2 * n * coh))
with h5py.File(mat_d, "r") as h:
    d = np.array(h["H_std"]).ravel()
report("derived H_std = |H| sqrt((1 - coh) / (2 n coh))", rel(d, expected) <= 1e-12, f"rel {rel(d, expected):.1e}")

# A response with coherence but no averages is refused, naming what to add.
bad = os.path.join(tmp, "bad.csv")
with open(bad, "w") as f:
    f.write("f,H_re,H_im,coherence\n1,1,0,0.9\n2,1,0,0.9\n")
q = subprocess.run([zw, "fit", bad, "--rate", "1000", "-o", os.path.join(tmp, "bad.json")], capture_output=True, text=True)
report("coherence without averages is refused", q.returncode == 2 and "num_averages" in q.stderr and
       not os.path.exists(os.path.join(tmp, "bad.json")), q.stderr.strip()[:160])

# --- a .mat log as one matrix with named columns --------------------------------
shutil.copy(log, os.path.join(tmp, "log.csv"))
octave("""d = dlmread('log.csv', ',', 1, 0);
data = d; columns = {'t', 'torque', 'position'}; save('-v7', 'cell.mat', 'data', 'columns');
data = d(:, [2 3 1]); columns = char('torque', 'position', 't'); save('-v7', 'char.mat', 'data', 'columns');
data = d(:, [3 2]); columns = {'y', 'u'}; save('-v7', 'named.mat', 'data', 'columns');""")
frf_ref = [float(r["H_re"]) for r in rows] + [float(r["H_im"]) for r in rows]
for name, extra in [("cell.mat", []), ("char.mat", []),
                    ("named.mat", ["--input-column", "u", "--output-column", "y", "--time-column", "none", "--rate", "1000"])]:
    out_csv = os.path.join(tmp, name + ".frf.csv")
    zwidth("estimate", os.path.join(tmp, name), *extra, "-o", out_csv)
    got_rows = list(csv.DictReader(open(out_csv)))
    got_h = [float(r["H_re"]) for r in got_rows] + [float(r["H_im"]) for r in got_rows]
    report(f"a .mat log as one matrix ({name}) estimates as the CSV log", rel(got_h, frf_ref) <= 1e-12,
           f"rel {rel(got_h, frf_ref):.1e}")
q = subprocess.run([zw, "estimate", os.path.join(tmp, "named.mat"), "-o", os.path.join(tmp, "no.csv")], capture_output=True, text=True)
report("a matrix log without the named column says which columns it has", q.returncode == 2 and "columns: y, u" in q.stderr,
       q.stderr.strip()[:160])

# --- .m and .py carry std and covariance ----------------------------------------
mfile, pyfile = os.path.join(tmp, "g.m"), os.path.join(tmp, "g.py")
zwidth("export", model, "--format", "matlab", "-o", mfile)
zwidth("export", model, "--format", "python", "-o", pyfile)
out = octave("""pkg load control; run('g.m');
fprintf('%.17g ', std_m, std_b, std_w1, std_c1, std_v1, std_d1); fprintf('\\n');
fprintf('%.17g ', covariance(:)); fprintf('\\n'); fprintf('%s\\n', covariance_parameters{end});""")
lines = out.strip().splitlines()
s = mj["std"]
report(".m std", rel([float(x) for x in lines[-3].split()], [s["m"], s["b"], s["modes"][0]["omega"], s["modes"][0]["c"],
                                                              s["modes"][0]["v"], s["modes"][0]["d"]]) <= 1e-12)
report(".m covariance", rel(np.array([float(x) for x in lines[-2].split()]).reshape(cov.shape).T, cov) <= 1e-12)
report(".m covariance_parameters", lines[-1] == mj["covariance"]["parameters"][-1], lines[-1])
ns = {}
exec(open(pyfile).read(), ns)
report(".py std", rel([ns["std_m"], ns["std_b"]] + [x for md in ns["std_modes"] for x in md],
                      [s["m"], s["b"]] + [md[k] for md in s["modes"] for k in ("omega", "c", "v", "d")]) <= 1e-12)
report(".py covariance", rel(ns["covariance"], cov) <= 1e-12 and ns["covariance_parameters"] == mj["covariance"]["parameters"])

shutil.rmtree(tmp)
print("FAILED" if failed else "all passed")
sys.exit(1 if failed else 0)
