#!/usr/bin/env bash
# fit --friction on the command line: the default (auto) on a linear log (no
# friction detected, no 'friction' in model.json), coulomb (friction fitted,
# near 0, with its std; compare and the exports show it), and the refusals
# (a bad word, a saved response, exit 2, nothing written). The logs are
# simulated from Table I (linear, seeded): the friction logs themselves are
# tested in friction_fit_test (the library's simulator has no friction yet).
# Usage: friction_cli_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
. "$SRC/tests/cli_lib.sh"
"$ZW" simulate --model "$M" -o "$T/log.h5" --seed 5 >/dev/null
"$ZW" fit "$T/log.h5" -o "$T/auto.json" > "$T/auto.out" 2>&1 && ok "fit (auto) runs" || { bad "fit (auto)"; cat "$T/auto.out"; }
grep -q "friction: none detected" "$T/auto.out" && ok "auto: none detected on a linear log" || bad "auto: no 'none detected' line"
$PY - "$T/auto.json" <<'PY' && ok "auto: model.json without friction, fit.friction recorded" || bad "auto: model.json"
import json, sys
j = json.load(open(sys.argv[1]))
assert "friction" not in j, j.get("friction")
assert j["fit"]["friction"]["status"] == "not detected", j["fit"]["friction"]
PY
"$ZW" fit "$T/log.h5" --friction coulomb -o "$T/coulomb.json" > "$T/c.out" 2>&1 && ok "fit --friction coulomb runs" || { bad "fit --friction coulomb"; cat "$T/c.out"; }
$PY - "$T/coulomb.json" <<'PY' && ok "coulomb: F_c within 5 std of 0, with its std" || bad "coulomb: model.json friction"
import json, sys
j = json.load(open(sys.argv[1]))
f, s = j["friction"], j["std"]["friction"]
assert f["coulomb_pos"] == f["coulomb_neg"]
assert s["coulomb_pos"] > 0 and abs(f["coulomb_pos"]) < 5 * s["coulomb_pos"], (f, s)
assert s["breakaway_pos"] is None
PY
grep -q "^F_c " "$T/c.out" && ok "the parameter table shows F_c" || bad "parameter table lacks F_c"
"$ZW" compare "$T/coulomb.json" --reference table1 > "$T/cmp.out" 2>&1 && grep -q "^friction" "$T/cmp.out" && ok "compare shows the friction" || { bad "compare"; cat "$T/cmp.out"; }
"$ZW" export "$T/coulomb.json" --format matlab -o "$T/m.m" >/dev/null 2>&1 && grep -q "^friction_coulomb_pos = " "$T/m.m" && ok "MATLAB export carries the friction" || bad "MATLAB export"
expect "a bad --friction word" "--friction 'viscous': expected none, auto or coulomb" "$T/bad.json" -- \
  "$ZW" fit "$T/log.h5" --friction viscous -o "$T/bad.json"
"$ZW" estimate "$T/log.h5" -o "$T/frf.csv" >/dev/null 2>&1
expect "--friction coulomb on a saved response" "needs one time-domain log" "$T/frf.json" -- \
  "$ZW" fit "$T/frf.csv" --friction coulomb -o "$T/frf.json"
# compare --table2: Table II's points beside Table I's predictions (the library's numbers are
# checked in table2_test; here the wiring: JSON, the chosen level one of the grid, the refusals).
"$ZW" compare "$M" --table2 --coulomb-levels 0,0.01 --seconds 2 --json > "$T/t2.json" 2>"$T/t2.err" \
  && $PY - "$T/t2.json" <<'PY' && ok "compare --table2 --json: every point, a level of the grid" || { bad "compare --table2"; cat "$T/t2.err"; }
import json, sys
t = json.load(open(sys.argv[1]))["table2"]
assert len(t["points"]) >= 20 and t["coulomb_levels"] == [0, 0.01], t["coulomb_levels"]
assert t["best_coulomb"] in t["coulomb_levels"] and len(t["relay_error"]) == 2
assert all(len(p["relay"]) == 2 for p in t["points"])
PY
"$ZW" compare "$M" --table2 --coulomb-levels 0.01 --seconds 2 > "$T/t2.txt" 2>&1 && grep -q "^best Coulomb level of the grid: F_c = 0.01 N m" "$T/t2.txt" \
  && ok "compare --table2 prints the table and the best level" || { bad "compare --table2 text"; cat "$T/t2.txt"; }
expect "a negative --coulomb-levels" "--coulomb-levels: each level must be finite, >= 0" "" -- \
  "$ZW" compare "$M" --table2 --coulomb-levels 0,-0.01
expect "compare without a reference or --table2" "--table2" "" -- "$ZW" compare "$M"
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
