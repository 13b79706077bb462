#!/usr/bin/env bash
# zwidth on logs as labs write them, end to end: the same data in several
# dialects and in .mat files written by Octave give the same frequency response
# as the plain CSV; several runs; whole records; the closed-loop flags; the
# reference defaults of run; refusals (exit 2, nothing written).
# Usage: logs_cli_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
source "$(dirname "$0")/cli_lib.sh"
# same FRF: same f, H within rel (default exact to print precision)
same_frf() {
  $PY - "$1" "$2" "${3:-1e-12}" <<'PY'
import csv, sys
def load(p):
    rows = [r for r in csv.reader(l for l in open(p) if not l.startswith('#'))]
    h = rows[0]; i = {k: h.index(k) for k in h}
    return [(float(r[0]), complex(float(r[i[[k for k in h if k.startswith('H_re')][0]]]), float(r[i[[k for k in h if k.startswith('H_im')][0]]]))) for r in rows[1:]]
a, b = load(sys.argv[1]), load(sys.argv[2]); tol = float(sys.argv[3])
ok = len(a) == len(b) and all(abs(x[0] - y[0]) < 1e-9 and abs(x[1] - y[1]) <= tol * abs(x[1]) for x, y in zip(a, b))
print(f"{len(a)} vs {len(b)} bins, worst rel diff {max(abs(x[1]-y[1])/abs(x[1]) for x, y in zip(a, b)) if len(a) == len(b) else 'n/a'}")
sys.exit(0 if ok else 1)
PY
}

"$ZW" simulate --model "$M" -o "$T/good.csv" --seconds 20 --seed 3 2>/dev/null
"$ZW" estimate "$T/good.csv" -o "$T/ref.csv" 2>"$T/err" || { cat "$T/err"; exit 1; }
grep -q "do not fill a 4096-sample segment" "$T/err" && ok "partial last segment warned: $(grep -o 'the last [0-9]* samples ([0-9.]* %' "$T/err")" || bad "no partial-segment warning"

# Dialects of the same data: semicolon + CRLF + comment lines + commented
# header + ms time + BOM; tab + CR-only + no header; scaled columns.
$PY - "$T" <<'PY'
import sys
d = sys.argv[1]
rows = [l.strip().split(',') for l in open(f"{d}/good.csv")][1:]
with open(f"{d}/semi.txt", "w", newline="") as f:
    f.write("\ufeff# rig 3, run 7\r\n# time [ms]; torque [N m]; angle [rad]\r\n#time_ms;tau;theta\r\n")
    for t, u, y in rows: f.write(f"{float(t)*1000!r};{u};{y}\r\n")
with open(f"{d}/tab.dat", "w", newline="") as f:
    f.write("\r".join(f"{u}\t{y}\t{t}" for t, u, y in rows) + "\r")
with open(f"{d}/scaled.csv", "w") as f:
    f.write("t,volts,counts\n")
    for t, u, y in rows: f.write(f"{t},{float(u)*4!r},{float(y)*1000!r}\n")
PY
"$ZW" estimate "$T/semi.txt" --time-column time_ms --time-unit ms --input-column tau --output-column theta -o "$T/semi_frf.csv" 2>"$T/err" \
  && grep -q "';'-separated, 3 columns, header at line 3 (comment)" "$T/err" && same_frf "$T/ref.csv" "$T/semi_frf.csv" 1e-9 \
  && ok "semicolon/CRLF/BOM/commented header/ms: same FRF" || { bad "semicolon dialect"; cat "$T/err"; }
"$ZW" estimate "$T/tab.dat" --input-column 1 --output-column 2 --time-column 3 -o "$T/tab_frf.csv" 2>"$T/err" \
  && grep -q "tab-separated, 3 columns, no header" "$T/err" && same_frf "$T/ref.csv" "$T/tab_frf.csv" \
  && ok "tab/CR-only/no header by position: same FRF" || { bad "tab dialect"; cat "$T/err"; }
"$ZW" estimate "$T/scaled.csv" --input-column volts --output-column counts --input-scale 0.25 --output-scale 0.001 -o "$T/sc_frf.csv" 2>"$T/err" \
  && same_frf "$T/ref.csv" "$T/sc_frf.csv" 1e-9 && ok "--input-scale/--output-scale undo the units" || { bad "scales"; cat "$T/err"; }

# .mat v6 (uncompressed) and v7 (compressed) written by Octave from the same
# numbers (Octave cannot write -v7.3; log_mat_test covers it via libmatio).
if command -v octave >/dev/null 2>&1; then
  (cd "$T" && timeout 300 octave --no-gui --quiet --eval "d = dlmread('good.csv', ',', 1, 0); t = d(:,1); u = d(:,2); Theta = d(:,3); save('-v6', 'o6.mat', 't', 'u', 'Theta'); save('-v7', 'o7.dat', 't', 'u', 'Theta'); s.u = u; s.Theta = Theta; s.t = t; save('-v7', 'os.mat', 's');" >/dev/null 2>&1)
  for f in o6.mat o7.dat; do
    "$ZW" estimate "$T/$f" --input-column u --output-column Theta -o "$T/$f.frf.csv" 2>"$T/err" && same_frf "$T/ref.csv" "$T/$f.frf.csv" \
      && ok "Octave $f read by content: same FRF" || { bad "Octave $f"; cat "$T/err"; }
  done
  "$ZW" estimate "$T/os.mat" --input-column s.u --output-column s.Theta --time-column s.t -o "$T/os.frf.csv" 2>"$T/err" && same_frf "$T/ref.csv" "$T/os.frf.csv" \
    && ok "Octave struct fields s.u, s.Theta: same FRF" || { bad "Octave struct"; cat "$T/err"; }
  expect mat-missing-variable "no variable 'torque' .*variables: .*Theta.*--input-column" "$T/m1.csv" -- "$ZW" estimate "$T/o6.mat" -o "$T/m1.csv"
else
  echo "octave not installed: .mat files from Octave not checked"
fi

# Several runs and whole records.
"$ZW" simulate --model "$M" -o "$T/run2.csv" --seconds 20 --seed 4 2>/dev/null
"$ZW" estimate "$T/good.csv" "$T/run2.csv" -o "$T/two.csv" 2>"$T/err" && grep -q "from 2 runs, 16 segments" "$T/err" \
  && ok "two runs averaged: $(grep -o 'from 2 runs, [0-9]* segments' "$T/err")" || { bad "two runs"; cat "$T/err"; }
"$ZW" estimate "$T/good.csv" "$T/run2.csv" --whole-record --detrend none -o "$T/whole.csv" 2>"$T/err" \
  && ! grep -q "do not fill" "$T/err" && $PY - "$T/whole.csv" <<'PY' && ok "whole record: 1 segment per run, bin spacing 1/20 s" || { bad "whole record"; cat "$T/err"; }
import sys
rows = [l for l in open(sys.argv[1]) if l[0].isdigit()]
f = [float(r.split(',')[0]) for r in rows]
sys.exit(0 if abs(f[1] - f[0] - 0.05) < 1e-9 else 1)
PY

# Closed-loop flags: with r = u the joint estimate is H1 (CSV and HDF5).
"$ZW" estimate "$T/good.csv" --reference-column torque -o "$T/joint.csv" 2>"$T/err" && grep -q "joint G = S_ry/S_ru" "$T/err" \
  && same_frf "$T/ref.csv" "$T/joint.csv" 1e-9 && ok "--reference-column: joint estimate, equals H1 when r = u" || { bad "reference column"; cat "$T/err"; }
"$ZW" estimate "$T/good.csv" --reference-column torque --coherences-output "$T/coh.csv" -o "$T/joint2.csv" 2>/dev/null && $PY - "$T/coh.csv" <<'PY' && ok "--coherences-output: r->u = 1 and r->y = u->y when r = u" || bad "coherences output"
import sys, csv
rows = list(csv.DictReader(open(sys.argv[1])))
sys.exit(0 if rows and all(abs(float(r["coherence_ru"]) - 1) < 1e-9 and abs(float(r["coherence_ry"]) - float(r["coherence_uy"])) < 1e-9 for r in rows) else 1)
PY
"$ZW" run "$T/good.csv" -o "$T/rj" --delays 2 --reference-column torque >/dev/null 2>"$T/err" && grep -q "coherence_ru coherence_ry" "$T/rj/figures/bode.dat" \
  && grep -q "joint" "$T/rj/summary.json" && ok "run --reference-column: joint estimate, r->u and r->y in the figure data" || { bad "run joint"; cat "$T/err"; }
"$ZW" simulate --model "$M" -o "$T/good.h5" --seconds 20 --seed 3 2>/dev/null
if $PY -c "import h5py" 2>/dev/null; then
  $PY -c "import h5py,sys; f=h5py.File(sys.argv[1],'a'); f['/input/r']=f['/input/torque'][()]" "$T/good.h5"
  "$ZW" estimate "$T/good.h5" --reference-dataset /input/r -o "$T/joint_h5.csv" 2>"$T/err" && same_frf "$T/ref.csv" "$T/joint_h5.csv" 1e-9 \
    && ok "--reference-dataset (HDF5)" || { bad "reference dataset"; cat "$T/err"; }
fi

# run: no comparison unless asked; Table II only beside Table I.
"$ZW" run "$T/good.csv" -o "$T/r0" --delays 2 >/dev/null 2>"$T/err" && [ ! -e "$T/r0/figures/kcr_reference.dat" ] && [ ! -e "$T/r0/figures/table2.dat" ] \
  && grep -q '"reference": "none"' "$T/r0/summary.json" && ok "run without --reference: no comparison, no Table II" || { bad "run default"; cat "$T/err"; }
"$ZW" run "$T/good.csv" -o "$T/r1" --delays 2 --reference table1 >"$T/out" 2>"$T/err" && [ -s "$T/r1/figures/kcr_reference.dat" ] \
  && [ "$(awk '$1 == 2' "$T/r1/figures/table2.dat" | wc -l)" -eq 7 ] && [ "$(awk '$1 != 2' "$T/r1/figures/table2.dat" | wc -l)" -eq 0 ] \
  && grep -q "diff/std" "$T/out" \
  && ok "run --reference table1: comparison and the 7 Table II points at d = 2" || { bad "run table1"; cat "$T/err"; }
"$ZW" run "$T/good.csv" -o "$T/r2" --delays 2 --reference "$M" >/dev/null 2>"$T/err" && [ ! -e "$T/r2/figures/table2.dat" ] \
  && ok "run --reference MODEL.json: no Table II points" || { bad "run model ref"; cat "$T/err"; }
"$ZW" fit "$T/good.csv" --units linear -o "$T/lin.json" >"$T/out" 2>"$T/err" && grep -q "N s/m" "$T/out" && ok "--units linear labels" || { bad "units"; cat "$T/err"; }

# Refusals.
$PY -c "print('t,torque,position'); [print(f'{k},{(k*7)%11},{k%5}') for k in range(5000)]" > "$T/ms.csv"
expect time-in-ms "implies a sample rate of 1 Hz.*--time-unit ms" "$T/e1.csv" -- "$ZW" estimate "$T/ms.csv" -o "$T/e1.csv"
sed '1s/torque/current/' "$T/semi.txt" > "$T/nocol.txt"
expect no-column "no column 'torque'.*';'-separated.*header at line 3 \(comment\)" "$T/e2.csv" -- "$ZW" estimate "$T/nocol.txt" -o "$T/e2.csv"
expect compare-needs-reference "--reference table1" "" -- "$ZW" compare "$M"
expect units-word "--units 'metric'" "$T/e3.json" -- "$ZW" fit "$T/good.csv" --units metric -o "$T/e3.json"
expect whole-record-window "drop --window-length" "$T/e4.csv" -- "$ZW" estimate "$T/good.csv" --whole-record --window-length 1024 -o "$T/e4.csv"
expect dataset-on-text "--reference-column" "$T/e5.csv" -- "$ZW" estimate "$T/good.csv" --reference-dataset /r -o "$T/e5.csv"
expect column-on-hdf5 "--reference-dataset" "$T/e6.csv" -- "$ZW" estimate "$T/good.h5" --reference-column r -o "$T/e6.csv"
expect bad-delimiter "--delimiter '5'" "$T/e7.csv" -- "$ZW" estimate "$T/good.csv" --delimiter 5 -o "$T/e7.csv"
expect runs-differ "same rate and segment length" "$T/e8.csv" -- "$ZW" estimate "$T/good.csv" "$T/ms.csv" --time-unit ms --whole-record -o "$T/e8.csv"
expect period-without-whole "--period-samples 500: needs --whole-record" "$T/e10.csv" -- "$ZW" estimate "$T/good.csv" --period-samples 500 -o "$T/e10.csv"
expect fit-one-whole-record "no per-bin std to weight the fit" "$T/e11.json" -- "$ZW" fit "$T/good.csv" --whole-record -o "$T/e11.json"
expect excite-kind "--kind 'pink'" "$T/e9.txt" -- "$ZW" excite --kind pink -o "$T/e9.txt"
expect run-bad-reference "cannot open|does it exist|not found" "$T/r9" -- "$ZW" run "$T/good.csv" -o "$T/r9" --reference "$T/absent.json"


# Units in the header (issue 29): the same log in mN m and degrees (names), with a units row and
# a decimal comma, and in encoder counts, gives the SI response; counts without a resolution are
# refused with the flag to pass.
$PY - "$T/good.csv" "$T" <<'PY'
import math, sys
rows = [l.split(",") for l in open(sys.argv[1]).read().splitlines()[1:]]
d = sys.argv[2]
open(d + "/mnm.csv", "w").write("t,torque [mNm],position [deg]\n" + "".join(
    f"{t},{float(u) * 1e3!r},{float(y) * 180 / math.pi!r}\n" for t, u, y in rows))
open(d + "/row.csv", "w").write("t;torque;position\ns;N mm;mrad\n" + "".join(
    f"{t};{float(u) * 1e3!r};{float(y) * 1e3!r}\n".replace(".", ",") for t, u, y in rows))
open(d + "/cnt.csv", "w").write("t,torque,position [counts]\n" + "".join(
    f"{t},{u},{float(y) * 8192 / (2 * math.pi)!r}\n" for t, u, y in rows))
PY
"$ZW" estimate "$T/good.csv" -o "$T/uref.csv" 2>/dev/null
"$ZW" estimate "$T/mnm.csv" --input-column "torque [mNm]" --output-column "position [deg]" -o "$T/u1.csv" 2>"$T/err"
grep -q "input unit 'mNm' read: x 0.001 to N m; output unit 'deg' read" "$T/err" && same_frf "$T/uref.csv" "$T/u1.csv" 1e-6 >/dev/null \
  && ok "header units mNm, deg read and said" || { bad "header units mNm, deg"; cat "$T/err"; }
"$ZW" estimate "$T/row.csv" -o "$T/u2.csv" 2>"$T/err"
grep -q "decimal comma.*units row at line 2" "$T/err" && same_frf "$T/uref.csv" "$T/u2.csv" 1e-6 >/dev/null \
  && ok "units row and decimal comma read" || { bad "units row, decimal comma"; cat "$T/err"; }
"$ZW" estimate "$T/cnt.csv" --output-column "position [counts]" --counts-per-rev 8192 -o "$T/u3.csv" 2>"$T/err"
same_frf "$T/uref.csv" "$T/u3.csv" 1e-6 >/dev/null && ok "counts with --counts-per-rev" || { bad "counts with --counts-per-rev"; cat "$T/err"; }
expect counts-need-resolution "--counts-per-rev N.*--counts-per-m N" "$T/u4.csv" -- "$ZW" estimate "$T/cnt.csv" --output-column "position [counts]" -o "$T/u4.csv"
expect unknown-unit "unit 'lbf ft'.*--input-unit si" "$T/u5.csv" -- "$ZW" estimate "$T/mnm.csv" --input-column 2 --input-unit "lbf ft" --output-column 3 -o "$T/u5.csv"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
