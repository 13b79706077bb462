#!/bin/bash
# The fleet's done-when test (issue 28): UNITS simulated units of a line (tests/fleet_generator.py:
# Table I as the design, seeded manufacturing scatter, one unit of each defect: m out of tolerance,
# a loose part's extra mode, heavy friction, the torque's sign wrong, a truncated log) through
# `zwidth batch --reference design.json`. The right verdict for each (normal units pass; the
# out-of-tolerance and defective ones fail, the truncated log is recorded as an input error and the
# batch goes on; the wrong sign fails on a poor fit or is refused by it, recorded), the defective ones flagged as outliers with a reason naming what is off, at most
# 2 % of the normal units flagged, the fleet report and the population table written; then an
# interrupted batch (SIGTERM after INTERRUPT_S s) resumed: the rows saved are taken, not computed,
# and the final table equals an uninterrupted one byte for byte.
# Usage: fleet_test.sh ZWIDTH SRC [UNITS=200] [SECONDS=4]
ZW=$1; SRC=$2; UNITS=${3:-200}; SECONDS_LOG=${4:-4}
source "$SRC/tests/cli_lib.sh"
FLAGS=(--delays 2,4 --window-length 512 --modes 2 --reference "$T/line/design.json" --spec "F_c<=0.005")
$PY "$SRC/tests/fleet_generator.py" "$ZW" "$T/line" "$UNITS" "$SECONDS_LOG" || { echo "FAIL generator"; exit 1; }
start=$(date +%s.%N)
"$ZW" batch --manifest "$T/line/units.csv" -o "$T/full.csv" "${FLAGS[@]}" --population "$T/pop.csv" \
  --fleet-report "$T/fleet.html" 2>"$T/full.err"; rc=$?
end=$(date +%s.%N)
[ $rc -eq 4 ] && ok "batch of $UNITS units: exit 4 (a unit failed), $(tail -1 "$T/full.err")" || bad "batch: exit $rc: $(tail -3 "$T/full.err")"
$PY - "$T/full.csv" "$T/line/truth.csv" "$T/pop.csv" "$T/fleet.html" <<'PY' && ok "verdicts, outliers, population table and report" || bad "verdicts and outliers"
import csv, sys
table, truth, pop, html = sys.argv[1:5]
kind = {r["serial"]: r["kind"] for r in csv.DictReader(open(truth))}
rows = {r["serial"]: r for r in csv.DictReader(open(table))}
assert set(rows) == set(kind), "every unit has its row"
bad = []
normal_outliers = []
# What each defect must show in its reasons (verdict or outlier): the column or the cause. Batch
# fits the Coulomb level as run does, so heavy friction fails the F_c spec (a linear-only fit
# failed b<= instead, with the friction folded into the damping).
want = {"out_of_tolerance": ("fail", "m<=", "m = "), "loose_part": ("fail", "fit is poor", "poor fit"),
        "friction": ("fail", "F_c<=", ""), "wrong_sign": ("fail", "fit is poor", "")}
for s, r in rows.items():
    k = kind[s]
    if k == "normal":
        if r["status"] != "ok" or r["verdict"] != "pass":
            bad.append(f"{s} normal: {r['status']} {r['verdict']} {r['verdict_reasons'][:200]} {r['error'][:100]}")
        if r["outlier"] == "yes":
            normal_outliers.append(s)
    elif k == "truncated":
        if r["status"] != "input_error" or r["verdict"] != "error" or "samples" not in r["error"]:
            bad.append(f"{s} truncated: {r['status']} {r['verdict']} {r['error'][:100]}")
    elif k == "wrong_sign" and r["status"] != "ok":  # refused by the fit: recorded with its error
        print(f"  {s} wrong_sign: {r['status']}: {r['error'][:160]}")
        if not r["error"] or r["verdict"] != "error":
            bad.append(f"{s} wrong_sign: {r['status']} without an error")
    else:
        verdict, in_reasons, in_outlier = want[k]
        if r["verdict"] != verdict or in_reasons not in r["verdict_reasons"]:
            bad.append(f"{s} {k}: verdict {r['verdict']} {r['verdict_reasons'][:200]}")
        if r["outlier"] != "yes" or in_outlier not in r["outlier_reasons"]:
            bad.append(f"{s} {k}: outlier {r['outlier']} {r['outlier_reasons'][:200]}")
n_normal = sum(k == "normal" for k in kind.values())
print(f"  {n_normal} normal units, {len(normal_outliers)} flagged as outliers: {normal_outliers}")
if len(normal_outliers) > 0.02 * n_normal:
    bad.append(f"{len(normal_outliers)} normal units flagged")
cols = {r["column"]: r for r in csv.DictReader(open(pop))}
# The population's median of m is the median of the table's ok rows (an independent computation).
import statistics
ms = sorted(float(r["m"]) for r in rows.values() if r["status"] == "ok")
if abs(float(cols["m"]["median"]) - statistics.median(ms)) > 1e-15:
    bad.append(f"population median m {cols['m']['median']} != {statistics.median(ms)}")
page = open(html).read()
for what in ("<svg", "Failures and outliers", "Regions", "Distributions"):
    if what not in page:
        bad.append(f"the report lacks {what}")
if "src=" in page or "href=" in page:
    bad.append("the report loads something from elsewhere")
print("\n".join("  " + b for b in bad))
sys.exit(1 if bad else 0)
PY
# Interrupted after a few seconds (SIGTERM), then run again: the saved rows are resumed.
"$ZW" batch --manifest "$T/line/units.csv" -o "$T/part.csv" "${FLAGS[@]}" 2>/dev/null &
pid=$!
sleep "${INTERRUPT_S:-8}"; kill -TERM $pid; wait $pid
saved=$($PY -c "import csv,sys; print(sum(1 for _ in csv.DictReader(open(sys.argv[1]))))" "$T/part.csv" 2>/dev/null || echo 0)
"$ZW" batch --manifest "$T/line/units.csv" -o "$T/part.csv" "${FLAGS[@]}" 2>"$T/resume.err"
line=$(tail -1 "$T/resume.err")
resumed=$(echo "$line" | sed -n 's/.* \([0-9]*\) resumed, \([0-9]*\) computed.*/\1 \2/p')
[ "$saved" -gt 0 ] && [ "$resumed" = "$saved $((UNITS - saved))" ] && ok "resumed after SIGTERM: $saved rows saved and taken, $((UNITS - saved)) computed" \
  || bad "resume: $saved saved, got '$line'"
cmp -s "$T/full.csv" "$T/part.csv" && ok "the resumed table equals the uninterrupted one" || bad "resumed table differs"
echo "$pass passed, $fail failed (batch of $UNITS: $(echo "$end - $start" | bc) s wall)"
[ $fail -eq 0 ]
