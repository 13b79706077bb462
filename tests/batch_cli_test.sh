#!/bin/bash
# zwidth batch (issue 28): many units into one table, each row as `run` gives
# that log (to the last digit), a broken log recorded without stopping the
# batch, resume by the hash of the inputs and options, manifest flags per
# unit, the same table on 1 and 2 threads, no progress in a pipe.
# Logs: `zwidth simulate` of Table I (white-noise torque, seeds 1..4), one as
# .h5; a corrupt text log (letters where numbers go); a missing file.
# Usage: batch_cli_test.sh ZWIDTH SRC
ZW=$1; SRC=$2
source "$SRC/tests/cli_lib.sh"
# The flags of every batch and run here (the fit's defaults may change: the
# test compares batch with run under the same flags, never with numbers).
FLAGS=(--delays 2,4 --b-points 20 --window-length 1024)
for s in 1 2 3; do "$ZW" simulate --model "$M" -o "$T/u$s.csv" --seconds 8 --seed $s 2>/dev/null; done
"$ZW" simulate --model "$M" -o "$T/u4.h5" --seconds 8 --seed 4 2>/dev/null
printf 't,torque,position\n0,1,2\n0.001,x,y\n0.002,zz,\n' >"$T/bad.csv"

# compare TABLE SERIAL RUNDIR: the row's parameters, std and Z-width figures equal run's model.json / summary.json.
compare() {
  $PY - "$@" <<'PY'
import csv, json, math, sys
table, serial, rundir = sys.argv[1:4]
row = next(r for r in csv.DictReader(open(table)) if r["serial"] == serial)
model = json.load(open(rundir + "/model.json")); summ = json.load(open(rundir + "/summary.json"))
def same(cell, want, what):
    got = float(cell)
    want = float("nan") if want is None else float(want)
    if not (got == want or (math.isnan(got) and math.isnan(want))):
        sys.exit(f"{serial} {what}: batch {cell} != run {want!r}")
plant = model["plant"] if "plant" in model else model
std = model.get("std_errors") or model.get("std") or {}
n = 0
for k in ("m", "b"):
    same(row[k], plant[k], k); n += 1
    if k in std: same(row[k + "_std"], std[k], k + "_std"); n += 1
assert int(row["modes"]) == len(plant["modes"]), "modes"
for i, md in enumerate(plant["modes"]):
    for k in ("omega", "c", "v", "d"):
        same(row[f"mode{i+1}_{k}"], md[k], f"mode{i+1}_{k}"); n += 1
        if std.get("modes"): same(row[f"mode{i+1}_{k}_std"], std["modes"][i][k], f"mode{i+1}_{k}_std"); n += 1
assert int(row["delay_samples"]) == plant["delay_samples"]
assert row["fit_quality"] == summ["fit_quality"], (row["fit_quality"], summ["fit_quality"])
assert row["fit_reasons"] == ";".join(r["code"] for r in summ["fit_quality_reasons"])
# The friction as model.json has it: fit.friction's status and linear-only b, the model's friction and std.
fr = (model.get("fit") or {}).get("friction")
for k in ("friction_status", "F_c", "F_c_std", "friction_offset", "friction_offset_std", "linear_only_b"):
    assert k in row, f"{serial}: no column {k}"
if fr is None:
    assert row["friction_status"] == "", row["friction_status"]
else:
    assert row["friction_status"] == fr["status"], (row["friction_status"], fr["status"])
    same(row["linear_only_b"], fr["linear_only_b"], "linear_only_b"); same(row["linear_only_b_std"], fr["linear_only_b_std"], "linear_only_b_std"); n += 2
    assert row["friction_topology"] == fr.get("topology", ""), (row["friction_topology"], fr.get("topology"))
if "friction" in model:
    f, fs = model["friction"], std.get("friction", {})
    assert f["coulomb_pos"] == f["coulomb_neg"], f
    same(row["F_c"], f["coulomb_pos"], "F_c"); same(row["friction_offset"], f.get("offset", 0.0), "friction_offset"); n += 2
    same(row["F_c_std"], fs.get("coulomb_pos"), "F_c_std"); same(row["friction_offset_std"], fs.get("offset"), "friction_offset_std"); n += 2
elif fr is not None:  # looked at, none found: the model's friction is 0
    assert float(row["F_c"]) == 0.0 and float(row["friction_offset"]) == 0.0 and math.isnan(float(row["F_c_std"])), row["F_c"]
else:
    assert row["F_c"] == "" and row["F_c_std"] == "", (row["F_c"], row["F_c_std"])
for e in summ["boundary"]:
    d = e["delay_samples"]
    for k in ("K_cr_at_zero_B", "K_cr_max", "B_t", "B_max", "B_max_from_zero"):
        same(row[f"d{d}_{k}"], e[k], f"d{d}_{k}"); n += 1
    for k in ("K_cr_at_zero_B", "K_cr_max", "B_t", "B_max"):
        same(row[f"d{d}_{k}_std"], e["std"][k], f"d{d}_{k}_std"); n += 1
print(f"{serial}: {n} numbers equal run's")
PY
}

# 1. Paths and a glob, a corrupt log among them: exit 4, every unit has its row.
"$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/t.csv" "${FLAGS[@]}" >"$T/out" 2>"$T/err"; rc=$?
[ $rc -eq 4 ] && ok "a batch with a corrupt log ends with exit 4" || { bad "exit $rc, expected 4"; cat "$T/err"; }
rows=$($PY -c "import csv,sys; print(sum(1 for _ in csv.DictReader(open(sys.argv[1]))))" "$T/t.csv")
[ "$rows" = 5 ] && ok "5 units, 5 rows" || bad "rows: $rows"
$PY - "$T/t.csv" "$T/bad.csv" <<'PY' && ok "the corrupt log's row holds its error, the others are ok" || bad "status column"
import csv, sys
rows = {r["serial"]: r for r in csv.DictReader(open(sys.argv[1]))}
bad = rows[sys.argv[2]]
assert bad["status"] == "input_error" and sys.argv[2] in bad["error"], bad
assert sum(r["status"] == "ok" for r in rows.values()) == 4, [r["status"] for r in rows.values()]
PY
grep -q $'\r' "$T/err" && bad "progress written into a pipe" || ok "no progress line in a pipe"

# 2. Each row equals `zwidth run` on that log with the same flags, to the last digit.
for u in u1.csv u2.csv u3.csv u4.h5; do
  "$ZW" run "$T/$u" -o "$T/run_$u" --no-figures "${FLAGS[@]}" >/dev/null 2>&1 || bad "run $u failed"
  if msg=$(compare "$T/t.csv" "$T/$u" "$T/run_$u" 2>&1); then ok "$msg"; else bad "$msg"; fi
done

# 2b. A device with Coulomb friction (Table I, 4 mN m at the motor): batch fits it as run does (run's
# --friction auto, one rule: analysis::EstimateAndFit), so its row is run's to the last digit, F_c included;
# with specs on F_c and K_CR^max its verdict is the one computed here from run's values and std.
"$ZW" simulate --model "$M" -o "$T/fric.csv" --seconds 12 --seed 7 --coulomb 0.004 2>/dev/null
SPECS=(--spec "F_c<=0.0045" --spec "d2_K_cr_max>=30")
"$ZW" batch "$T/fric.csv" "$T/u1.csv" -o "$T/fric_t.csv" "${SPECS[@]}" "${FLAGS[@]}" 2>"$T/err" || { bad "friction batch"; cat "$T/err"; }
"$ZW" run "$T/fric.csv" -o "$T/run_fric" --no-figures "${FLAGS[@]}" >/dev/null 2>&1 || bad "run fric.csv failed"
if msg=$(compare "$T/fric_t.csv" "$T/fric.csv" "$T/run_fric" 2>&1); then ok "friction unit: $msg"; else bad "$msg"; fi
if msg=$(compare "$T/fric_t.csv" "$T/u1.csv" "$T/run_u1.csv" 2>&1); then ok "linear unit beside it: $msg"; else bad "$msg"; fi
$PY - "$T/fric_t.csv" "$T/fric.csv" "$T/run_fric" "$T/u1.csv" "$T/run_u1.csv" <<'PY' && ok "friction fitted (not on the linear unit), verdicts as from run's values" || bad "friction verdict"
import csv, json, math, sys
t, fric, fdir, lin, ldir = sys.argv[1:6]
rows = {r["serial"]: r for r in csv.DictReader(open(t))}
def verdict(rundir):
    m = json.load(open(rundir + "/model.json")); s = json.load(open(rundir + "/summary.json"))
    b2 = next(e for e in s["boundary"] if e["delay_samples"] == 2)
    fc = m.get("friction", {}).get("coulomb_pos", 0.0); fcs = m.get("std", {}).get("friction", {}).get("coulomb_pos", float("nan"))
    ps = []
    for v, sd, bound, at_least in ((fc, fcs, 0.0045, False), (b2["K_cr_max"], b2["std"]["K_cr_max"], 30.0, True)):
        met = v >= bound if at_least else v <= bound
        p = 1.0 if met else 0.0
        if math.isfinite(v) and math.isfinite(sd) and sd > 0:
            z = (v - bound if at_least else bound - v) / sd
            p = 0.5 * math.erfc(-z / math.sqrt(2))
        ps.append(p)
    p = min(ps)
    v = "pass" if p >= 0.95 else "fail" if p <= 0.05 else "marginal"
    return "fail" if s["fit_quality"] == "poor" else v
assert rows[fric]["friction_status"] == "fitted" and float(rows[fric]["F_c"]) > 0, rows[fric]["friction_status"]
assert rows[lin]["friction_status"] == "not detected" and float(rows[lin]["F_c"]) == 0, rows[lin]["friction_status"]
for serial, d in ((fric, fdir), (lin, ldir)):
    assert rows[serial]["verdict"] == verdict(d), (serial, rows[serial]["verdict"], verdict(d), rows[serial]["verdict_reasons"])
print(rows[fric]["verdict"], rows[lin]["verdict"])
PY

# 3. Resume: the same batch again computes nothing and writes the same table.
cp "$T/t.csv" "$T/t0.csv"
"$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/t.csv" "${FLAGS[@]}" 2>"$T/err"
grep -q "5 resumed, 0 computed" "$T/err" && cmp -s "$T/t.csv" "$T/t0.csv" && ok "a re-run resumes every unit, same table" \
  || { bad "resume"; cat "$T/err"; }
# A changed log is computed again, alone.
"$ZW" simulate --model "$M" -o "$T/u2.csv" --seconds 8 --seed 12 2>/dev/null
"$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/t.csv" "${FLAGS[@]}" 2>"$T/err"
grep -q "4 resumed, 1 computed" "$T/err" && ok "a changed log alone is computed again" || { bad "changed log"; cat "$T/err"; }
"$ZW" run "$T/u2.csv" -o "$T/run_u2b" --no-figures "${FLAGS[@]}" >/dev/null 2>&1
if msg=$(compare "$T/t.csv" "$T/u2.csv" "$T/run_u2b" 2>&1); then ok "recomputed row: $msg"; else bad "$msg"; fi
# Other options: every unit again.
"$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/t.csv" --delays 2 --b-points 20 --window-length 1024 2>"$T/err"
grep -q "0 resumed, 5 computed" "$T/err" && ok "other options: every unit computed" || { bad "options change"; cat "$T/err"; }
# An interrupted batch: a table of the first two units, then the whole batch resumes them.
"$ZW" batch "$T/u1.csv" "$T/u2.csv" -o "$T/part.csv" "${FLAGS[@]}" 2>/dev/null
"$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" -o "$T/part.csv" "${FLAGS[@]}" 2>"$T/err"
grep -q "2 resumed, 2 computed" "$T/err" && ok "units of an earlier partial table are not recomputed" || { bad "partial"; cat "$T/err"; }

# Interrupted for real: SIGTERM (a background job of a script ignores SIGINT) once the first checkpoint (every 2 s) is on disk; the re-run
# resumes the units it holds and gives the table of an uninterrupted batch.
for s in 5 6 7 8 9; do "$ZW" simulate --model "$M" -o "$T/v$s.csv" --seconds 8 --seed $s 2>/dev/null; done
"$ZW" batch "$T/u[1-3].csv" "$T/v*.csv" -o "$T/whole.csv" --jobs 1 "${FLAGS[@]}" 2>/dev/null
"$ZW" batch "$T/u[1-3].csv" "$T/v*.csv" -o "$T/int.csv" --jobs 1 "${FLAGS[@]}" 2>/dev/null & pid=$!
for _ in $(seq 600); do [ -f "$T/int.csv" ] && break; sleep 0.05; done
kill -TERM $pid 2>/dev/null; wait $pid; rc=$?
saved=$($PY -c "import csv,sys; print(sum(1 for _ in csv.DictReader(open(sys.argv[1]))))" "$T/int.csv" 2>/dev/null)
if [ $rc -ne 0 ] && [ -n "$saved" ] && [ "$saved" -lt 8 ]; then
  "$ZW" batch "$T/u[1-3].csv" "$T/v*.csv" -o "$T/int.csv" --jobs 1 "${FLAGS[@]}" 2>"$T/err"
  grep -q "$saved resumed, $((8 - saved)) computed" "$T/err" && cmp -s "$T/int.csv" "$T/whole.csv" && \
    ok "interrupted after $saved of 8 units: the re-run computes the other $((8 - saved)), the same table" || { bad "interrupted resume"; cat "$T/err"; }
else
  echo "skip interrupt: the batch ended (exit $rc) before its first checkpoint (${saved:-no} rows)"
fi
ls -a "$T" | grep -q '\.tmp' && bad "a temporary file left after the signal" || ok "no temporary file left after the signal"

# 4. Threads: 1 and 2 units at once give the same table, byte for byte.
ZWIDTH_NUM_THREADS=2 "$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/j1.csv" --jobs 1 "${FLAGS[@]}" 2>/dev/null
ZWIDTH_NUM_THREADS=2 "$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/j2.csv" --jobs 2 "${FLAGS[@]}" 2>"$T/err"
cmp -s "$T/j1.csv" "$T/j2.csv" && grep -q "on 2 threads" "$T/err" && ok "--jobs 1 and --jobs 2: the same table" || { bad "threads"; cat "$T/err"; }

# The table as HDF5 (-o *.h5): the CSV's cells, read with h5py as an independent reader (numbers as float64,
# text as UTF-8, /empty marking the empty cells of a number column); a re-run resumes from it.
ZWIDTH_NUM_THREADS=2 "$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/j1.h5" --jobs 1 "${FLAGS[@]}" 2>/dev/null
h5cmp() {
  $PY - "$1" "$2" <<'PY'
import csv, math, sys
try:
    import h5py
except ImportError:
    sys.exit(77)
rows = list(csv.DictReader(open(sys.argv[1], newline="")))
with h5py.File(sys.argv[2], "r") as f:
    cols = [c.decode() for c in f["columns"][:]]
    assert cols == list(rows[0].keys()), (cols, list(rows[0]))
    numeric = 0
    for c in cols:
        d = f["batch"][c]
        assert d.shape == (len(rows),), (c, d.shape)
        empty = f["empty"][c][:] if "empty" in f and c in f["empty"] else [0] * len(rows)
        for i, r in enumerate(rows):
            if d.dtype.kind == "f":
                want = r[c]
                if empty[i]:
                    assert want == "", (c, i, want)
                    continue
                got = float(d[i])
                assert got == float(want) or (math.isnan(got) and math.isnan(float(want))), (c, i, got, want)
            else:
                assert d[i].decode() == r[c], (c, i, d[i], r[c])
        numeric += d.dtype.kind == "f"
    assert numeric > 20 and f["batch"]["m"].dtype.kind == "f", numeric
print(f"{len(rows)} rows x {len(cols)} columns, {numeric} of them float64")
PY
}
msg=$(h5cmp "$T/j1.csv" "$T/j1.h5"); rc=$?
if [ $rc -eq 77 ]; then echo "skip the HDF5 table's h5py check: no h5py"; elif [ $rc -eq 0 ]; then ok "-o t.h5: the CSV table's cells read by h5py ($msg)"; else bad "HDF5 table: $msg"; fi
ZWIDTH_NUM_THREADS=2 "$ZW" batch "$T/u[1-3].csv" "$T/u4.h5" "$T/bad.csv" -o "$T/j1.h5" --jobs 1 "${FLAGS[@]}" 2>"$T/err"
msg=$(h5cmp "$T/j1.csv" "$T/j1.h5"); rc=$?
if ! grep -q "5 resumed, 0 computed" "$T/err"; then bad "HDF5 resume"; cat "$T/err"
elif [ $rc -eq 77 ]; then ok "a re-run resumes every unit from the HDF5 table (cells not compared: no h5py)"
elif [ $rc -eq 0 ]; then ok "a re-run resumes every unit from the HDF5 table, the same cells"
else bad "HDF5 resume: $msg"; fi
cp "$T/u4.h5" "$T/log_as_table.h5"
expect "-o an HDF5 file that is no batch table" "log_as_table.h5.*not a table zwidth batch wrote" "" -- "$ZW" batch "$T/u1.csv" -o "$T/log_as_table.h5" "${FLAGS[@]}"

# End-of-line specs: from u1's own K_CR^max at delay 2 and its std, a bound 6 std below passes, 6 above
# fails, at the value is marginal (P = 0.5); the corrupt log's verdict is error; a spec on no column: exit 2.
read v sd < <($PY -c "import csv,sys; r=next(r for r in csv.DictReader(open(sys.argv[1])) if r['serial']==sys.argv[2]); print(r['d2_K_cr_max'], r['d2_K_cr_max_std'])" "$T/j1.csv" "$T/u1.csv")
for want in pass fail marginal; do
  bound=$($PY -c "import sys; v,s=map(float,sys.argv[1:3]); print(repr({'pass': v-6*s, 'fail': v+6*s, 'marginal': v}['$want']))" "$v" "$sd")
  "$ZW" batch "$T/u1.csv" "$T/bad.csv" -o "$T/spec_$want.csv" --spec "d2_K_cr_max>=$bound" "${FLAGS[@]}" 2>/dev/null
  got=$($PY -c "import csv,sys; print(' '.join(r['verdict'] for r in csv.DictReader(open(sys.argv[1]))))" "$T/spec_$want.csv")
  [ "$got" = "$want error" ] && ok "--spec d2_K_cr_max>=$bound: $got" || bad "--spec $want: got '$got'"
done
expect "a spec on a delay not run" "d8_K_cr_max.*no column" "$T/spec_bad" -- "$ZW" batch "$T/u1.csv" -o "$T/spec_bad.csv" --spec "d8_K_cr_max>=1" "${FLAGS[@]}"

# 5. A manifest: serials, relative paths, a unit's own log flag (output-scale) equal to run with that flag.
mkdir -p "$T/line"; cp "$T/u1.csv" "$T/u3.csv" "$T/line/"
printf 'serial,path,output-scale\nSN-001,u1.csv,2\nSN-002,u3.csv,\nSN-003,missing.csv,\n' >"$T/line/units.csv"
mkdir "$T/folders"
"$ZW" batch --manifest "$T/line/units.csv" -o "$T/m.csv" --unit-folders "$T/folders" "${FLAGS[@]}" 2>"$T/err"; rc=$?
[ $rc -eq 4 ] && ok "manifest with a missing log: exit 4" || { bad "manifest exit $rc"; cat "$T/err"; }
"$ZW" run "$T/line/u1.csv" -o "$T/run_s2" --no-figures --output-scale 2 "${FLAGS[@]}" >/dev/null 2>&1
if msg=$(compare "$T/m.csv" SN-001 "$T/run_s2" 2>&1); then ok "manifest flag output-scale 2: $msg"; else bad "$msg"; fi
if msg=$(compare "$T/m.csv" SN-002 "$T/run_u3.csv" 2>&1); then ok "manifest row with the command's flags: $msg"; else bad "$msg"; fi
$PY - "$T/m.csv" <<'PY' && ok "the missing log is a row with its error" || bad "missing log row"
import csv, sys
r = {r["serial"]: r for r in csv.DictReader(open(sys.argv[1]))}["SN-003"]
assert r["status"] == "input_error" and "missing.csv" in r["error"], r
PY
# Equal to run's but for the provenance (its command and date are batch's; its inputs the same log);
# the friction looked at by both (none found here).
same_but_provenance() {
  $PY - "$1" "$2" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
pa, pb = a.pop("provenance"), b.pop("provenance")
assert (b.get("fit") or {}).get("friction", {}).get("status", "not detected") == "not detected", b["fit"]
assert a == b, "content differs"
assert pa["command"].startswith("zwidth batch") and pb["command"].startswith("zwidth run"), (pa["command"], pb["command"])
assert [i["sha256"] for i in pa["inputs"] if i["path"].endswith("u1.csv")] == \
       [i["sha256"] for i in pb["inputs"] if i["path"].endswith("u1.csv")] != [], (pa["inputs"], pb["inputs"])
# The unit's own log only: not the logs of the units read on other threads meanwhile.
import re
others = [i["path"] for i in pa["inputs"] if re.search(r"/u\d+\.csv$", i["path"]) and not i["path"].endswith("/u1.csv")]
assert not others, others
PY
}
same_but_provenance "$T/folders/SN-001/model.json" "$T/run_s2/model.json" && \
  same_but_provenance "$T/folders/SN-001/summary.json" "$T/run_s2/summary.json" && \
  [ ! -e "$T/folders/SN-003" ] && ok "--unit-folders: a unit's model.json and summary.json are run's (but for the provenance's command)" || { bad "unit folders"; diff "$T/folders/SN-001/summary.json" "$T/run_s2/summary.json" | head; }

# 6. User mistakes: exit 2, the file, line and column named, no table written.
printf 'serial,path,rat\nA,u1.csv,1000\n' >"$T/line/typo.csv"
expect "manifest column that is no log flag" "typo.csv line 2.*rat" "$T/typo_out" -- "$ZW" batch --manifest "$T/line/typo.csv" -o "$T/typo_out.csv"
printf 'serial,log\nA,u1.csv\n' >"$T/line/nopath.csv"
expect "manifest without a path column" "nopath.csv line 1.*'path'" "$T/nopath_out" -- "$ZW" batch --manifest "$T/line/nopath.csv" -o "$T/nopath_out.csv"
printf 'serial,path\nA,u1.csv\nA,u3.csv\n' >"$T/line/twice.csv"
expect "a serial given twice" "twice.csv line 3.*already on line 2" "$T/twice_out" -- "$ZW" batch --manifest "$T/line/twice.csv" -o "$T/twice_out.csv"
printf 'serial,path,rate\nA,u1.csv,nan\n' >"$T/line/nan.csv"
expect "a NaN rate in a manifest" "nan.csv line 2" "$T/nan_out" -- "$ZW" batch --manifest "$T/line/nan.csv" -o "$T/nan_out.csv"
expect "a glob matching nothing" "matches no file" "$T/glob_out" -- "$ZW" batch "$T/none*.csv" -o "$T/glob_out.csv"
expect "neither logs nor a manifest" "logs.*or --manifest" "$T/none_out" -- "$ZW" batch -o "$T/none_out.csv"
expect "the table over a log" "same file|input" "" -- "$ZW" batch "$T/u1.csv" -o "$T/u1.csv"
echo "batch_cli: $pass passed, $fail failed"
[ $fail -eq 0 ]
