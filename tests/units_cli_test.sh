#!/usr/bin/env bash
# The axis's units of issue #24: a log whose header says force [N], position [m]
# fits a linear model without --units (fit and run); a header that contradicts
# --units or mixes rotary and linear is refused (exit 2, nothing written); and
# compare (and run --reference) refuse models of different units. A 2 kg linear
# axis simulated (seeded). Usage: units_cli_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
. "$SRC/tests/cli_lib.sh"
check() { if eval "$2"; then ok "$1"; else bad "$1"; fi; }
printf '{"name": "2 kg linear axis", "m": 2.0, "b": 10.0, "modes": [{"omega": 251.3, "c": 10, "v": 226.2, "d": 9}], "delay_samples": 0}' > "$T/axis.json"
"$ZW" simulate --model "$T/axis.json" --torque-rms 20 --bandwidth-hz 200 --encoder-step 1e-6 --seed 8 -o "$T/axis.csv" >/dev/null 2>&1
# The same samples under three headers.
{ echo "t,force [N],position [m]"; tail -n +2 "$T/axis.csv"; } > "$T/lin.csv"
{ echo "t,force [N],position [rad]"; tail -n +2 "$T/axis.csv"; } > "$T/mixed.csv"
{ echo "t,force,position"; tail -n +2 "$T/axis.csv"; } > "$T/plain.csv"
SEL="--input-column force --modes 1"
"$ZW" fit "$T/lin.csv" $SEL -o "$T/lin.json" > "$T/out" 2>&1
check "fit of a force [N], position [m] log: linear without --units" 'grep -q "\"units\": \"linear\"" "$T/lin.json" && grep -qE "^m .* kg$" "$T/out" && grep -qE "^b .* N s/m$" "$T/out"'
"$ZW" fit "$T/lin.csv" $SEL --units linear -o "$T/lin_given.json" > /dev/null 2>&1
check "fit --units linear agrees with the header: the same model" 'cmp -s <(grep -v "\"utc_date\"\|\"command\"" "$T/lin.json") <(grep -v "\"utc_date\"\|\"command\"" "$T/lin_given.json")'
"$ZW" fit "$T/plain.csv" $SEL -o "$T/plain.json" > /dev/null 2>&1
check "fit of a header without units: rotary (no units key)" '[ -f "$T/plain.json" ] && ! grep -q "\"units\"" "$T/plain.json"'
expect "fit --units rotary on a linear header" "header says linear units.*--units rotary was given" "$T/bad.json" -- \
  "$ZW" fit "$T/lin.csv" $SEL --units rotary -o "$T/bad.json"
expect "fit of a header that mixes rotary and linear" "mixes rotary and linear" "$T/bad.json" -- \
  "$ZW" fit "$T/mixed.csv" $SEL -o "$T/bad.json"
expect "run of a header that mixes rotary and linear" "mixes rotary and linear" "$T/bad_run" -- \
  "$ZW" run "$T/mixed.csv" $SEL --no-figures -o "$T/bad_run"
"$ZW" run "$T/lin.csv" $SEL --no-figures -o "$T/run" > "$T/out" 2>&1
check "run of the linear header: model.json linear, the table in kg" 'grep -q "\"units\": \"linear\"" "$T/run/model.json" && grep -qE "^m .* kg$" "$T/out"'
expect "compare a linear model with Table I" "is linear \(kg, N s/m\).*Table I.*is rotary \(kg m\^2, N m s/rad\).*compare models of one kind" "" -- \
  "$ZW" compare "$T/lin.json" --reference table1
check "compare refused: nothing on stdout" '[ ! -s "$T/stdout" ]'
expect "compare a rotary model with a linear reference" "is rotary.*is linear" "" -- \
  "$ZW" compare "$T/plain.json" --reference "$T/lin.json"
"$ZW" compare "$T/lin.json" --reference "$T/lin.json" > "$T/out" 2>&1
check "compare of two linear models: compared" 'grep -q "N s/m" "$T/out"'
expect "run --reference table1 on a linear axis" "the fitted model is linear.*table1 is rotary" "$T/ref_run" -- \
  "$ZW" run "$T/lin.csv" $SEL --reference table1 --no-figures -o "$T/ref_run"
# A linear model's own simulated log ("t,force [N],position [m]") fits without a flag: linear.
sed 's/"delay_samples": 0}/"delay_samples": 0, "units": "linear"}/' "$T/axis.json" > "$T/axis_lin.json"
"$ZW" simulate --model "$T/axis_lin.json" --torque-rms 20 --bandwidth-hz 200 --encoder-step 1e-6 --seed 8 -o "$T/sim_lin.csv" >/dev/null 2>&1
"$ZW" fit "$T/sim_lin.csv" --modes 1 -o "$T/sim_lin_fit.json" > "$T/out" 2>&1
check "fit of simulate's linear log, no flags: read, linear" 'grep -q "\"units\": \"linear\"" "$T/sim_lin_fit.json" && grep -qE "^b .* N s/m$" "$T/out"'
echo "$pass passed, $fail failed"
[ $fail = 0 ]
