#!/usr/bin/env bash
# Issue 30, what round two left: empty items of a delimited list flag; values
# of a response file checked like the flag (one rate per file, in the range
# --rate allows; PSDs >= 0); the report and compare texts the same under a
# German locale. Usage: hostile3_test.sh ZWIDTH SRC
set -u
ZW=$(realpath "$1"); SRC=$(realpath "$2")
source "$SRC/tests/cli_lib.sh"
LOG=$SRC/datasets/phantom/phantom_30s.csv
"$ZW" estimate "$LOG" -o "$T/frf.csv" 2>/dev/null

# ---- empty items of --delays (CLI11 dropped them: 2,,4 was read as 2,4)
for v in "2,,4" ",2" "2," "2, ,4"; do
  expect "boundary-delays[$v]" "--delays.*empty" "$T/o1" -- "$ZW" boundary "$M" --delays "$v" -o "$T/o1"
done
expect boundary-delays-eq "--delays.*empty" "$T/o2" -- "$ZW" boundary "$M" --delays=2,,4 -o "$T/o2"
expect compare-delays "--delays.*empty" "" -- "$ZW" compare "$M" --reference table1 --delays 2,,4
expect run-delays "--delays.*empty" "$T/o3" -- "$ZW" run "$LOG" --delays 2,,4 -o "$T/o3"
"$ZW" boundary "$M" --delays 2,4 --b-points 20 -o "$T/ok.csv" 2>/dev/null && ok "--delays 2,4 still accepted" || bad "--delays 2,4 refused"

# ---- a response file's values, as strictly as --rate and the per-bin rules
$PY - "$T" <<'PYEOF'
import sys
T = sys.argv[1]
rows = open(f"{T}/frf.csv").read().splitlines()
h = [i for i, l in enumerate(rows) if not l.startswith("#")][0]
cols = rows[h].split(",")
def write(name, col, value, which):
    r = list(rows); c = cols.index(col)
    for k in which(range(h + 1, len(r))):
        p = r[k].split(","); p[c] = value; r[k] = ",".join(p)
    open(f"{T}/{name}.csv", "w").write("\n".join(r) + "\n")
one = lambda rng: [rng[4]]  # a row in the middle
every = lambda rng: list(rng)
write("rate_row", "sample_rate_hz", "2000", one)          # one row of another response
write("navg_row", "num_averages", "3", one)
write("rate_period", "sample_rate_hz", "0.001", every)    # the period typed for the rate
write("rate_huge", "sample_rate_hz", "1e9", every)
write("suu_neg", "S_uu", "-1", every)
PYEOF
expect frf-rate-row "line [0-9]+: sample_rate_hz = 2000 differs from 1000" "$T/m1.json" -- "$ZW" fit "$T/rate_row.csv" -o "$T/m1.json"
expect frf-navg-row "num_averages = 3 differs" "$T/m2.json" -- "$ZW" fit "$T/navg_row.csv" -o "$T/m2.json"
expect frf-rate-period "sample_rate_hz = 0.001 Hz.*\[10, 1e6\].*is it the period" "$T/m3.json" -- "$ZW" fit "$T/rate_period.csv" -o "$T/m3.json"
expect frf-rate-huge "sample_rate_hz = 1e\+09 Hz.*\[10, 1e6\]" "$T/m4.json" -- "$ZW" fit "$T/rate_huge.csv" -o "$T/m4.json"
expect frf-rate-flag "--rate = 1e\+09 Hz|--rate.*\[10, 1e6\]" "$T/m5.json" -- "$ZW" fit "$T/frf.csv" --rate 1e9 -o "$T/m5.json"
expect frf-suu-neg "S_uu = -1.*>= 0" "$T/m6.json" -- "$ZW" fit "$T/suu_neg.csv" -o "$T/m6.json"
"$ZW" fit "$T/frf.csv" -o "$T/good.json" >/dev/null 2>&1 && ok "the untouched response still fits" || bad "the untouched response refused"

# ---- NaN and Infinity in a JSON file (Python's json.dump writes them): named, not "malformed"
printf '{"objects":[{"name":"a","K":NaN,"B":0.001}]}' > "$T/nan_scene.json"
expect scene-nan "line 1: NaN is not a JSON number" "" -- "$ZW" check "$T/nan_scene.json" --model "$M" --delay 2
$PY -c "import json,sys; m=json.load(open(sys.argv[1])); m['b']=float('inf'); json.dump(m, open(sys.argv[2],'w'))" "$M" "$T/inf_model.json"
expect model-inf "Infinity is not a JSON number" "$T/o9" -- "$ZW" boundary "$T/inf_model.json" -o "$T/o9"
printf '{"objects":[{"name":"NaN Infinity","K":1.5,"B":0.01}]}' > "$T/nan_name.json"
"$ZW" check "$T/nan_name.json" --model "$M" --delay 2 >/dev/null 2>&1 && ok "NaN inside a string is a name" || bad "NaN inside a string refused"

# ---- the texts under a German locale: byte for byte the C locale's
if locale -a 2>/dev/null | grep -qi '^de_DE\.utf-\?8$'; then
  printf '{"objects":[{"name":"wall","K":1.5,"B":0.01}]}' > "$T/scene.json"
  for c in "compare $M --reference table1 --delays 2,4" "boundary $M --delays 2 --b-points 30 -o -" \
           "check $T/scene.json --model $M --delay 2"; do
    set -- $c
    LC_ALL=C "$ZW" "$@" >"$T/c.txt" 2>&1; LC_ALL=de_DE.UTF-8 "$ZW" "$@" >"$T/de.txt" 2>&1
    cmp -s "$T/c.txt" "$T/de.txt" && grep -q '[0-9]\.[0-9]' "$T/de.txt" && ok "$1 under de_DE.UTF-8: the C locale's text" ||
      { bad "$1 differs under de_DE.UTF-8"; diff "$T/c.txt" "$T/de.txt" | head -4; }
  done
  LC_ALL=C "$ZW" run "$LOG" --no-figures --delays 2 -o "$T/run_c" >/dev/null 2>&1
  LC_ALL=de_DE.UTF-8 "$ZW" run "$LOG" --no-figures --delays 2 -o "$T/run_de" >/dev/null 2>&1
  # The provenance (report line, JSON block) holds the time and the output folder: the rest must match.
  strip() { grep -v "class='provenance'" "$1"; }
  if [ -s "$T/run_de/report.html" ] && diff <(strip "$T/run_c/report.html") <(strip "$T/run_de/report.html") >/dev/null &&
     $PY -c "import json,sys; a,b=(json.load(open(p)) for p in sys.argv[1:3]); a.pop('provenance'); b.pop('provenance'); sys.exit(a!=b)" \
       "$T/run_c/summary.json" "$T/run_de/summary.json"; then ok "run's report.html and summary.json under de_DE.UTF-8"
  else bad "run's report under de_DE.UTF-8 differs"; fi
else
  echo "skip: no de_DE.UTF-8 locale (scripts/setup generates it)"
fi
# ---- scene object names: what a report and a CI gate read the verdicts by
for case in 'empty|{"objects":[{"name":"","K":1,"B":0}]}|non-empty string' \
            'number|{"objects":[{"name":5,"K":1,"B":0}]}|non-empty string' \
            'twice|{"objects":[{"name":"w","K":1,"B":0},{"name":"w","K":2,"B":0}]}|already used'; do
  IFS='|' read -r label json pattern <<<"$case"
  printf '%s' "$json" > "$T/scene_$label.json"
  expect "scene-name-$label" "$pattern" "" -- "$ZW" check "$T/scene_$label.json" --model "$M" --delay 2
done
printf '%s' '{"objects":[{"K":1,"B":0},{"K":2,"B":0}]}' > "$T/scene_unnamed.json"
"$ZW" check "$T/scene_unnamed.json" --model "$M" --delay 2 --json 2>/dev/null | grep -q '"object1"' \
  && ok "scene objects without a name are called object<i>" || bad "unnamed scene objects"

# ---- relay past B_max_from_zero: K_cr = 0 has no crossing, so no frequency
# (it printed "K_cr = 0 N m/rad at nan Hz")
out=$("$ZW" relay "$M" --delay 2 --damping 5 --seconds 2 2>/dev/null)
echo "$out" | grep -q "K_cr = 0 N m/rad (no crossing)" && ! echo "$out" | grep -qi "nan" \
  && ok "relay past B_max_from_zero names no frequency" || bad "relay past B_max_from_zero: $out"

no_temps() { [ -z "$(find "$1" -name '*.tmp-*' 2>/dev/null | head -1)" ]; }
no_temps "$T" && ok "no temporary left" || bad "temporaries left"
echo "hostile3: $pass passed, $fail failed"
[ $fail -eq 0 ]
