#!/usr/bin/env bash
# run --friction (issue 32): `run` fits friction by the rule `fit` uses
# (analysis::FrictionInputFor, analysis::FitToModelFile). The logs are made
# here by `zwidth simulate` from Table I, seeded: one with Coulomb friction
# 0.004 N m (13 % of the torque's 0.03 N m rms), one without.
# - the friction log: run's model.json is fit's (--modes auto, run's default
#   order) byte for byte but the provenance; its summary.json holds the A* rows
#   and its boundary.csv the A_star columns that `boundary` computes from that
#   model (another front end over analysis::FrictionAmplitudes), both with the
#   encoder step model.json holds, read from the log (simulate's default);
# - the friction-free log: the default (auto) run folder equals --friction
#   none's byte for byte but the provenance (friction only detected, not
#   fitted), with no friction in model.json and none in summary.json;
# - run --table2: summary.json's "table2" is `compare --table2`'s on run's model;
# - refusals: a bad word, coulomb on two logs (exit 2, the flag named,
#   no folder left).
# Usage: run_friction_cli_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
. "$SRC/tests/cli_lib.sh"
"$ZW" simulate --model "$M" -o "$T/fr.csv" --seconds 20 --coulomb 0.004 --seed 7 >/dev/null 2>&1
"$ZW" simulate --model "$M" -o "$T/lin.csv" --seconds 12 --seed 3 >/dev/null 2>&1
"$ZW" fit "$T/fr.csv" --modes auto -o "$T/fit.json" > "$T/fit.out" 2>&1 || { bad "fit"; cat "$T/fit.out"; }
"$ZW" run "$T/fr.csv" -o "$T/runf" --no-figures --delays 2,4 --b-points 60 --table2 --coulomb-levels 0,0.004 \
  --seconds 2 > "$T/run.out" 2>&1 \
  && ok "run on the friction log" || { bad "run on the friction log"; cat "$T/run.out"; }
grep -q "^friction: Coulomb friction" "$T/run.out" && ok "run prints the friction line" || bad "run: no friction line"
"$ZW" boundary "$T/runf/model.json" --delays 2,4 --b-points 60 -o "$T/b.csv" --summary "$T/b.json" >/dev/null 2>&1 \
  || bad "boundary on run's model"
cmp -s "$T/b.csv" "$T/runf/boundary.csv" && ok "run's boundary.csv (A_star columns) is boundary's" \
  || bad "run's boundary.csv differs from boundary's"
$PY - "$T" <<'PY' && ok "run's model.json is fit's; summary.json holds boundary's A* rows" || bad "run vs fit / boundary"
import json, os, sys
t = sys.argv[1]
def load(p): return json.load(open(os.path.join(t, p)))
fit, run = load("fit.json"), load("runf/model.json")
assert run["friction"]["coulomb_pos"] > 0.001, run["friction"]  # fitted (the truth is 0.004)
assert run["fit"]["friction"]["status"] == "fitted", run["fit"]["friction"]
# simulate's default encoder (2 pi / 40960 rad per count), read back from the log (ident::EncoderStep)
assert abs(run["encoder_step"] / (2 * 3.141592653589793 / 40960) - 1) < 1e-9, run.get("encoder_step")
for j in (fit, run): j.pop("provenance")
assert fit == run, [k for k in fit if fit[k] != run.get(k)]
s, b = load("runf/summary.json"), load("b.json")
assert len(s["boundary"]) == 2
for mine, theirs in zip(s["boundary"], b["delays"]):
    f = mine["friction"]
    assert f == theirs["friction"], (f, theirs["friction"])
    assert f["at_zero_B"]["B"] == 0 and f["at_zero_B"]["amplitude"] > 0, f
    assert abs(f["coulomb"] - run["friction"]["coulomb_pos"]) < 1e-15
PY
# relay (as wall, boundary, check) takes the model's encoder step unless --encoder-step is given.
"$ZW" relay "$T/runf/model.json" --delay 2 --damping 0 --seconds 1 --json > "$T/relay.json" 2>/dev/null &&
  "$ZW" relay "$T/runf/model.json" --delay 2 --damping 0 --seconds 1 --json --encoder-step 0 > "$T/relay0.json" 2>/dev/null ||
  bad "relay on run's model"
$PY - "$T" <<'PY' && ok "relay uses model.json's encoder_step, --encoder-step 0 an exact one" || bad "relay's encoder step"
import json, os, sys
t = sys.argv[1]
m = json.load(open(os.path.join(t, "runf/model.json")))["encoder_step"]
def step(j):  # the options' encoder_step, wherever the record keeps it
    if isinstance(j, dict):
        if "encoder_step" in j: return j["encoder_step"]
        for v in j.values():
            s = step(v)
            if s is not None: return s
    return None
a, b = (step(json.load(open(os.path.join(t, f)))) for f in ("relay.json", "relay0.json"))
assert a == m and b == 0, (a, b, m)
PY
grep -q "A\* = " "$T/runf/report.html" && ok "report.html shows A*" || bad "report.html lacks A*"
# run --table2: summary.json's "table2" is compare --table2's on run's model (the same library call).
"$ZW" compare "$T/runf/model.json" --table2 --coulomb-levels 0,0.004 --seconds 2 --json > "$T/t2.json" 2>/dev/null \
  || bad "compare --table2 on run's model"
$PY - "$T/runf/summary.json" "$T/t2.json" <<'PY' && ok "run --table2: summary.json's table2 is compare's" || bad "run --table2 vs compare"
import json, sys
a, b = json.load(open(sys.argv[1]))["table2"], json.load(open(sys.argv[2]))["table2"]
assert a == b and len(a["points"]) >= 20
PY
grep -q "Table II: the paper's relay points" "$T/runf/report.html" && ok "report.html shows Table II" || bad "report.html lacks Table II"
# The friction-free log: the default is --friction none's folder (the friction only detected).
"$ZW" run "$T/lin.csv" -o "$T/auto" --reference table1 --delays 2,5 --b-points 100 >/dev/null 2>&1 || bad "run (auto)"
"$ZW" run "$T/lin.csv" -o "$T/none" --reference table1 --delays 2,5 --b-points 100 --friction none >/dev/null 2>&1 \
  || bad "run --friction none"
$PY - "$T/auto" "$T/none" <<'PY' && ok "friction-free log: auto's folder is none's but the provenance" || bad "auto vs none"
import json, os, re, sys
a, n = sys.argv[1], sys.argv[2]
def files(d):
    return sorted(os.path.relpath(os.path.join(r, f), d) for r, _, fs in os.walk(d) for f in fs)
def blank(name, text):
    text = re.sub(r'"command": "[^"\n]*"', '"command": ""', text)
    text = re.sub(r'"utc_date": "[^"\n]*"', '"utc_date": ""', text)
    return re.sub(r"report written [0-9T:Z-]+; command: <code>.*?</code>", "", text)
assert files(a) == files(n) and "summary.json" in files(a)
for f in files(a):
    x, y = open(os.path.join(a, f), "rb").read(), open(os.path.join(n, f), "rb").read()
    if f.endswith((".json", ".html")): x, y = blank(f, x.decode()), blank(f, y.decode())
    assert x == y, f
m = json.load(open(os.path.join(a, "model.json")))
assert "friction" not in m and m["fit"]["friction"]["status"] == "not detected", m["fit"].get("friction")
s = json.load(open(os.path.join(a, "summary.json")))
assert all("friction" not in e for e in s["boundary"]) and "table2" not in s
PY
expect "a bad --friction word" "--friction 'viscous': expected none, auto or coulomb" "$T/bad" -- \
  "$ZW" run "$T/lin.csv" -o "$T/bad" --friction viscous
expect "--friction coulomb on two logs" "--friction coulomb needs one time-domain log, not 2 logs" "$T/two" -- \
  "$ZW" run "$T/lin.csv" "$T/fr.csv" -o "$T/two" --friction coulomb --no-figures
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
