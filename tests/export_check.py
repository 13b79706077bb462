#!/usr/bin/env python3
"""Executes exported models and compares them with independent references.

- python: runs the exported .py; its G must equal the factored formula of eq. (1)
  and its Gz SciPy's own ZOH (cont2discrete of the factored transfer function,
  times z^-delay), both to 1e-6 relative.
- matlab: runs the exported .m in GNU Octave with the control package and checks
  the same; reported as skipped (exit 77 when it is the only check left) if
  Octave is not installed.
- hdf5: reads back the parameters.
"""
import json, os, shutil, subprocess, sys, tempfile
try:
    import numpy as np
    import scipy.signal as ss
    import h5py
except ImportError as e:
    print(f"skipped: {e}"); sys.exit(77)
from reference_model import plant_tf

zw, src = sys.argv[1], sys.argv[2]
tmp = tempfile.mkdtemp()
model = os.path.join(tmp, "m.json")
with open(os.path.join(src, "datasets/phantom/table1.json")) as f:
    mj = json.load(f)
mj["delay_samples"] = 2
json.dump(mj, open(model, "w"))
T = 1e-3
w = 2 * np.pi * np.array([0.5, 5, 50, 66, 76, 87, 184, 300, 450])

def factored(s):
    g = 1 / (mj["m"] * s * s + mj["b"] * s)
    for md in mj["modes"]:
        g = g * md["omega"]**2 / md["v"]**2 * (s*s + md["d"]*s + md["v"]**2) / (s*s + md["c"]*s + md["omega"]**2)
    return g

A, B, C, D = ss.tf2ss(*plant_tf(mj))
Ad, Bd, Cd, Dd, _ = ss.cont2discrete((A, B, C, D), T, method="zoh")
z = np.exp(1j * w * T)
ref_d = np.array([(Cd @ np.linalg.solve(zz*np.eye(len(Ad)) - Ad, Bd))[0, 0] for zz in z]) * z**-2
ref_c = factored(1j * w)

def resp(sys_, zs):
    return np.array([(sys_.C @ np.linalg.solve(zz*np.eye(sys_.A.shape[0]) - sys_.A, sys_.B))[0, 0] + sys_.D[0, 0] for zz in zs])

passed = failed = skipped = 0
def report(name, ok, detail):
    global passed, failed
    print(("ok   " if ok else "FAIL ") + name + ": " + detail)
    passed += ok; failed += not ok

py = os.path.join(tmp, "g.py")
subprocess.run([zw, "export", model, "--format", "python", "--period", str(T), "-o", py], check=True)
ns = {}
exec(open(py).read(), ns)
ec = np.max(np.abs(resp(ns["G"], 1j*w) - ref_c) / np.abs(ref_c))
ed = np.max(np.abs(resp(ns["Gz"], z) - ref_d) / np.abs(ref_d))
report("python export", ec < 1e-6 and ed < 1e-6 and ns["Gz"].dt == T, f"G rel err {ec:.1e}, Gz rel err {ed:.1e}")

h5 = os.path.join(tmp, "g.h5")
subprocess.run([zw, "export", model, "--format", "hdf5", "--period", str(T), "-o", h5], check=True)
with h5py.File(h5) as f:
    ok = (f["/parameters/m"][0] == mj["m"] and f["/parameters/b"][0] == mj["b"]
          and np.allclose(f["/parameters/omega"][:], [md["omega"] for md in mj["modes"]], rtol=0, atol=0)
          and np.allclose(f["/parameters/d"][:], [md["d"] for md in mj["modes"]], rtol=0, atol=0)
          and f.attrs["delay_samples"] == 2 and f["/discrete/A"].shape == (8, 8))
report("hdf5 export reads back", bool(ok), "parameters, delay and matrix shapes")

octave = shutil.which("octave-cli") or shutil.which("octave")
if octave:
    mfile = os.path.join(tmp, "g.m")
    subprocess.run([zw, "export", model, "--format", "matlab", "--period", str(T), "-o", mfile], check=True)
    wlist = " ".join(repr(x) for x in w)
    script = (f"pkg load control; run('{mfile}'); w=[{wlist}]; "
              "hc=squeeze(freqresp(G, w)); hd=squeeze(freqresp(Gz, w)); "
              "printf('%.17g %.17g %.17g %.17g\\n', [real(hc) imag(hc) real(hd) imag(hd)]');")
    out = subprocess.run([octave, "--no-gui", "--quiet", "--eval", script], capture_output=True, text=True)
    if out.returncode != 0:
        report("matlab export in Octave", False, out.stderr.strip()[:300])
    else:
        v = np.array([[float(x) for x in l.split()] for l in out.stdout.strip().splitlines()])
        hc, hd = v[:, 0] + 1j*v[:, 1], v[:, 2] + 1j*v[:, 3]
        ec = np.max(np.abs(hc - ref_c) / np.abs(ref_c)); ed = np.max(np.abs(hd - ref_d) / np.abs(ref_d))
        report("matlab export in Octave", ec < 1e-6 and ed < 1e-6, f"G rel err {ec:.1e}, Gz rel err {ed:.1e}")
else:
    skipped += 1
    print("skip matlab export: GNU Octave is not installed (apt-get install octave octave-control)")
print(f"{passed} passed, {failed} failed, {skipped} skipped")
sys.exit(1 if failed else 0)
