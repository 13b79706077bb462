#!/usr/bin/env python3
"""The library names option fields (Struct::field) in its messages; the CLI maps
them to flags and the Python module to keywords through one table, OptionNames()
in io/option_names.cc. This check keeps the table from going stale:

1. every Struct::field named in a string literal of the library (model/, ident/,
   fit/, stability/, io/, analysis/, report/), or by a validator's bad("field ...") that
   prepends "Struct::", has a row in the table, with a flag and a keyword column
   ("" where there is none; tests/python checks that each keyword is one the
   module accepts);
2. every row's field is still named by the library (no dead rows), and every
   row's flag is a flag the CLI registers (add_option / add_flag in apps/ or flags/);
3. no string literal of the library names a command-line flag ("--name");
4. end to end: the CLI prints the flag, not the field, for an option error
   (zwidth excite --rms -1) and for a log-selection error (zwidth estimate
   --time-unit min), and writes nothing; the fit's quality advice in the model
   JSON that `zwidth fit` writes names flags.

Usage: field_flags_check.py ZWIDTH_BINARY SOURCE_DIR
"""
import os
import re
import subprocess
import sys
import tempfile

zwidth, src = sys.argv[1], sys.argv[2]
LIBRARY = ["model", "ident", "fit", "stability", "io", "analysis", "report"]
STRING = re.compile(r'"(?:[^"\\\n]|\\.)*"')
FIELD = re.compile(r"\b[A-Z][A-Za-z0-9]*::[a-z_][A-Za-z_0-9]*")  # a field may hold capitals: area_B_max
failures = []


def code_lines(path):
    """Lines of a C++ file without // comments (a // inside a string is kept)."""
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            out, i, in_str = [], 0, False
            while i < len(line):
                c = line[i]
                if in_str:
                    out.append(c)
                    if c == "\\" and i + 1 < len(line):
                        out.append(line[i + 1])
                        i += 1
                    elif c == '"':
                        in_str = False
                elif c == '"':
                    in_str = True
                    out.append(c)
                elif line.startswith("//", i):
                    break
                else:
                    out.append(c)
                i += 1
            yield n, "".join(out)


# 1 and 3: the fields and flags the library's string literals name.
named = {}  # field -> first "file:line"
for d in LIBRARY:
    for root, _, files in os.walk(os.path.join(src, d)):
        for name in sorted(files):
            if not name.endswith((".cc", ".h")):
                continue
            path = os.path.join(root, name)
            rel = os.path.relpath(path, src)
            if rel == os.path.join("io", "option_names.cc"):
                continue  # the table itself
            prefix = None  # a validator whose bad() prepends "Struct::" to each message
            for n, line in code_lines(path):
                if line.startswith("}"):
                    prefix = None
                for lit in STRING.findall(line):
                    if re.fullmatch(r'"[A-Z][A-Za-z0-9]*::"', lit):
                        prefix = lit[1:-1]
                        continue
                    for field in FIELD.findall(lit):
                        named.setdefault(field, f"{rel}:{n}")
                    lead = re.match(r'"([a-z_][a-z_0-9]*)', lit)
                    if prefix and lead and "bad(" in line:
                        named.setdefault(prefix + lead.group(1), f"{rel}:{n}")
                    if re.search(r"(^|[\s(/'])--[a-z]", lit[1:-1]):
                        failures.append(f"{rel}:{n}: a library message names a command-line flag: {lit}")

# The table.
with open(os.path.join(src, "io", "option_names.cc"), encoding="utf-8") as f:
    common = f.read()
body = common[common.index("OptionNames() {"):]
body = body[: body.index("return table;")]
rows = re.findall(r'\{"([A-Za-z0-9_]+::[A-Za-z_0-9]+)",\s*"([^"]*)"(?:,\s*"([^"]*)")?\}', body)
table = {field: flag for field, flag, _ in rows}
for field, flag, keyword in rows:
    if not re.search(r'\{"' + re.escape(field) + r'",\s*"[^"]*",\s*"[^"]*"\}', body):
        failures.append(f"OptionNames() row {field}: no Python keyword column (write \"\" when there is none)")
if len(table) < 40:
    failures.append(f"the table in io/option_names.cc parsed to only {len(table)} rows")

# The flags the CLI registers.
registered = set()
for folder in ("apps", "flags"):  # the commands, and the option table they share with Python (flags/)
    for name in os.listdir(os.path.join(src, folder)):
        if name.endswith(".cc"):
            with open(os.path.join(src, folder, name), encoding="utf-8") as f:
                text = f.read()
            for m in re.finditer(r'add_(?:option|flag)\(\s*"([^"]+)"', text):
                registered.update(p for p in m.group(1).split(",") if p.startswith("--"))

for field, where in sorted(named.items()):
    if field not in table:
        failures.append(f"{where}: the library names {field}, which has no row in OptionNames() (io/option_names.cc)")
for field, flag in sorted(table.items()):
    if field not in named:
        failures.append(f"OptionNames() row {field}: no library message names it (stale row?)")
    if flag and flag.split()[0] not in registered:
        failures.append(f"OptionNames() row {field}: {flag.split()[0]} is not a flag of any command")
print(f"{len(named)} fields named by the library, {len(table)} table rows, "
      f"{sum(1 for v in table.values() if v)} with a flag, {len(registered)} CLI flags")

# 4: end to end.
with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "x.txt")
    r = subprocess.run([zwidth, "excite", "-o", out, "--rms", "-1"], capture_output=True, text=True)
    if r.returncode != 2 or "--rms must be finite and > 0" not in r.stderr or "::" in r.stderr:
        failures.append(f"excite --rms -1: exit {r.returncode}, stderr {r.stderr!r}")
    if os.path.exists(out):
        failures.append("excite --rms -1 wrote its output")
    log = os.path.join(tmp, "log.csv")
    with open(log, "w") as f:
        f.write("t,torque,position\n" + "".join(f"{i * 1e-3},{(i * 7919) % 13 - 6},{i % 5}\n" for i in range(64)))
    r = subprocess.run([zwidth, "estimate", log, "-o", os.path.join(tmp, "f.csv"), "--time-unit", "min"],
                       capture_output=True, text=True)
    if r.returncode != 2 or "--time-unit 'min'" not in r.stderr or "::" in r.stderr:
        failures.append(f"estimate --time-unit min: exit {r.returncode}, stderr {r.stderr!r}")
    if os.path.exists(os.path.join(tmp, "f.csv")):
        failures.append("estimate --time-unit min wrote its output")

    # The files the CLI writes give flags too: the fit's quality advice in the model JSON.
    table1 = os.path.join(src, "datasets", "phantom", "table1.json")
    sim, model = os.path.join(tmp, "s.csv"), os.path.join(tmp, "m.json")
    subprocess.run([zwidth, "simulate", "--model", table1, "-o", sim, "--seconds", "4", "--seed", "3"],
                   capture_output=True, check=True)
    subprocess.run([zwidth, "fit", sim, "-o", model, "--allow-short", "--window-length", "2048"],
                   capture_output=True, check=True)
    with open(model) as f:
        text = f.read()
    if "use a shorter --window-length" not in text or "Options::" in text:
        failures.append("fit's model JSON: the few_averages advice does not name --window-length")

    # And `run`: its terminal report, summary.json and report.html (the same poor fit).
    outdir = os.path.join(tmp, "run")
    r = subprocess.run([zwidth, "run", sim, "-o", outdir, "--no-figures", "--allow-short", "--window-length", "2048",
                        "--modes", "1", "--delays", "2"], capture_output=True, text=True)
    shown = {"run's terminal output": r.stdout + r.stderr}
    for name in ("summary.json", "report.html"):
        path = os.path.join(outdir, name)
        shown[name] = open(path).read() if os.path.exists(path) else ""
    for name, text in shown.items():
        if "--window-length" not in text or "Options::" in text:
            failures.append(f"{name}: the fit's advice does not name --window-length (or names a field)")

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
