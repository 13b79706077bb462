#!/usr/bin/env bash
# The fit's command-line behaviour of issue 14: a one-segment log refused
# (exit 2, nothing written), --fmin/--fmax on a saved response, no raw
# Ceres/glog lines, the verdict first in run's summary.json, the used_by_fit
# column. Logs simulated from Table I (seeded). Usage: fit_cli_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2; T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
pass=0; fail=0
check() { if eval "$2"; then pass=$((pass + 1)); echo "ok   $1"; else fail=$((fail + 1)); echo "FAIL $1"; fi; }
M=$SRC/datasets/phantom/table1.json
"$ZW" simulate --model "$M" -o "$T/short.h5" --seconds 5 --seed 3 >/dev/null
# The default window fits 3 segments into a 5 s log (2048 samples at 1 kHz,
# ident::DefaultWindowLength); a 4096 window given leaves one, refused.
"$ZW" fit "$T/short.h5" -o "$T/d.json" > "$T/out" 2> "$T/err"; rc=$?
check "5 s log: the default window is 2048 samples, 3 segments" '[ $rc = 0 ] && grep -q "3 segments" "$T/err" && grep -q "2048-sample segment" "$T/err"'
"$ZW" fit "$T/short.h5" --window-length 4096 -o "$T/s.json" > "$T/out" 2> "$T/err"; rc=$?
check "one-segment log refused" '[ $rc = 2 ] && [ ! -e "$T/s.json" ] && grep -q -- "--allow-short" "$T/err" && grep -q -- "--window-length" "$T/err"'
"$ZW" fit "$T/short.h5" --window-length 4096 -o "$T/s.json" --allow-short > "$T/out" 2>&1
check "--allow-short fits and says poor" 'grep -q "\"quality\": \"poor\"" "$T/s.json"'
"$ZW" simulate --model "$M" -o "$T/log.h5" --seed 4 >/dev/null
"$ZW" estimate "$T/log.h5" -o "$T/frf.csv" >/dev/null
"$ZW" fit "$T/frf.csv" --fmin 2 --fmax 20 --modes 0 -o "$T/b.json" > /dev/null 2>&1
check "--fmin/--fmax limit a saved response" 'python3 -c "import json,sys; b=json.load(open(sys.argv[1]))[\"fit\"][\"band\"]; sys.exit(0 if b[\"f_min_used_hz\"] >= 2 and b[\"f_max_used_hz\"] <= 20 else 1)" "$T/b.json"'
"$ZW" fit "$T/log.h5" --modes 4 -o "$T/m4.json" > "$T/out" 2>&1
check "no raw glog/Ceres lines" '! grep -qE "InitGoogleLogging|^[WEF][0-9]{4} " "$T/out"'
check "one section too many named from 1" 'grep -qE "section [1-4]:" "$T/out" && ! grep -q "section 0" "$T/out"'
"$ZW" run "$T/log.h5" -o "$T/run" > "$T/out" 2>&1
check "run: verdict first in summary.json" '[ "$(sed -n 2p "$T/run/summary.json" | tr -d " ")" = "\"fit_quality\":\"good\"," ]'
check "run: frf.csv has used_by_fit" 'head -1 "$T/run/frf.csv" | grep -q ",used_by_fit$"'
"$ZW" run "$T/log.h5" -o "$T/run_nf" --no-figures > /dev/null 2>&1
check "run --no-figures: no figures/, same boundary.csv and summary" '[ ! -e "$T/run_nf/figures" ] && cmp -s "$T/run/boundary.csv" "$T/run_nf/boundary.csv" && grep -q "no-figures" "$T/run_nf/report.html"'
# --delay-samples auto is the default (issue 29): a log with a 3-sample input
# delay is fitted with it, and every delay shown is the loop's + the model's.
"$ZW" simulate --model "$M" -o "$T/late.h5" --delay-samples 3 --seed 6 >/dev/null 2>&1
"$ZW" fit "$T/late.h5" -o "$T/late.json" > "$T/out" 2>&1
check "fit: the input delay found by default (3 samples), verdict good" 'python3 -c "import json,sys; m=json.load(open(sys.argv[1])); sys.exit(0 if m[\"delay_samples\"] == 3 and m[\"fit\"][\"quality\"] == \"good\" else 1)" "$T/late.json"'
"$ZW" fit "$T/late.h5" --delay-samples 0 -o "$T/late0.json" > /dev/null 2>&1
check "fit --delay-samples 0 on it: poor" 'grep -q "\"quality\": \"poor\"" "$T/late0.json"'
"$ZW" run "$T/late.h5" --delays 2 --no-figures -o "$T/run_late" > "$T/out" 2>&1
check "run summary.json: loop 2, model 3, total 5" 'python3 -c "import json,sys; e=json.load(open(sys.argv[1]))[\"boundary\"][0]; sys.exit(0 if (e[\"delay_samples\"], e[\"model_delay_samples\"], e[\"total_delay_samples\"]) == (2, 3, 5) else 1)" "$T/run_late/summary.json"'
check "run report: loop 2 + model 3 = 5 samples" 'grep -q "loop 2 + model 3 = 5 samples" "$T/run_late/report.html"'
"$ZW" boundary "$T/late.json" --delays 2 --summary "$T/late_sum.json" -o "$T/late_b.csv" > "$T/out" 2>&1
check "boundary: loop 2 + model 3 = 5 samples (text and summary)" 'grep -q "loop 2 + model 3 = 5 samples" "$T/out" && python3 -c "import json,sys; e=json.load(open(sys.argv[1]))[\"delays\"][0]; sys.exit(0 if (e[\"delay_samples\"], e[\"model_delay_samples\"], e[\"total_delay_samples\"]) == (2, 3, 5) else 1)" "$T/late_sum.json"'
echo '{"objects": [{"name": "wall", "K": 0.5, "B": 0.01}]}' > "$T/scene.json"
"$ZW" check "$T/scene.json" --model "$T/late.json" --delay 2 > "$T/out" 2>&1
check "check: loop 2 + model 3 = 5 samples" 'grep -q "delay: loop 2 + model 3 = 5 samples" "$T/out"'
# --units linear is kept by the model file (issue 24 item 3): a 2 kg linear
# axis (one section at 40 Hz) fitted with --units linear; compare and the
# exports read the model's units without the flag.
printf '{"name": "2 kg linear axis", "m": 2.0, "b": 10.0, "modes": [{"omega": 251.3, "c": 10, "v": 226.2, "d": 9}], "delay_samples": 0}' > "$T/axis.json"
"$ZW" simulate --model "$T/axis.json" --torque-rms 20 --bandwidth-hz 200 --encoder-step 1e-6 --seed 8 -o "$T/axis.h5" >/dev/null 2>&1
"$ZW" fit "$T/axis.h5" --units linear --modes 1 -o "$T/axis_fit.json" > "$T/out" 2>&1
check "fit --units linear: model.json says linear, the table kg and N s/m" 'grep -q "\"units\": \"linear\"" "$T/axis_fit.json" && grep -qE "^m .* kg$" "$T/out" && grep -qE "^b .* N s/m$" "$T/out"'
"$ZW" compare "$T/axis_fit.json" --reference "$T/axis_fit.json" > "$T/out" 2>&1
check "compare: the linear model in kg and N s/m without --units" 'grep -q " kg" "$T/out" && grep -q "N s/m" "$T/out" && ! grep -q "kg m^2" "$T/out" && ! grep -q "N m s/rad" "$T/out"'
"$ZW" export "$T/axis_fit.json" --format matlab --period 0.001 -o "$T/axis.m" > /dev/null 2>&1
check "export .m: inertia [kg], damping [N s/m]" 'grep -q "inertia \[kg\]" "$T/axis.m" && grep -q "damping \[N s/m\]" "$T/axis.m" && ! grep -q "kg m^2" "$T/axis.m"'
"$ZW" relay "$T/axis_fit.json" --damping 1 --delay 2 > "$T/out" 2>&1
check "relay: the linear model's K_cr in N/m" 'grep -q "K_cr = .* N/m at" "$T/out" && ! grep -q "N m/rad" "$T/out"'
"$ZW" run "$T/axis.h5" --units linear --modes 1 --no-figures -o "$T/axis_run" > /dev/null 2>&1
check "run --units linear: model.json says linear" 'grep -q "\"units\": \"linear\"" "$T/axis_run/model.json"'
"$ZW" run "$T/axis.h5" --units linear --modes 1 -o "$T/axis_run_fig" > /dev/null 2>&1
check "run --units linear: every figure's axes in N/m and N s/m (the region and loop figures too)" 'grep -q "K \[N/m\]" "$T/axis_run_fig/figures/figures.gp" && grep -q "B \[N s/m\]" "$T/axis_run_fig/figures/figures.gp" && ! grep -qE "N m/rad|N m s/rad" "$T/axis_run_fig/figures/figures.gp"'
"$ZW" run "$T/log.h5" --no-figures -o "$T/rot_run" > /dev/null 2>&1
check "a rotary run's model.json has no units key" '[ -f "$T/rot_run/model.json" ] && ! grep -q "\"units\"" "$T/rot_run/model.json"'
echo "$pass passed, $fail failed"
[ $fail = 0 ]
