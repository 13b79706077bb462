#!/usr/bin/env python3
"""Every JSON file zwidth writes validates against its schema in docs/schema/ and carries the
provenance (issue 26, item 3): the zwidth version (= `zwidth --version`), a UTC date within the
test's run, the command line, and each input's SHA-256 equal to hashlib's.

Files: fit -o model.json, run's model.json and summary.json, export --format json and statespace,
validate -o, boundary --summary, check --json, compare --json, relay --json, wall --json. Also: a model file without format_version (an
older file) is still read, one with a newer format_version is refused naming the key.
Exit 77 (skipped) without python3-jsonschema.
"""
import datetime, glob, hashlib, json, os, shutil, subprocess, sys, tempfile

zw, src = sys.argv[1], sys.argv[2]
try:
    import jsonschema
except ImportError as e:
    print(f"skipped: {e} (Debian package python3-jsonschema)"); sys.exit(77)
tmp = tempfile.mkdtemp()
schema_dir = os.path.join(src, "docs/schema")
schemas = {os.path.basename(p): json.load(open(p)) for p in glob.glob(os.path.join(schema_dir, "*.schema.json"))}
# Each schema's relative $ref ("provenance.schema.json") resolves to the file beside it.
store = {}
for name, s in schemas.items():
    store[s["$id"]] = s
    store["file://" + os.path.join(schema_dir, name)] = s
log = os.path.join(src, "datasets/phantom/phantom_30s.csv")
table1 = os.path.join(src, "datasets/phantom/table1.json")
failed = 0
start = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
version = subprocess.run([zw, "--version"], capture_output=True, text=True).stdout


def report(name, ok, detail=""):
    global failed
    print(("ok   " if ok else "FAIL ") + name + (": " + detail if detail else ""))
    failed += not ok


def zwidth(*args, stdout=None):
    p = subprocess.run([zw, *args], capture_output=True, text=True)
    if p.returncode not in (0, 3, 4):  # check: 3/4 = an unstable/marginal object
        print(p.stdout, p.stderr)
        raise SystemExit(f"FAIL zwidth {' '.join(args)} exited {p.returncode}")
    if stdout:
        open(stdout, "w").write(p.stdout)
    return p


def sha(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def check(label, path, schema, inputs):
    doc = json.load(open(path))
    s = schemas[schema]
    resolver = jsonschema.RefResolver(s["$id"], s, store=store)
    errors = list(jsonschema.Draft202012Validator(s, resolver=resolver).iter_errors(doc))
    report(f"{label} validates against {schema}", not errors,
           "; ".join(f"{'/'.join(map(str, e.path))}: {e.message[:120]}" for e in errors[:3]))
    p = doc.get("provenance", {})
    report(f"{label} provenance version", bool(p.get("zwidth_version")) and p["zwidth_version"] in version,
           p.get("zwidth_version", "none"))
    try:
        when = datetime.datetime.strptime(p.get("utc_date", ""), "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=datetime.timezone.utc)
        now = datetime.datetime.now(datetime.timezone.utc)
        report(f"{label} provenance date is now (UTC)", start <= when <= now, p["utc_date"])
    except ValueError:
        report(f"{label} provenance date", False, repr(p.get("utc_date")))
    report(f"{label} provenance command", p.get("command", "").startswith("zwidth ") and label.split()[0] in p["command"],
           p.get("command", "")[:100])
    got = {os.path.realpath(i["path"]): i["sha256"] for i in p.get("inputs", [])}
    for path_in in inputs:
        real = os.path.realpath(path_in)
        report(f"{label} provenance sha256 of {os.path.basename(path_in)}", got.get(real) == sha(path_in),
               f"{got.get(real, 'missing')[:16]}... vs hashlib {sha(path_in)[:16]}...")


model = os.path.join(tmp, "model.json")
zwidth("fit", log, "-o", model)
check("fit -o", model, "model.schema.json", [log])

out = os.path.join(tmp, "run")
zwidth("run", log, "-o", out, "--no-figures")
check("run model.json", os.path.join(out, "model.json"), "model.schema.json", [log])
check("run summary.json", os.path.join(out, "summary.json"), "summary.schema.json", [log])

for fmt, schema in [("json", "model.schema.json"), ("statespace", "statespace.schema.json")]:
    path = os.path.join(tmp, f"export.{fmt}.json")
    zwidth("export", model, "--format", fmt, "--period", "0.001", "-o", path)
    check(f"export --format {fmt}", path, schema, [model])

val = os.path.join(tmp, "validation.json")
zwidth("validate", model, log, "-o", val)
check("validate -o", val, "validation.schema.json", [model, log])

summ = os.path.join(tmp, "boundary_summary.json")
zwidth("boundary", model, "--period", "0.001", "-o", os.path.join(tmp, "b.csv"), "--summary", summ)
check("boundary --summary", summ, "boundary-summary.schema.json", [model])
# With friction (the model's, here given by flag): each delay's "friction" entry and the CSV's A* columns.
summ_f = os.path.join(tmp, "boundary_summary_friction.json")
zwidth("boundary", model, "--period", "0.001", "--delays", "2", "--b-points", "20", "--coulomb", "0.005",
       "--encoder-step", "0.000153398", "-o", os.path.join(tmp, "bf.csv"), "--summary", summ_f)
check("boundary --summary with friction", summ_f, "boundary-summary.schema.json", [model])
report("boundary --summary with friction has a friction entry",
       all("friction" in d for d in json.load(open(summ_f))["delays"]))

scene = os.path.join(tmp, "scene.json")
json.dump({"objects": [{"name": "wall", "K": 100, "B": 0.01}]}, open(scene, "w"))
chk = os.path.join(tmp, "check.json")
zwidth("check", scene, "--model", model, "--delay", "2", "--json", stdout=chk)
check("check --json", chk, "check.schema.json", [model, scene])

cmp_json = os.path.join(tmp, "compare.json")
zwidth("compare", model, "--reference", table1, "--json", stdout=cmp_json)
check("compare --json", cmp_json, "compare.schema.json", [model, table1])
t2_json = os.path.join(tmp, "compare_table2.json")  # Table II alone: 1 level, 1 s relay runs
zwidth("compare", table1, "--table2", "--coulomb-levels", "0.01", "--seconds", "1", "--json", stdout=t2_json)
check("compare --table2 --json", t2_json, "compare.schema.json", [table1])

relay_json = os.path.join(tmp, "relay.json")
zwidth("relay", model, "--delay", "2", "--damping", "0", "--seconds", "2", "--json", stdout=relay_json)
check("relay --json", relay_json, "relay.schema.json", [model])

wall_json = os.path.join(tmp, "wall.json")
zwidth("wall", model, "--stiffness", "1", "--damping", "0.01", "--delay", "2", "--coulomb", "0.008", "--seconds", "1",
       "--json", stdout=wall_json)
check("wall --json", wall_json, "wall.schema.json", [model])

# The schema is not vacuous: a model file with a misspelt key or a string m is refused by it.
bad = dict(json.load(open(model)), mm=1)
s = schemas["model.schema.json"]
v = jsonschema.Draft202012Validator(s, resolver=jsonschema.RefResolver(s["$id"], s, store=store))
report("model schema refuses an unknown key", not v.is_valid(bad))
report("model schema refuses a string m", not v.is_valid(dict(json.load(open(model)), m="1")))

# Older model files (no format_version) are read; a newer version is refused naming the key.
old = json.load(open(table1))
report("table1.json has no format_version (an older file)", "format_version" not in old)
p = subprocess.run([zw, "export", table1, "--format", "json", "-o", os.path.join(tmp, "t1.json")], capture_output=True, text=True)
report("an older model file is read", p.returncode == 0 and json.load(open(os.path.join(tmp, "t1.json")))["format_version"] == 1,
       p.stderr.strip()[:120])
newer = os.path.join(tmp, "newer.json")
json.dump(dict(old, format_version=2), open(newer, "w"))
p = subprocess.run([zw, "export", newer, "--format", "json", "-o", os.path.join(tmp, "n.json")], capture_output=True, text=True)
report("a newer format_version is refused", p.returncode == 2 and "format_version" in p.stderr and
       not os.path.exists(os.path.join(tmp, "n.json")), p.stderr.strip()[:160])

# The design file (an input of batch --reference): the schema and zwidth agree. A valid design validates
# and a batch of one unit reads it (a verdict per spec); each broken one is refused by both, zwidth with
# exit 2 naming the line and the key.
design = {"format": "zwidth-design", "format_version": 1, "name": "PHANToM", "model": "table1",
          "tolerances": [{"parameter": "m", "relative": 0.15}, {"parameter": "b", "min": 1e-3, "max": 0.02},
                         {"figure": "K_cr_max", "delay": 2, "absolute": 8}]}
s = schemas["design.schema.json"]
v = jsonschema.Draft202012Validator(s)
report("design schema takes the example design", v.is_valid(design))
dpath = os.path.join(tmp, "design.json")
json.dump(design, open(dpath, "w"), indent=1)
unit = os.path.join(tmp, "unit.csv")
zwidth("simulate", "--model", table1, "-o", unit, "--seconds", "4", "--seed", "3")
table = os.path.join(tmp, "fleet.csv")
p = subprocess.run([zw, "batch", unit, "-o", table, "--delays", "2", "--window-length", "1024", "--reference", dpath],
                   capture_output=True, text=True)
import csv
rows = list(csv.DictReader(open(table))) if os.path.exists(table) else []
report("batch reads the example design", p.returncode == 0 and len(rows) == 1 and rows[0]["verdict"] in
       ("pass", "marginal", "fail") and "p_d2_K_cr_max_min" in rows[0], p.stderr.strip()[-160:])
broken = [("a misspelt key", dict(design, tolerances=[{"parameter": "m", "relatve": 0.1}]), "relatve"),
          ("no bound", dict(design, tolerances=[{"parameter": "m"}]), "tolerances[0]"),
          ("two kinds of bound", dict(design, tolerances=[{"parameter": "m", "min": 0, "relative": 0.1}]), "tolerances[0]"),
          ("a figure without delay", dict(design, tolerances=[{"figure": "K_cr_max", "min": 1}]), "delay"),
          ("no such parameter", dict(design, tolerances=[{"parameter": "mass", "min": 1}]), "parameter"),
          ("a negative relative", dict(design, tolerances=[{"parameter": "m", "relative": -0.1}]), "relative"),
          ("no model", {k: x for k, x in design.items() if k != "model"}, "model")]
for label, d, key in broken:
    path = os.path.join(tmp, "broken.json")
    json.dump(d, open(path, "w"), indent=1)
    p = subprocess.run([zw, "batch", unit, "-o", os.path.join(tmp, "broken.csv"), "--delays", "2", "--reference", path],
                       capture_output=True, text=True)
    report("design with " + label + ": refused by the schema and by zwidth naming " + key,
           not v.is_valid(d) and p.returncode == 2 and key in p.stderr and ("line" in p.stderr or key == "model") and
           not os.path.exists(os.path.join(tmp, "broken.csv")), p.stderr.strip()[:200])

shutil.rmtree(tmp)
print("FAILED" if failed else "all passed")
sys.exit(1 if failed else 0)
