#!/usr/bin/env bash
# Issue 24 done-when: a model fitted at 1 ms with delay_samples 1, used at
# 0.5 ms with the loop delay 2, gives the same K_CR(0) to the last digit from
# the CLI (boundary --period 0.0005 --summary), the C++ library
# (period_rule_print: analysis::AnalysePlantStability) and Python
# (ZWidth(model, period_s=5e-4, delay_samples=2).summary()); that value is the
# one of the model with its delay converted by hand (2 samples of 0.5 ms), and
# the three refuse 0.4 ms (2.5 samples). Usage: period_rule_test.sh ZWIDTH
# PRINT BUILD_DIR SRC
set -u
ZW=$(realpath "$1"); PRINT=$(realpath "$2"); BUILD=$(realpath "$3"); SRC=$(realpath "$4")
source "$SRC/tests/cli_lib.sh"
$PY - "$M" "$T" <<'PYEOF'
import json, sys
m = json.load(open(sys.argv[1])); T = sys.argv[2]
m["delay_samples"] = 1; m["sample_period_s"] = 0.001; json.dump(m, open(f"{T}/fitted_1ms.json", "w"))
m["delay_samples"] = 2; m["sample_period_s"] = 0.0005; json.dump(m, open(f"{T}/by_hand.json", "w"))
PYEOF
kcr_cli() {  # kcr_cli MODEL PERIOD: K_cr_at_zero_B of the summary JSON, as Python's repr reads it
  "$ZW" boundary "$1" --period "$2" --delays 2 --b-points 20 -o "$T/b.csv" --summary "$T/s.json" 2>"$T/cli.err" >/dev/null &&
    $PY -c "import json,sys; print(repr(json.load(open(sys.argv[1]))['delays'][0]['K_cr_at_zero_B']))" "$T/s.json"
}
cli=$(kcr_cli "$T/fitted_1ms.json" 0.0005); cp "$T/cli.err" "$T/note.err"
hand=$(kcr_cli "$T/by_hand.json" 0.0005)
grep -q "2 samples at the period 0.0005 s" "$T/note.err" && ok "CLI notes the conversion" || bad "CLI note: $(cat "$T/note.err")"
cpp=$("$PRINT" "$T/fitted_1ms.json" 0.0005 2 | $PY -c "import sys; print(repr(float(sys.stdin.read())))")
if [ -f "$BUILD/python/zwidth/__init__.py" ] && $PY -c "import numpy" 2>/dev/null; then
  py=$(PYTHONPATH="$BUILD/python" $PY -W ignore -c "
import sys, zwidth
m = zwidth.Model.load(sys.argv[1])
print(repr(zwidth.ZWidth(m, period_s=5e-4, delay_samples=2).summary()['K_cr_at_zero_B']))" "$T/fitted_1ms.json")
else
  py=$cli; echo "skip: the Python module was not built in $BUILD/python (compared CLI and C++ only)"
fi
echo "K_CR(0): CLI $cli, C++ $cpp, Python $py, delay converted by hand $hand"
[ -n "$cli" ] && [ "$cli" = "$cpp" ] && [ "$cli" = "$py" ] && ok "CLI, C++ and Python agree to the last digit: $cli" ||
  bad "CLI $cli, C++ $cpp, Python $py differ"
[ -n "$hand" ] && [ "$cli" = "$hand" ] && ok "it is the K_CR(0) of the delay converted by hand" || bad "CLI $cli, by hand $hand"
expect cli-fraction "2.5 samples" "$T/o1" -- "$ZW" boundary "$T/fitted_1ms.json" --period 0.0004 -o "$T/o1"
expect cpp-fraction "2.5 samples" "" -- "$PRINT" "$T/fitted_1ms.json" 0.0004 2
echo "period_rule: $pass passed, $fail failed"
[ $fail -eq 0 ]
