#!/usr/bin/env bash
# Bad input across subcommands: exit code 2, a message on stderr that names
# what and where, and no output file left behind. Usage: cli_errors_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
pass=0; fail=0
M=$SRC/datasets/phantom/table1.json
"$ZW" simulate --model "$M" -o "$T/good.csv" --seconds 10 2>/dev/null
"$ZW" simulate --model "$M" -o "$T/good.h5" --seconds 10 2>/dev/null

# expect NAME PATTERN OUTPUT -- command...
expect() {
  local name=$1 pattern=$2 out=$3; shift 4
  "$@" >"$T/stdout" 2>"$T/stderr"; local rc=$?
  if [ $rc -ne 2 ]; then echo "FAIL $name: exit $rc, expected 2"; cat "$T/stderr"; fail=$((fail+1)); return; fi
  if ! grep -qiE -e "$pattern" "$T/stderr"; then echo "FAIL $name: stderr lacks /$pattern/:"; cat "$T/stderr"; fail=$((fail+1)); return; fi
  if [ -n "$out" ] && ls "$out"* >/dev/null 2>&1; then echo "FAIL $name: left $out"; fail=$((fail+1)); return; fi
  echo "ok   $name: $(head -c 150 "$T/stderr" | tr '\n' ' ')"; pass=$((pass+1))
}

{ head -1 "$T/good.csv"; sed -n '2,5000p' "$T/good.csv"; echo "5.0,nan,0.1"; sed -n '5002,8000p' "$T/good.csv"; } > "$T/nan.csv"
expect nan-row "non-finite.*line 5001" "$T/o1.csv" -- "$ZW" estimate "$T/nan.csv" -o "$T/o1.csv"
awk -F, 'NR==100{$1="0.05"}1' OFS=, "$T/good.csv" > "$T/back.csv"
expect time-backwards "not strictly increasing at line 100" "$T/o2.csv" -- "$ZW" estimate "$T/back.csv" -o "$T/o2.csv"
sed '1s/torque/current/' "$T/good.csv" > "$T/nocol.csv"
expect missing-column "no column 'torque'" "$T/o3.csv" -- "$ZW" estimate "$T/nocol.csv" -o "$T/o3.csv"
: > "$T/empty.csv"
expect empty-file "empty file" "$T/o4.csv" -- "$ZW" estimate "$T/empty.csv" -o "$T/o4.csv"
head -c 20000 "$T/good.h5" > "$T/trunc.h5"
expect truncated-hdf5 "trunc.h5.*(truncated|corrupt|cannot)" "$T/o5.csv" -- "$ZW" estimate "$T/trunc.h5" -o "$T/o5.csv"
awk -F, 'NR>1{$2="0.5"}1' OFS=, "$T/good.csv" > "$T/const.csv"
expect constant-input "constant" "$T/o6.csv" -- "$ZW" estimate "$T/const.csv" -o "$T/o6.csv"
sed 's/"m": 1.168e-3/"m": -1.168e-3/' "$M" > "$T/neg.json"
expect model-negative "'?m'? = -0.001168|m = -" "$T/o7.csv" -- "$ZW" boundary "$T/neg.json" -o "$T/o7.csv"
grep -v '"b"' "$M" > "$T/miss.json"
expect model-missing "missing key 'b'" "$T/o8.csv" -- "$ZW" boundary "$T/miss.json" -o "$T/o8.csv"
sed 's/"b": 0.00584/"b": NaN/' "$M" > "$T/nan.json"
expect model-nan "not valid JSON|not finite|number" "$T/o9.csv" -- "$ZW" boundary "$T/nan.json" -o "$T/o9.csv"
head -c 60 "$M" > "$T/trunc.json"
expect model-truncated "not valid JSON" "$T/o10.csv" -- "$ZW" boundary "$T/trunc.json" -o "$T/o10.csv"
sed 's/"modes"/"mdoes"/' "$M" > "$T/typo.json"
expect model-unknown-key "unknown key 'mdoes'" "$T/o11.csv" -- "$ZW" boundary "$T/typo.json" -o "$T/o11.csv"
expect negative-delay "--delays = -1: a loop delay must lie in \[0, 1000\]" "$T/o12.csv" -- "$ZW" boundary "$M" --delays 2,-1 -o "$T/o12.csv"
expect zero-period "period" "$T/o13.csv" -- "$ZW" boundary "$M" --period 0 -o "$T/o13.csv"
expect window-longer "10000 samples.*fewer than one window of 16384.*--window-length 8192" "$T/o14.csv" -- "$ZW" estimate "$T/good.h5" --window-length 16384 -o "$T/o14.csv"
expect overlap-one "overlap" "$T/o15.csv" -- "$ZW" estimate "$T/good.h5" --overlap 1 -o "$T/o15.csv"
expect no-output-folder "output folder .* does not exist" "" -- "$ZW" estimate "$T/good.h5" -o "$T/nope/frf.csv"
expect missing-file "cannot open|does it exist" "$T/o16.csv" -- "$ZW" estimate "$T/absent.csv" -o "$T/o16.csv"
expect bad-window-name "--window 'kaiser'" "$T/o17.csv" -- "$ZW" estimate "$T/good.h5" --window kaiser -o "$T/o17.csv"
expect relay-negative-delay "delay" "" -- "$ZW" relay "$M" --delay -2 --damping 0
echo '{"objects":[{"name":"w","K":-1,"B":0}]}' > "$T/negK.json"
expect check-negative-K "'K'" "" -- "$ZW" check "$T/negK.json" --model "$M" --delay 2
expect check-scene-pipe "scene file is a FIFO.*not a regular file" "" -- "$ZW" check <(echo '{"objects":[{"name":"w","K":1,"B":0}]}') --model "$M" --delay 2
sed 's/"modes"/"covariance": {"space": "log", "parameters": ["m", "b"], "matrix": [[1e-4, 0], [0, 1e-4]]}, "modes"/' "$M" > "$T/cov.json"
expect model-covariance-shape "covariance.parameters" "$T/o26.csv" -- "$ZW" boundary "$T/cov.json" -o "$T/o26.csv"
python3 -c "import json, sys; m = json.load(open(sys.argv[1])); n = 2 + 4 * len(m['modes']); \
names = ['m', 'b'] + ['modes[%d].%s' % (i, k) for i in range(len(m['modes'])) for k in ('omega', 'c', 'v', 'd')]; \
m['covariance'] = {'space': 'log', 'parameters': names, 'matrix': [[1e300 * (i == j) for j in range(n)] for i in range(n)]}; \
json.dump(m, open(sys.argv[2], 'w'))" "$M" "$T/cov300.json"
expect model-covariance-absolute "log\(m\).*variance of 1e\+300.*natural logs" "$T/o27.csv" -- "$ZW" boundary "$T/cov300.json" --monte-carlo 5 -o "$T/o27.csv"
expect b-grid-cap "over the cap.*--b-step" "$T/o24.csv" -- "$ZW" boundary "$M" --b-max 1e12 --b-step 1e-3 -o "$T/o24.csv"
expect b-grid-bad-max "--b-max.*not a finite number" "$T/o25.csv" -- "$ZW" boundary "$M" --b-max inf -o "$T/o25.csv"
# check: exit 3 (not 1 or 2) when an object is unstable, 0 when all are stable.
echo '{"objects":[{"name":"ok","K":1,"B":0.01},{"name":"wall","K":80,"B":0.01}]}' > "$T/scene2.json"
echo '{"objects":[{"name":"ok","K":1,"B":0.01}]}' > "$T/scene1.json"
"$ZW" check "$T/scene2.json" --model "$M" --delay 2 >"$T/stdout" 2>&1; rc=$?
"$ZW" check "$T/scene1.json" --model "$M" --delay 2 >/dev/null 2>&1; rc0=$?
if [ $rc -eq 3 ] && [ $rc0 -eq 0 ] && grep -q "UNSTABLE" "$T/stdout"; then echo "ok   check-exit-3"; pass=$((pass+1));
else echo "FAIL check-exit-3: exit $rc / $rc0"; cat "$T/stdout"; fail=$((fail+1)); fi
# check with a model covariance (1 % relative std on every parameter): an object 0.1 % past K_cr
# is within 2 std of the boundary, so 'marginal' and exit 4; --marginal-sigmas 0 gives the nominal 3.
python3 -c "import json, sys; m = json.load(open(sys.argv[1])); n = 2 + 4 * len(m['modes']); \
names = ['m', 'b'] + [f'modes[{i}].{k}' for i in range(len(m['modes'])) for k in ('omega', 'c', 'v', 'd')]; \
m['covariance'] = {'space': 'log', 'parameters': names, 'matrix': [[1e-4 * (i == j) for j in range(n)] for i in range(n)]}; \
json.dump(m, open(sys.argv[2], 'w'))" "$M" "$T/cov_full.json"
kcr=$("$ZW" check "$T/scene1.json" --model "$M" --delay 2 --json | python3 -c "import json, sys; print(json.load(sys.stdin)['objects'][0]['K_cr'])")
echo "{\"objects\":[{\"name\":\"edge\",\"K\":$(python3 -c "print($kcr * 1.001)"),\"B\":0.01}]}" > "$T/scene_edge.json"
"$ZW" check "$T/scene_edge.json" --model "$T/cov_full.json" --delay 2 >"$T/stdout" 2>&1; rc=$?
"$ZW" check "$T/scene_edge.json" --model "$T/cov_full.json" --delay 2 --marginal-sigmas 0 >/dev/null 2>&1; rc3=$?
"$ZW" check "$T/scene_edge.json" --model "$M" --delay 2 >/dev/null 2>&1; rc_nocov=$?
if [ $rc -eq 4 ] && [ $rc3 -eq 3 ] && [ $rc_nocov -eq 3 ] && grep -q "marginal .*std from the boundary" "$T/stdout"; then echo "ok   check-marginal-exit-4"; pass=$((pass+1));
else echo "FAIL check-marginal-exit-4: exit $rc / $rc3 / $rc_nocov"; cat "$T/stdout"; fail=$((fail+1)); fi
expect unknown-flag "unknown|extra|not expected" "" -- "$ZW" boundary "$M" --bogus 1 -o "$T/x.csv"
awk -F, 'NR!=200' OFS=, "$T/good.csv" > "$T/gap.csv"
expect not-uniform "not uniformly sampled" "$T/o18.csv" -- "$ZW" estimate "$T/gap.csv" -o "$T/o18.csv"
expect fit-bad-delay "delay-samples 'soon'" "$T/o19.json" -- "$ZW" fit "$T/good.h5" --delay-samples soon -o "$T/o19.json"
# A frequency response saved as HDF5 and read back by fit: damaged copies.
"$ZW" estimate "$T/good.h5" -o "$T/frf.h5" 2>/dev/null
head -c 3000 "$T/frf.h5" > "$T/frf_trunc.h5"
expect frf-h5-truncated "frf_trunc.h5.*(truncated|corrupt|cannot)" "$T/o20.json" -- "$ZW" fit "$T/frf_trunc.h5" -o "$T/o20.json"
expect frf-h5-wrong-rate "reach 499\.7[0-9]* Hz, above the Nyquist frequency of 50 Hz; wrong --rate" "$T/o21.json" -- "$ZW" fit "$T/frf.h5" --rate 100 -o "$T/o21.json"
"$ZW" estimate "$T/good.h5" -o "$T/frf.csv" 2>/dev/null
awk -F, 'NR==3{$11="1e300"}1' OFS=, "$T/frf.csv" > "$T/frf_navg.csv"
expect frf-csv-bad-count "num_averages = .* is not a whole number" "$T/o24.json" -- "$ZW" fit "$T/frf_navg.csv" -o "$T/o24.json"
if /usr/bin/python3 -c "import h5py" 2>/dev/null; then
  /usr/bin/python3 - "$T" <<'PY'
import sys, shutil, h5py, numpy as np
t = sys.argv[1]
shutil.copy(f"{t}/frf.h5", f"{t}/frf_noim.h5")
with h5py.File(f"{t}/frf_noim.h5", "a") as f:
    del f["/frf/H_im"]
shutil.copy(f"{t}/frf.h5", f"{t}/frf_nan.h5")
with h5py.File(f"{t}/frf_nan.h5", "a") as f:
    f["/frf/H_re"][7] = np.nan
PY
  /usr/bin/python3 - "$T" <<'PY'
import sys, h5py, numpy as np
t = sys.argv[1]
with h5py.File(f"{t}/prealloc.h5", "w") as f:  # a logger that preallocated 1e10 samples and stopped
    f.attrs["sample_rate_hz"] = 1000.0
    for name in ("/input/torque", "/output/position"):
        f.create_dataset(name, shape=(10**8,), chunks=(4096,), dtype="f8")[:4096] = np.random.randn(4096)
with h5py.File(f"{t}/huge.h5", "w") as f:  # declares 1e10 samples: over the cap, refused before any read
    f.attrs["sample_rate_hz"] = 1000.0
    for name in ("/input/torque", "/output/position"):
        f.create_dataset(name, shape=(10**10,), chunks=(4096,), dtype="f8")[:4096] = np.random.randn(4096)
with h5py.File(f"{t}/unwritten.h5", "w") as f:  # contiguous, never written
    f.attrs["sample_rate_hz"] = 1000.0
    f.create_dataset("/input/torque", shape=(10**6,), dtype="f8")
    f.create_dataset("/output/position", data=np.random.randn(10**6))
with h5py.File(f"{t}/compressed.h5", "w") as f:  # fully written, gzip: accepted
    f.attrs["sample_rate_hz"] = 1000.0
    for name in ("/input/torque", "/output/position"):
        f.create_dataset(name, data=np.random.randn(20000), chunks=(4096,), compression="gzip")
PY
  expect h5-preallocated "declares 100000000 samples, but only 1 of its 24415 chunks were ever written" "$T/o25.csv" -- "$ZW" estimate "$T/prealloc.h5" -o "$T/o25.csv"
  expect h5-over-sample-cap "declares 10000000000 samples, more than zwidth reads \(1073741824\)" "$T/o28.csv" -- "$ZW" estimate "$T/huge.h5" -o "$T/o28.csv"
  expect h5-unwritten "torque: declares 1000000 samples, but its data were never written" "$T/o26.csv" -- "$ZW" estimate "$T/unwritten.h5" -o "$T/o26.csv"
  if "$ZW" estimate "$T/compressed.h5" -o "$T/o27.csv" >/dev/null 2>&1 && [ -s "$T/o27.csv" ]; then
    echo "ok   h5-compressed: a fully written gzip log is read"; pass=$((pass+1))
  else
    echo "FAIL h5-compressed: a fully written gzip log was refused"; fail=$((fail+1))
  fi
  expect frf-h5-missing-dataset "no dataset '/frf/H_im'" "$T/o22.json" -- "$ZW" fit "$T/frf_noim.h5" -o "$T/o22.json"
  expect frf-h5-nan "/frf/H_re: value 7 is not finite" "$T/o23.json" -- "$ZW" fit "$T/frf_nan.h5" -o "$T/o23.json"
fi
# A fit that does not converge: exit 1 (not 2), a message, no model file.
"$ZW" fit "$T/good.h5" --max-iterations 1 -o "$T/nc.json" >"$T/stdout" 2>"$T/stderr"; rc=$?
if [ $rc -eq 1 ] && grep -q "did not converge" "$T/stderr" && [ ! -e "$T/nc.json" ]; then
  echo "ok   fit-no-convergence: exit 1, $(head -c 100 "$T/stderr" | tr '\n' ' ')"; pass=$((pass+1))
else
  echo "FAIL fit-no-convergence: exit $rc"; cat "$T/stderr"; fail=$((fail+1))
fi
# --seed: CLI11 wraps -1 to 2^64 - 1 in an unsigned option; a seed is a
# whole number in [0, 2^64 - 1] (simulate, excite, boundary's Monte Carlo).
expect seed-negative "--seed: must be a whole number.*got '-1'" "$T/s1.h5" -- "$ZW" simulate --model "$M" --seed -1 --seconds 1 -o "$T/s1.h5"
expect seed-overflow "--seed: must be a whole number.*18446744073709551616" "$T/s2.h5" -- "$ZW" simulate --model "$M" --seed 18446744073709551616 --seconds 1 -o "$T/s2.h5"
expect seed-fraction "--seed: must be a whole number.*got '1.5'" "$T/e1.txt" -- "$ZW" excite --seed 1.5 -o "$T/e1.txt"
expect seed-boundary "--seed: must be a whole number" "$T/b1.csv" -- "$ZW" boundary "$M" --monte-carlo 10 --seed -2 -o "$T/b1.csv"
# A log too short (issue 24): 39 ms at 1 kHz. One rule (analysis::CheckLogLength) for every
# command that estimates: 3 segments of the shortest default window (256 samples at 1 kHz), so
# 512 samples (0.512 s); refused with exit 2 before any fit or figure, nothing written.
head -40 "$T/good.csv" > "$T/short.csv"
SHORT="the log is too short: 39 samples \(0.039 s at 1000 Hz\).*256 samples.*at least 512 samples \(0.512 s\).*Record a longer log"
expect short-estimate "$SHORT" "$T/sh1.csv" -- "$ZW" estimate "$T/short.csv" -o "$T/sh1.csv"
expect short-fit "$SHORT" "$T/sh2.json" -- "$ZW" fit "$T/short.csv" -o "$T/sh2.json"
expect short-run "$SHORT" "$T/sh3" -- "$ZW" run "$T/short.csv" -o "$T/sh3"
grep -qi gnuplot "$T/stderr" && { echo "FAIL short-run: gnuplot on stderr"; fail=$((fail+1)); }
expect short-window "39 samples \(0.039 s at 1000 Hz\), fewer than one window of 64 samples \(--window-length, 0.064 s\).*use --window-length 32 or less" "$T/sh4.csv" -- "$ZW" estimate "$T/short.csv" --window-length 64 -o "$T/sh4.csv"
head -520 "$T/good.csv" > "$T/long_enough.csv"  # 519 samples >= 512: estimated
if "$ZW" estimate "$T/long_enough.csv" -o "$T/sh5.csv" 2>"$T/stderr" && [ -s "$T/sh5.csv" ]; then
  echo "ok   short-boundary: 519 samples are estimated"; pass=$((pass+1))
else echo "FAIL short-boundary: 519 samples refused"; cat "$T/stderr"; fail=$((fail+1)); fi
"$ZW" batch "$T/short.csv" -o "$T/sh6.csv" >"$T/stdout" 2>"$T/stderr"; rc=$?
if [ $rc -ne 0 ] && grep -q "the log is too short: 39 samples" "$T/sh6.csv" "$T/stderr"; then
  echo "ok   short-batch: exit $rc, the unit's row says the log is too short"; pass=$((pass+1))
else echo "FAIL short-batch: exit $rc"; cat "$T/stderr" "$T/sh6.csv"; fail=$((fail+1)); fi
# simulate follows the model's units (issue 24): a linear model's log says force [N], position [m],
# and is read back by fit --units linear --input-column force; --units must agree with the model.
sed 's/"delay_samples": 0/"delay_samples": 0, "units": "linear"/' "$M" > "$T/lin.json"
expect simulate-units-disagree "--units linear, but .*table1.json is a rotary model" "$T/lin1.csv" -- "$ZW" simulate --model "$M" --units linear -o "$T/lin1.csv"
expect simulate-units-word "--units.*'metric'|metric.*rotary.*linear" "$T/lin2.csv" -- "$ZW" simulate --model "$T/lin.json" --units metric -o "$T/lin2.csv"
if "$ZW" simulate --model "$T/lin.json" --units linear --seconds 4 -o "$T/lin.csv" 2>"$T/stderr" \
   && [ "$(head -1 "$T/lin.csv")" = "t,force [N],position [m]" ] \
   && "$ZW" simulate --model "$M" --seconds 1 -o "$T/rot.csv" 2>/dev/null && [ "$(head -1 "$T/rot.csv")" = "t,torque,position" ] \
   && "$ZW" fit "$T/lin.csv" --units linear --input-column force -o "$T/lin_fit.json" 2>"$T/stderr" && grep -q '"units": "linear"' "$T/lin_fit.json"; then
  echo "ok   simulate-linear: header '$(head -1 "$T/lin.csv")', fitted back as a linear model"; pass=$((pass+1))
else echo "FAIL simulate-linear: $(head -1 "$T/lin.csv" 2>/dev/null)"; cat "$T/stderr"; fail=$((fail+1)); fi
# Output names (issue 24): a name of another format's extension is refused, nothing written (the
# existing file kept byte for byte); a folder is refused; a same-kind file is replaced, as cp does.
cp "$M" "$T/keep.json"
"$ZW" boundary "$M" -o "$T/keep.json" >"$T/stdout" 2>"$T/stderr"; rc=$?
if [ $rc -eq 2 ] && cmp -s "$M" "$T/keep.json" && grep -q "writes a boundary CSV, but '.json' is the extension of another format" "$T/stderr"; then
  echo "ok   boundary-over-model: exit 2, the model kept: $(head -c 120 "$T/stderr")"; pass=$((pass+1))
else echo "FAIL boundary-over-model: exit $rc"; cat "$T/stderr"; fail=$((fail+1)); fi
expect simulate-json "writes a log.*'.json' is the extension of another format.*\.csv" "$T/x.json" -- "$ZW" simulate --model "$M" --seconds 1 -o "$T/x.json"
expect export-ext "writes the python export, but '.json'.*ending \.py" "$T/m.json" -- "$ZW" export "$M" --format python -o "$T/m.json"
expect boundary-summary-ext "writes a summary JSON, but '.csv'" "$T/bs.csv" -- "$ZW" boundary "$M" --summary "$T/bs.csv" -o "$T/bs_b.csv"
mkdir -p "$T/adir"
"$ZW" boundary "$M" -o "$T/adir" >"$T/stdout" 2>"$T/stderr"; rc=$?
[ $rc -eq 2 ] && [ -z "$(ls -A "$T/adir")" ] && { echo "ok   boundary-into-folder: exit 2, $(head -c 100 "$T/stderr")"; pass=$((pass+1)); } ||
  { echo "FAIL boundary-into-folder: exit $rc"; cat "$T/stderr"; fail=$((fail+1)); }
echo old > "$T/again.csv"
if "$ZW" boundary "$M" -o "$T/again.csv" 2>/dev/null >/dev/null && head -1 "$T/again.csv" | grep -q "," && "$ZW" boundary "$M" -o "$T/noext" 2>/dev/null >/dev/null && [ -s "$T/noext" ]; then
  echo "ok   boundary-replaces-csv: an existing CSV is replaced, a name without extension written"; pass=$((pass+1))
else echo "FAIL boundary-replaces-csv"; fail=$((fail+1)); fi
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
