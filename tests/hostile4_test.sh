#!/usr/bin/env bash
# Issue 30, round four: members of the named classes the earlier rounds left.
# (b) flags: CLI11's own messages escaped; a delay twice; an empty text value;
# an explicit 0 that meant "not given"; the relay's --table2 options without
# --table2. (a) the encoder step, a signal's RMS, a loop's B and a scene's K and
# B bounded as the model file and the wall bound them. (d) a response CSV with
# a UTF-8 BOM. (e) a full disk named with its reason and the user's file name.
# Each refusal: exit 2, a message naming the problem, nothing written.
# Usage: hostile4_test.sh ZWIDTH SRC
set -u
ZW=$(realpath "$1"); SRC=$(realpath "$2")
source "$SRC/tests/cli_lib.sh"
LOG=$SRC/datasets/phantom/phantom_30s.csv
"$ZW" estimate "$LOG" -o "$T/frf.csv" 2>/dev/null
no_temps() { [ -z "$(find "$1" -name '*.tmp-*' 2>/dev/null | head -1)" ]; }

# ---- (f) CLI11's messages quote the typed value: shown escaped, not obeyed
for case in "b-points|boundary $M -o $T/o1 --b-points @" "extra|boundary $M -o $T/o1 @" "seed|simulate --model $M -o $T/o1 --seed @"; do
  IFS='|' read -r label cmd <<<"$case"
  set -- ${cmd//@/X}; args=("$@"); for i in "${!args[@]}"; do [ "${args[$i]}" = X ] && args[$i]=$'\e[2J\e[31mred\rx'; done
  "$ZW" "${args[@]}" >/dev/null 2>"$T/stderr"; rc=$?
  if [ $rc -eq 2 ] && ! grep -q $'\e' "$T/stderr" && ! grep -q $'\r' "$T/stderr" && grep -q '\\x1b' "$T/stderr"; then
    ok "CLI11 message escaped ($label): $(head -1 "$T/stderr")"
  else bad "CLI11 message raw ($label), exit $rc: $(cat -A "$T/stderr" | head -2)"; fi
done

# ---- (b) the overlap given is the one a message names (--overlap 0 was "at 50 % overlap")
"$ZW" simulate --model "$M" --seconds 10 -o "$T/ten.csv" >/dev/null 2>&1
expect overlap-0-message "at 0 % overlap, so at least 12288 samples" "$T/o19.csv" -- "$ZW" estimate "$T/ten.csv" --overlap 0 -o "$T/o19.csv"

# ---- (b) a delay given twice: computed twice, its rows and summary repeated
expect boundary-delays-twice "the delay 2 is given twice" "$T/o2" -- "$ZW" boundary "$M" --delays 2,4,2 -o "$T/o2"
expect compare-delays-twice "given twice" "" -- "$ZW" compare "$M" --reference table1 --delays 8,8
expect run-delays-twice "given twice" "$T/o3" -- "$ZW" run "$LOG" --delays 4,4 -o "$T/o3"
"$ZW" boundary "$M" --delays 4,2 --b-points 20 -o "$T/two.csv" >/dev/null 2>&1 && ok "--delays 4,2 still accepted" || bad "--delays 4,2 refused"

# ---- (b) an empty text value silently meant the default
for f in --detrend --time-unit --input-unit --output-unit --delimiter --reference-column --window; do
  expect "empty$f" "$f '': an empty value" "$T/o4.csv" -- "$ZW" estimate "$LOG" "$f" "" -o "$T/o4.csv"
done
expect "empty--detrend=" "--detrend '': an empty value" "$T/o4.csv" -- "$ZW" estimate "$LOG" --detrend= -o "$T/o4.csv"
expect "empty-o" "-o '': an empty value" "" -- "$ZW" boundary "$M" -o ""

# ---- (b) an explicit 0 meant "not given": counts read as radians, the log's rate, the default window
for f in --counts-per-rev --counts-per-m --rate --window-length; do
  expect "zero$f" "$f.*means \"not given\"" "$T/o5.csv" -- "$ZW" estimate "$LOG" "$f" 0 -o "$T/o5.csv"
done
"$ZW" estimate "$LOG" --window-length 2048 -o "$T/wl.csv" 2>/dev/null && ok "--window-length 2048 still accepted" || bad "--window-length 2048 refused"

# ---- (b) the relay's options of compare and run need --table2 (alone they were ignored, even -1)
expect compare-amplitude-alone "--amplitude requires --table2" "" -- "$ZW" compare "$M" --reference table1 --amplitude -1
expect compare-levels-alone "--coulomb-levels requires --table2" "" -- "$ZW" compare "$M" --reference table1 --coulomb-levels 0.01
expect run-seconds-alone "--seconds requires --table2" "$T/o6" -- "$ZW" run "$LOG" --seconds 5 -o "$T/o6"

# ---- (a) the encoder step, as the model file bounds it: 0 or [1e-12, 1] per count
expect wall-encoder "--encoder-step = 1e\+300: an encoder step is 0" "$T/o7" -- "$ZW" wall "$M" --delay 2 --damping 0 --stiffness 1 --seconds 1 --encoder-step 1e300 -o "$T/o7"
expect relay-encoder "--encoder-step = 2: an encoder step is 0" "" -- "$ZW" relay "$M" --delay 2 --damping 0 --seconds 1 --encoder-step 2
expect compare-table2-encoder "--encoder-step = 1e\+300" "" -- "$ZW" compare "$M" --reference table1 --table2 --seconds 1 --encoder-step 1e300
expect simulate-encoder "--encoder-step = 5: an encoder step" "$T/o8.csv" -- "$ZW" simulate --model "$M" --seconds 1 --encoder-step 5 -o "$T/o8.csv"
expect simulate-encoder-tiny "--encoder-step = 1e-300" "$T/o8.csv" -- "$ZW" simulate --model "$M" --seconds 1 --encoder-step 1e-300 -o "$T/o8.csv"
printf '{"objects":[{"name":"w","K":1,"B":0.01}]}' > "$T/scene.json"
expect check-encoder "--encoder-step = 3" "" -- "$ZW" check "$T/scene.json" --model "$M" --delay 2 --encoder-step 3
"$ZW" relay "$M" --delay 2 --damping 0 --seconds 2 --encoder-step 0 >/dev/null 2>&1 && ok "--encoder-step 0 (exact) still accepted" || bad "--encoder-step 0 refused"

# ---- (a) a fixed fit delay beyond what a model file holds (100000 was fitted and written, then refused)
expect fit-delay-huge "--delay-samples must be in \[0, 1000\]" "$T/o12.json" -- "$ZW" fit "$T/frf.csv" --modes 2 --delay-samples 100000 -o "$T/o12.json"
expect boundary-k-factor "--amplitude-k-factor = 1e\+300 must be in \(1, 100\]" "$T/o13.csv" -- "$ZW" boundary "$M" --amplitude-k-factor 1e300 -o "$T/o13.csv"

# ---- (a) a signal's RMS: 1e300 was written (then refused by every reader), 1e308 as "rms=inf"
expect simulate-rms-huge "--torque-rms = 1e\+300 is above 1e12" "$T/o9.csv" -- "$ZW" simulate --model "$M" --seconds 1 --torque-rms 1e300 -o "$T/o9.csv"
expect excite-rms-huge "--rms = 1e\+308 is above 1e12" "$T/o10.csv" -- "$ZW" excite --rms 1e308 -o "$T/o10.csv"

# ---- (c) the sample counts of simulate and excite, bounded in memory (1e8: 2.4 GB and ~5.8 GB)
expect simulate-samples "more than simulate writes \(4e7\)" "$T/o15.h5" -- "$ZW" simulate --model "$M" --seconds 50000 -o "$T/o15.h5"
expect excite-samples "over 1e7 samples" "$T/o16.csv" -- "$ZW" excite --seconds 20000 -o "$T/o16.csv"

# ---- (b) B ranges past a loop's bound and a Coulomb level twice (simulated twice, its column twice)
expect boundary-b-max-huge "--b-max = 1e\+300 is above 1e12" "$T/o17.csv" -- "$ZW" boundary "$M" --b-max 1e300 -o "$T/o17.csv"
expect sweep-area-b-max-huge "--area-b-max must be at most 1e12" "$T/o18.csv" -- "$ZW" filter-sweep "$M" --delay 2 --measure area --area-b-max 1e300 -o "$T/o18.csv"
expect compare-levels-twice "the level 0.01 is given twice" "" -- "$ZW" compare "$M" --reference table1 --table2 --seconds 1 --coulomb-levels 0.01,0.01

# ---- (a) a loop's B and a scene's K and B, bounded as the wall's --stiffness/--damping and a hand
expect relay-damping-huge "--damping must lie in \[0, 1e12\]" "" -- "$ZW" relay "$M" --delay 2 --damping 1e300 --seconds 1
printf '{"objects":[{"name":"w","K":1e300,"B":0.01}]}' > "$T/scene_k.json"
printf '{"objects":[{"name":"w","K":1,"B":1e13}]}' > "$T/scene_b.json"
expect scene-K-huge "'K' = 1e\+300 must be finite and in \[0, 1e12\]" "" -- "$ZW" check "$T/scene_k.json" --model "$M" --delay 2
expect scene-B-huge "'B' = 1e\+13 must be finite and in \[0, 1e12\]" "" -- "$ZW" check "$T/scene_b.json" --model "$M" --delay 2

# ---- (d) a response CSV saved with a UTF-8 BOM (a spreadsheet's): read, not taken for a log
printf '\xef\xbb\xbf' > "$T/frf_bom.csv"; cat "$T/frf.csv" >> "$T/frf_bom.csv"
if "$ZW" fit "$T/frf_bom.csv" --modes 2 --delay-samples 0 -o "$T/bom.json" >/dev/null 2>"$T/stderr" &&
   "$ZW" fit "$T/frf.csv" --modes 2 --delay-samples 0 -o "$T/plain.json" >/dev/null 2>&1 &&
   $PY -c "import json,sys; a,b=(json.load(open(p)) for p in sys.argv[1:3]); sys.exit(not (a['m']==b['m'] and a['modes']==b['modes']))" "$T/bom.json" "$T/plain.json"; then
  ok "a response CSV with a BOM fits as the same file without it"
else bad "a response CSV with a BOM: $(tail -1 "$T/stderr")"; fi

# ---- (d) a response .h5 whose sample_rate_hz attribute is NaN: named, not "no sample_rate_hz attribute"
if $PY -c "import h5py" 2>/dev/null; then
  "$ZW" estimate "$LOG" -o "$T/frf.h5" >/dev/null 2>&1
  $PY -c "import h5py, sys; f = h5py.File(sys.argv[1], 'r+'); f.attrs['sample_rate_hz'] = float('nan')" "$T/frf.h5"
  expect frf-h5-rate-nan "sample_rate_hz = nan is not a finite number" "$T/o14.json" -- "$ZW" fit "$T/frf.h5" --modes 2 -o "$T/o14.json"
fi

# ---- (d) a manifest with a UTF-8 BOM (refused: "it reads 'serial,path'")
mkdir -p "$T/line"; cp "$LOG" "$T/line/u1.csv"
printf '\xef\xbb\xbfserial,path\nA,u1.csv\n' > "$T/line/bom.csv"
if "$ZW" batch --manifest "$T/line/bom.csv" -o "$T/fleet_bom.csv" --jobs 1 >/dev/null 2>"$T/stderr" && grep -q '^A,' "$T/fleet_bom.csv"; then
  ok "a manifest with a BOM is read"
else bad "a manifest with a BOM: $(tail -1 "$T/stderr")"; fi

# ---- (d) a MATLAB logical array as a signal (read as 0/1 samples; an HDF5 boolean is refused)
if $PY -c "import scipy" 2>/dev/null; then
  $PY -c "
import sys, numpy as np, scipy.io as sio
n = 5000; t = np.arange(n) / 1000.0; u = np.random.default_rng(1).standard_normal(n)
sio.savemat(sys.argv[1], {'t': t, 'torque': u > 0, 'position': np.cumsum(np.cumsum(u)) * 1e-6})" "$T/logical.mat"
  expect mat-logical "'torque' is a logical array" "$T/o11.csv" -- "$ZW" estimate "$T/logical.mat" --window-length 512 -o "$T/o11.csv"
fi

# ---- (e) a full disk: the reason and the user's name, not "failed writing 'X.tmp-abc123'"
mkdir -p "$T/full"
if mount -t tmpfs -o size=64k tmpfs "$T/full" 2>/dev/null; then
  expect full-boundary "failed writing '$T/full/b.csv': No space left on device" "$T/full/b.csv" -- "$ZW" boundary "$M" --b-points 20000 -o "$T/full/b.csv"
  expect full-estimate "failed writing '$T/full/f.csv': No space left" "$T/full/f.csv" -- "$ZW" estimate "$LOG" -o "$T/full/f.csv"
  expect full-simulate "failed writing '$T/full/s.csv': No space left" "$T/full/s.csv" -- "$ZW" simulate --model "$M" --seconds 30 -o "$T/full/s.csv"
  expect full-simulate-h5 "failed writing '$T/full/s.h5': No space left" "$T/full/s.h5" -- "$ZW" simulate --model "$M" --seconds 30 -o "$T/full/s.h5"
  expect full-run "failed writing '$T/full/run/[a-z]+\.[a-z]+': No space left" "$T/full/run" -- "$ZW" run "$LOG" --no-figures --delays 2 -o "$T/full/run"
  [ -z "$(ls -A "$T/full")" ] && ok "the full disk holds nothing afterwards" || bad "the full disk holds $(ls -A "$T/full")"
  umount "$T/full"
else
  echo "skip: cannot mount a tmpfs here (the full-disk messages)"
fi

no_temps "$T" && ok "no temporary left" || bad "temporaries left: $(find "$T" -name '*.tmp-*' | head -3)"
echo "hostile4: $pass passed, $fail failed"
[ $fail -eq 0 ]
