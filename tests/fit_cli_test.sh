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
"$ZW" fit "$T/short.h5" -o "$T/s.json" > "$T/out" 2> "$T/err"; rc=$?
check "one-segment log refused" '[ $rc = 2 ] && [ ! -e "$T/s.json" ] && grep -q -- "--allow-short" "$T/err" && grep -q -- "--window-length" "$T/err"'
"$ZW" fit "$T/short.h5" -o "$T/s.json" --allow-short > "$T/out" 2>&1
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
echo "$pass passed, $fail failed"
[ $fail = 0 ]
