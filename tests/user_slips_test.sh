#!/usr/bin/env bash
# A new user's slips (the tryout's findings 5, 6, 11-14, 18): each gets a
# clear refusal (exit 2, what, where, what to do, nothing written) or a
# warning, and a --period other than the model's converts its delay exactly
# as a model written at that period would have it. Usage: user_slips_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
source "$(dirname "$0")/cli_lib.sh"
# json FILE EXPR: prints a value of a JSON file
json() { $PY -c "import json,sys; d=json.load(open(sys.argv[1])); print($2)" "$1"; }
# Two JSON results equal but for their provenance (command, date and inputs differ by design).
same_result() { $PY -c "import json,sys; a,b=(json.load(open(p)) for p in sys.argv[1:3]); a.pop('provenance',None); b.pop('provenance',None); sys.exit(a!=b)" "$1" "$2"; }

"$ZW" simulate --model "$M" -o "$T/good.csv" --seconds 10 --seed 2 2>/dev/null

# ---- 5. --period out of the plausible range (the rate typed instead of the period)
expect period-is-rate "--period = 1000 s.*not the rate: for 1000 Hz pass --period 0.001" "$T/p1.csv" -- "$ZW" boundary "$M" --period 1000 -o "$T/p1.csv"
expect period-in-ms "for 10 Hz pass --period 0.1; for 10 ms pass --period 0.01" "$T/p2.csv" -- "$ZW" boundary "$M" --period 10 -o "$T/p2.csv"
expect period-tiny "--period = 1e-07 s.*\[1e-06, 0.1\]" "$T/p3.csv" -- "$ZW" boundary "$M" --period 1e-7 -o "$T/p3.csv"
echo '{"objects":[{"name":"wall","K":1,"B":0.001}]}' > "$T/scene.json"
expect period-check "not the rate" "" -- "$ZW" check "$T/scene.json" --model "$M" --delay 2 --period 1000
expect period-relay "not the rate" "$T/p4.csv" -- "$ZW" relay "$M" --delay 2 --damping 0 --period 1000 -o "$T/p4.csv"
expect period-compare "not the rate" "" -- "$ZW" compare "$M" --reference table1 --period 1000
expect period-filter-sweep "not the rate" "$T/p5.csv" -- "$ZW" filter-sweep "$M" --delay 2 --period 1000 -o "$T/p5.csv"
expect period-export "not the rate" "$T/p6.m" -- "$ZW" export "$M" --format matlab --period 1000 -o "$T/p6.m"

# ---- 6. --period with a model delay: delay_samples counts the model's own samples.
# d3: 3 samples of 1 ms; d6: the same 3 ms as 6 samples of 0.5 ms (written by hand);
# d3h: 3 samples of 0.5 ms (what the old reading silently used).
$PY - "$M" "$T" <<'PY'
import json, sys
m = json.load(open(sys.argv[1])); d = sys.argv[2]
for name, delay, period in (("d3", 3, 0.001), ("d6", 6, 0.0005), ("d3h", 3, 0.0005), ("d4", 4, 0.001)):
    m2 = dict(m); m2["delay_samples"] = delay; m2["sample_period_s"] = period
    json.dump(m2, open(f"{d}/{name}.json", "w"))
PY
if "$ZW" boundary "$T/d3.json" --period 0.0005 --delays 2 --b-points 50 -o "$T/c3.csv" --summary "$T/c3.json" >/dev/null 2>"$T/err" \
   && grep -q "note: the model's input delay is 3 samples of its sample_period_s 0.001 s (0.003 s): 6 samples at the period 0.0005 s" "$T/err"; then
  ok "boundary --period 0.0005 on a 1 ms model with delay 3: converted to 6 samples, noted"
else bad "delay conversion note"; cat "$T/err"; fi
"$ZW" boundary "$T/d6.json" --delays 2 --b-points 50 -o "$T/c6.csv" --summary "$T/c6.json" >/dev/null 2>&1
"$ZW" boundary "$T/d3h.json" --delays 2 --b-points 50 -o "$T/c3h.csv" --summary "$T/c3h.json" >/dev/null 2>&1
k3=$(json "$T/c3.json" "d['delays'][0]['K_cr_at_zero_B']"); k6=$(json "$T/c6.json" "d['delays'][0]['K_cr_at_zero_B']")
k3h=$(json "$T/c3h.json" "d['delays'][0]['K_cr_at_zero_B']")
if cmp -s "$T/c3.csv" "$T/c6.csv" && [ "$k3" = "$k6" ] && [ "$k3" != "$k3h" ]; then
  ok "converted delay = the model written with 6 samples at 0.5 ms (K_cr(0) $k3, identical CSV; 3 samples at 0.5 ms would give $k3h)"
else bad "converted boundary differs: K_cr(0) $k3 vs $k6 (3 samples at 0.5 ms: $k3h)"; fi
"$ZW" check "$T/scene.json" --model "$T/d3.json" --delay 2 --period 0.0005 --json > "$T/ch3.json" 2>/dev/null
"$ZW" check "$T/scene.json" --model "$T/d6.json" --delay 2 --json > "$T/ch6.json" 2>/dev/null
same_result "$T/ch3.json" "$T/ch6.json" && ok "check --period converts the delay the same way" || bad "check --period conversion"
"$ZW" relay "$T/d3.json" --delay 2 --damping 0 --period 0.0005 --seconds 5 --json > "$T/r3.json" 2>/dev/null
"$ZW" relay "$T/d6.json" --delay 2 --damping 0 --seconds 5 --json > "$T/r6.json" 2>/dev/null
same_result "$T/r3.json" "$T/r6.json" && ok "relay --period converts the delay the same way" || bad "relay --period conversion"
"$ZW" boundary "$T/d4.json" --period 0.002 --delays 2 --b-points 20 -o "$T/c4.csv" >/dev/null 2>"$T/err" \
  && grep -q "2 samples at the period 0.002 s" "$T/err" && ok "4 samples of 1 ms at --period 0.002: 2 samples" || { bad "d4 at 2 ms"; cat "$T/err"; }
expect delay-fraction "input delay is 3 samples of its sample_period_s 0.001 s \(0.003 s\), which is 7.5 samples.*re-fit the model from a log at that rate, or edit its delay_samples" "$T/c5.csv" -- "$ZW" boundary "$T/d3.json" --period 0.0004 -o "$T/c5.csv"
expect delay-fraction-slower "1.5 samples" "" -- "$ZW" check "$T/scene.json" --model "$T/d3.json" --delay 2 --period 0.002

# ---- 5. time columns: a unit in the header, exactly 10 Hz, under 100 Hz
$PY - "$T" <<'PY'
import sys
d = sys.argv[1]
rows = [l.strip().split(',') for l in open(f"{d}/good.csv")][1:]
with open(f"{d}/t_ms.csv", "w") as f:  # a 10 kHz log's time in ms: 0, 0.1, 0.2, ...
    f.write("t_ms,torque,position\n")
    for k, (t, u, y) in enumerate(rows): f.write(f"{k * 0.1!r},{u},{y}\n")
with open(f"{d}/t10.csv", "w") as f:  # the same under a plain "t", 4 decimals: 10 Hz in s (the tryout's file)
    f.write("t,torque,position\n")
    for k, (t, u, y) in enumerate(rows): f.write(f"{k / 10:.4f},{u},{y}\n")
with open(f"{d}/t50.csv", "w") as f:
    f.write("t,torque,position\n")
    for k, (t, u, y) in enumerate(rows): f.write(f"{k * 0.02!r},{u},{y}\n")
PY
expect time-unit-header "the time column 't_ms' looks like milliseconds: pass --time-unit ms \(or --time-unit s if it is in seconds\)" "$T/e1.csv" -- "$ZW" estimate "$T/t_ms.csv" --time-column t_ms -o "$T/e1.csv"
"$ZW" estimate "$T/t_ms.csv" --time-column t_ms --time-unit ms -o "$T/e2.csv" 2>"$T/err" && grep -q "at 10000 Hz" "$T/err" \
  && ok "--time-unit ms reads t_ms at 10 kHz" || { bad "t_ms with --time-unit ms"; cat "$T/err"; }
expect time-10hz "implies a sample rate of 10 Hz.*--time-unit ms \(1e\+04 Hz\)" "$T/e3.csv" -- "$ZW" estimate "$T/t10.csv" -o "$T/e3.csv"
"$ZW" estimate "$T/t50.csv" --window-length 1024 -o "$T/e4.csv" 2>"$T/err" && grep -q "warning: .*implies 50 Hz, low for a haptic device log: if it is in milliseconds pass --time-unit ms" "$T/err" \
  && ok "50 Hz time column: read with a warning naming --time-unit" || { bad "50 Hz warning"; cat "$T/err"; }

# ---- 5. jitter: the whole log's mean interval and --rate
$PY - "$T" <<'PY'
import sys, random
d = sys.argv[1]; random.seed(3)
rows = [l.strip().split(',') for l in open(f"{d}/good.csv")][1:]
with open(f"{d}/jit.csv", "w") as f:
    f.write("t,torque,position\n")
    for k, (t, u, y) in enumerate(rows): f.write(f"{k * 0.001 + random.uniform(-2e-5, 2e-5)!r},{u},{y}\n")
PY
expect jitter "not uniformly sampled at line [0-9]+: .* the log's mean interval (0\.001|0\.000999[0-9]*) s .*--rate 1000 \(the log's mean rate\)" "$T/e5.csv" -- "$ZW" estimate "$T/jit.csv" -o "$T/e5.csv"
"$ZW" estimate "$T/jit.csv" --rate 1000 -o "$T/e6.csv" 2>/dev/null && ok "the suggested --rate reads the jittered log" || bad "jitter --rate"

# ---- 11. non-finite responses: their causes
$PY - "$T" <<'PY'
import sys, math
d = sys.argv[1]
# A multisine with lines 1..200 Hz (period 1000 samples at 1 kHz), 10 periods, through
# a double integrator with a little damping (y only needs to be a response here).
N, P = 10000, 1000
u = [sum(math.cos(2 * math.pi * f * k / P + f * f * math.pi / 200) for f in range(1, 201)) * 1e-3 for k in range(N)]
v = x = 0.0; y = []
for k in range(N):
    y.append(x); v += 1e-3 * (u[k] - 0.5 * v); x += 1e-3 * v
with open(f"{d}/ms.csv", "w") as f:
    f.write("t,torque,position\n")
    for k in range(N): f.write(f"{k / 1000!r},{u[k]!r},{y[k]!r}\n")
PY
expect no-input-power "no input power at 201-500 Hz.*limit the band with --fmax 200" "$T/e7.csv" -- "$ZW" estimate "$T/ms.csv" --whole-record --period-samples 1000 -o "$T/e7.csv"
"$ZW" estimate "$T/ms.csv" --whole-record --period-samples 1000 --fmax 200 -o "$T/e8.csv" 2>/dev/null && ok "--fmax 200 then estimates it" || bad "multisine with --fmax"
awk -F, 'NR>1{$3="0"}1' OFS=, "$T/good.csv" > "$T/zero_out.csv"
expect constant-output "output column 'position' is constant \(every sample 0\).*wrong --output-column" "$T/e9.csv" -- "$ZW" estimate "$T/zero_out.csv" -o "$T/e9.csv"
expect one-whole-record "one segment: no scatter to estimate the per-bin std from" "$T/e10.csv" -- "$ZW" estimate "$T/good.csv" --whole-record -o "$T/e10.csv"

# ---- 14, 18: files of the wrong kind, duplicate keys, b = 0, two outputs on stdout
"$ZW" simulate --model "$M" -o "$T/good.h5" --seconds 5 2>/dev/null
"$ZW" estimate "$T/good.csv" -o "$T/frf.csv" 2>/dev/null
expect model-is-hdf5 "not a model JSON: this is an HDF5 file.*boundary takes a model JSON" "$T/w1.csv" -- "$ZW" boundary "$T/good.h5" -o "$T/w1.csv"
expect model-is-log "not a model JSON: it starts 't,torque,position', like a text log" "$T/w2.csv" -- "$ZW" boundary "$T/good.csv" -o "$T/w2.csv"
expect model-is-frf "a frequency response saved by .zwidth estimate." "" -- "$ZW" check "$T/scene.json" --model "$T/frf.csv" --delay 2
expect scene-is-log "not a scene JSON" "" -- "$ZW" check "$T/good.csv" --model "$M" --delay 2
expect log-is-model "looks like a JSON file \(a model or a scene\), not a log" "$T/w3.json" -- "$ZW" fit "$M" -o "$T/w3.json"
expect two-frfs "a saved frequency response can only be fitted alone" "$T/w4.json" -- "$ZW" fit "$T/frf.csv" "$T/frf.csv" -o "$T/w4.json"
echo '{"m": 1e-3, "b": 0.005,
"modes": [],
"m": 2}' > "$T/dup.json"
expect duplicate-key "line 3: duplicate key 'm' \(first at line 1" "$T/w5.csv" -- "$ZW" boundary "$T/dup.json" -o "$T/w5.csv"
echo '{"objects": [{"name": "a", "K": 1, "B": 0, "K": 2}]}' > "$T/dup_scene.json"
expect duplicate-key-scene "duplicate key 'K'" "" -- "$ZW" check "$T/dup_scene.json" --model "$M" --delay 2
echo '{"m": 1e-3, "b": 0, "modes": []}' > "$T/b0.json"
expect b-zero "key 'b' = 0: b must be > 0; use e.g. 1e-12 for an undamped body" "$T/w6.csv" -- "$ZW" boundary "$T/b0.json" -o "$T/w6.csv"
expect two-stdout "both write to standard output" "" -- "$ZW" boundary "$M" -o - --summary -
expect simulate-band "--bandwidth-hz 600 is above Nyquist \(500 Hz" "$T/s1.csv" -- "$ZW" simulate --model "$M" --bandwidth-hz 600 -o "$T/s1.csv"
expect simulate-rate "--rate 5 Hz: a device log's rate must be above 10 Hz" "$T/s2.csv" -- "$ZW" simulate --model "$M" --rate 5 -o "$T/s2.csv"
"$ZW" simulate --model "$M" --bandwidth-hz 500 --seconds 1 -o "$T/s3.csv" 2>/dev/null && ok "simulate --bandwidth-hz at Nyquist (white) still accepted" || bad "bandwidth at Nyquist"
head -20 "$T/good.csv" > "$T/tiny.csv"
expect tiny-log "the log is too short: 1 Welch segment\(s\) of 16 samples \(the shortest window\).*record a longer log \(at least 32 samples" "$T/w7.json" -- "$ZW" fit "$T/tiny.csv" --window-length 16 -o "$T/w7.json"

# An Octave `save -hdf5` log stores each variable as a group {type, value}.
if $PY -c "import h5py" 2>/dev/null; then
  $PY - "$T" <<'PY'
import sys, h5py, numpy as np
d = sys.argv[1]; rng = np.random.default_rng(1)
with h5py.File(f"{d}/oct.h5", "w") as f:
    for name, v in (("u", rng.standard_normal(3000)), ("y", np.cumsum(rng.standard_normal(3000))), ("t", np.arange(3000) / 1000)):
        f[f"/{name}/type"] = np.bytes_("matrix"); f[f"/{name}/value"] = v
PY
  expect octave-group "'/u' is a group, not a dataset \(members: type, value\); pass --input-dataset /u/value" "$T/o1.csv" -- "$ZW" estimate "$T/oct.h5" --input-dataset /u --output-dataset /y/value --time-dataset /t/value -o "$T/o1.csv"
fi
# Runs of different rates: the rates as numbers, not 2000.000000.
"$ZW" simulate --model "$M" -o "$T/fast.csv" --seconds 10 --rate 2000 2>/dev/null
expect runs-rates "run 2 has 2000 Hz and 4096-sample segments, run 1 1000 Hz" "$T/o2.csv" -- "$ZW" estimate "$T/good.csv" "$T/fast.csv" -o "$T/o2.csv"

# ---- 13. simulate: an output of a few encoder steps is warned about
$PY -c "import json,sys; m=json.load(open(sys.argv[1])); m['m']*=300; m['b']*=300; json.dump(m, open(sys.argv[2],'w'))" "$M" "$T/heavy.json"
"$ZW" simulate --model "$T/heavy.json" -o "$T/h.csv" --seconds 5 2>"$T/err"
steps=$($PY -c "
import sys; y=[float(l.split(',')[2]) for l in open(sys.argv[1]).readlines()[1:]]; print(round((max(y)-min(y))/(6.283185307179586/40960)))" "$T/h.csv")
if grep -q "warning: the output spans only $steps encoder steps.*raise --torque-rms" "$T/err" && [ "$steps" -lt 50 ]; then
  ok "heavy device at the default torque: $steps encoder steps, warned"
else bad "few encoder steps ($steps) not warned"; cat "$T/err"; fi
"$ZW" simulate --model "$M" -o "$T/g2.csv" --seconds 5 2>"$T/err"; grep -q "encoder steps" "$T/err" && bad "PHANToM defaults warned" || ok "PHANToM defaults: no encoder warning"

# ---- 12. reversed output sign, swapped columns: the fit's advice names the cause
"$ZW" fit "$T/good.csv" --output-scale -1 --modes 2 -o "$T/neg.json" >"$T/out" 2>&1
grep -q "sign_reversed\|phase at low frequency is" "$T/out" && grep -q -- "--output-scale -1" "$T/out" \
  && json "$T/neg.json" "[q['code'] for q in d['fit']['quality_reasons']][0]" | grep -qx sign_reversed \
  && ok "reversed output: '$(grep -o "phase at low frequency is [-0-9]* deg" "$T/out" | head -1)', advice --output-scale -1" || { bad "sign advice"; cat "$T/out"; }
"$ZW" fit "$T/good.csv" --input-column position --output-column torque --modes 2 -o "$T/swap.json" >"$T/out" 2>&1
grep -q "|H| rises with frequency" "$T/out" && grep -q -- "--input-column" "$T/out" \
  && ok "swapped columns: '$(grep -o "log-log slope [-+0-9.]*" "$T/out" | head -1)', advice --input-column/--output-column" || { bad "swap advice"; cat "$T/out"; }
"$ZW" fit "$T/good.csv" --modes 2 -o "$T/ok.json" >"$T/out" 2>&1
grep -q "sign_reversed\|rises with frequency" "$T/out" && bad "advice on a correct log" || ok "no sign/swap advice on the correct log"

# ---- the model file's fit record names the CLI's flags, not the library's fields
# (a 128-sample window gives a leakage warning that names the window length)
"$ZW" fit "$T/good.csv" --modes 2 --window-length 128 -o "$T/leak.json" >"$T/out" 2>&1
json "$T/leak.json" "' '.join(d['fit']['warnings'])" | grep -q -- "--window-length" || bad "no leakage warning naming --window-length in leak.json"
grep -q "Options::" "$T/neg.json" "$T/swap.json" "$T/ok.json" "$T/leak.json" && bad "a model file names library fields: $(grep -o "[A-Za-z]*Options::[a-z_]*" "$T/neg.json" "$T/swap.json" | head -3)" \
  || ok "model files name the CLI's flags only"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
