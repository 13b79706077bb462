#!/usr/bin/env bash
# Hostile inputs and output paths (issue 11), written by this script in a
# temporary folder: devices (mknod), FIFOs, folders, symlinks and hard links as
# outputs; an output that is an input; `run` into non-empty and concurrent
# folders and folder names holding a quote and $(...); SIGINT/SIGTERM while
# writing; a full disk (a 64 KiB tmpfs, as root only); FIFOs and /dev/zero as
# inputs; HDF5 array attributes, external storage and external links; a
# frequency-response CSV with a duplicated column; JSON nested 100000 deep; caps
# on delays, modes and samples; inputs that overflow to non-finite values.
# Each case: exit 2, a message naming what and where, no damage, and no
# *.tmp-* file or folder left. Usage: hostile_test.sh ZWIDTH SRC
set -u
ZW=$(realpath "$1"); SRC=$(realpath "$2")
PY=/usr/bin/python3
T=$(mktemp -d); trap 'umount "$T/full" 2>/dev/null; rm -rf "$T"' EXIT
pass=0; fail=0; skipped=0
M=$SRC/datasets/phantom/table1.json
"$ZW" simulate --model "$M" -o "$T/good.csv" --seconds 10 2>/dev/null
"$ZW" simulate --model "$M" -o "$T/good.h5" --seconds 10 2>/dev/null
"$ZW" estimate "$T/good.h5" -o "$T/frf.csv" 2>/dev/null
"$ZW" estimate "$T/good.h5" -o "$T/frf.h5" 2>/dev/null
cp "$M" "$T/model.json"

ok() { echo "ok   $1"; pass=$((pass+1)); }
bad() { echo "FAIL $1"; [ -f "$T/stderr" ] && head -c 400 "$T/stderr"; fail=$((fail+1)); }
leftovers() { find "$T" -name '*.tmp-*' 2>/dev/null | head -5; }

# expect NAME PATTERN -- command...: exit 2, stderr matches, no temporary left.
expect() {
  local name=$1 pattern=$2; shift 3
  timeout 60 "$@" >"$T/stdout" 2>"$T/stderr"; local rc=$?
  if [ $rc -ne 2 ]; then bad "$name: exit $rc, expected 2"; return 1; fi
  if ! grep -qiE -e "$pattern" "$T/stderr"; then bad "$name: stderr lacks /$pattern/"; return 1; fi
  if [ -n "$(leftovers)" ]; then bad "$name: left $(leftovers)"; return 1; fi
  ok "$name: $(head -c 140 "$T/stderr" | tr '\n' ' ')"
}
# check NAME CONDITION: one more assertion after a case.
check() { if eval "$2"; then ok "$1"; else bad "$1"; fi; }

# ---- 1. outputs only to regular files
expect out-dev-null "/dev/null' is a character device, not a regular file" -- "$ZW" estimate "$T/good.csv" -o /dev/null
check dev-null-intact '[ -c /dev/null ]'
expect out-dev-full "/dev/full' is a character device" -- "$ZW" fit "$T/frf.csv" -o /dev/full
check dev-full-intact '[ -c /dev/full ]'
expect excite-out-dev-null "/dev/null' is a character device" -- "$ZW" excite -o /dev/null
expect filter-sweep-out-dev-null "/dev/null' is a character device" -- "$ZW" filter-sweep "$M" --delay 2 --points 3 -o /dev/null
expect relay-out-dev-null "/dev/null' is a character device" -- "$ZW" relay "$M" --delay 2 --damping 0 -o /dev/null
expect coherences-out-dev-null "/dev/null' is a character device" -- "$ZW" estimate "$T/good.csv" -o "$T/coh_frf.csv" --coherences-output /dev/null
check coherences-dev-null-nothing '[ ! -e "$T/coh_frf.csv" ] && [ -c /dev/null ]'
if mknod "$T/chardev" c 1 3 2>/dev/null; then
  expect out-mknod-chardev "chardev' is a character device" -- "$ZW" simulate --model "$M" -o "$T/chardev" --seconds 1
  check mknod-intact '[ -c "$T/chardev" ]'
  ln -s "$T/chardev" "$T/link_to_chardev"
  expect out-symlink-to-chardev "link_to_chardev' is a symbolic link to a character device" -- "$ZW" export "$M" --format json -o "$T/link_to_chardev"
  check symlink-intact '[ -L "$T/link_to_chardev" ] && [ -c "$T/chardev" ]'
else
  echo "skip mknod cases (not root)"; skipped=$((skipped+1))
fi
mkfifo "$T/fifo"
expect out-fifo "fifo' is a FIFO" -- "$ZW" estimate "$T/good.csv" -o "$T/fifo"
check fifo-intact '[ -p "$T/fifo" ]'
ln -s "$T/fifo" "$T/link_to_fifo"
expect out-symlink-to-fifo "symbolic link to a FIFO" -- "$ZW" boundary "$M" -o "$T/link_to_fifo"
mkdir "$T/adir"
expect out-directory "adir' is a folder" -- "$ZW" estimate "$T/good.csv" -o "$T/adir"
expect out-stdout-pipe "/dev/stdout' is a symbolic link to a FIFO|/dev/stdout' is a FIFO" -- bash -o pipefail -c "'$ZW' estimate '$T/good.csv' -o /dev/stdout | cat"
# input == output, by name, through a hard link and a symlink
sum0=$(md5sum < "$T/good.csv")
expect out-is-input "output '.*good.csv' is the input" -- "$ZW" estimate "$T/good.csv" -o "$T/good.csv"
ln "$T/good.csv" "$T/hardlink.csv"
expect out-is-input-hardlink "hardlink.csv' is the input" -- "$ZW" estimate "$T/good.csv" -o "$T/hardlink.csv"
ln -s "$T/good.csv" "$T/symlink.csv"
expect out-is-input-symlink "symlink.csv' is the input" -- "$ZW" estimate "$T/good.csv" -o "$T/symlink.csv"
check input-intact '[ "$(md5sum < "$T/good.csv")" = "$sum0" ]'
expect fit-out-is-input "is the input" -- "$ZW" fit "$T/frf.csv" -o "$T/frf.csv"
expect simulate-out-is-model "is the input" -- "$ZW" simulate --model "$T/model.json" -o "$T/model.json" --seconds 1
expect export-out-is-model "is the input" -- "$ZW" export "$T/model.json" --format matlab -o "$T/model.json"
expect boundary-out-is-model "is the input" -- "$ZW" boundary "$T/model.json" -o "$T/model.json"
# Refused before any work: a later bad flag (--points 1, --b-points 1) is not
# reached, and relay does not start simulating.
expect filter-sweep-out-is-model "is the input" -- "$ZW" filter-sweep "$T/model.json" --delay 2 --points 1 -o "$T/model.json"
expect relay-out-is-model "is the input" -- "$ZW" relay "$T/model.json" --delay 2 --damping 0 --seconds 1 -o "$T/model.json"
check relay-refused-before-simulating '! grep -q simulating "$T/stderr"'
echo "b:1;a:1" > "$T/filter.txt"
expect boundary-out-is-filter-file "filter.txt' is the input" -- "$ZW" boundary "$T/model.json" --velocity-filter-coeffs "$T/filter.txt" --b-points 1 -o "$T/filter.txt"
check filter-file-intact '[ "$(cat "$T/filter.txt")" = "b:1;a:1" ]'
expect coherences-output-is-output "also -o" -- "$ZW" estimate "$T/good.csv" -o "$T/same.csv" --coherences-output "$T/same.csv"
check model-intact 'cmp -s "$M" "$T/model.json"'
# "-": standard output; a symlink to a regular file is followed (the link stays)
"$ZW" estimate "$T/good.csv" -o - > "$T/frf_stdout.csv" 2>/dev/null
check dash-is-stdout 'head -c 4 "$T/frf_stdout.csv" | grep -q f_hz && cmp -s "$T/frf_stdout.csv" "$T/frf.csv"'
: > "$T/target.csv"; ln -s "$T/target.csv" "$T/link_to_target.csv"
"$ZW" estimate "$T/good.csv" -o "$T/link_to_target.csv" 2>/dev/null
check symlink-to-regular-followed '[ -L "$T/link_to_target.csv" ] && cmp -s "$T/target.csv" "$T/frf.csv"'

# ---- run: new, empty or --force folders; built aside and renamed
mkdir "$T/full_dir"; echo "keep me" > "$T/full_dir/notes.txt"
expect run-nonempty "full_dir' is not empty" -- "$ZW" run "$T/good.csv" -o "$T/full_dir"
check run-nonempty-intact '[ "$(ls "$T/full_dir")" = notes.txt ] && grep -q "keep me" "$T/full_dir/notes.txt"'
"$ZW" run "$T/good.csv" -o "$T/full_dir" --force >/dev/null 2>&1
check run-force-keeps-others '[ -f "$T/full_dir/model.json" ] && grep -q "keep me" "$T/full_dir/notes.txt" && [ -z "$(ls -a "$T" | grep tmp-)" ]'
expect run-bad-log-leaves-nothing "cannot open log" -- "$ZW" run "$T/absent.csv" -o "$T/run_fail"
check run-fail-no-folder '[ ! -e "$T/run_fail" ] && [ -z "$(ls -a "$T" | grep run_fail)" ]'
# The cap is on B values x delays (stability::kMaxBGridValues, 1e6): 2.6e11 x 3 here.
expect run-grid-cap "B grid would have .* values x 3 delays, over the cap of 1000000" -- "$ZW" run "$T/good.csv" -o "$T/run_grid" --b-step 1e-12
check run-grid-no-folder '[ ! -e "$T/run_grid" ]'
# A folder name holding a quote and $(...): nothing executed, figures drawn.
evil="$T/it's \$(touch pwned) \`touch pwned2\`; touch pwned3 '"
(cd "$T" && "$ZW" run good.csv -o "$evil" >/dev/null 2>"$T/stderr"); rc=$?
check run-evil-name-no-injection "[ $rc -eq 0 ] && [ -z \"\$(find '$T' -name 'pwned*' | head -1)\" ] && [ -f \"\$evil/report.html\" ]"
if command -v gnuplot >/dev/null; then
  check run-evil-name-figures '[ -s "$evil/figures/bode.svg" ] && [ -z "$(ls "$evil/figures" | grep png)" ]'
  # --png: the six figures as PNG as well (and never with --no-figures).
  "$ZW" run "$T/good.csv" -o "$T/run_png" --png >/dev/null 2>&1
  check run-png '[ "$(ls "$T/run_png/figures" | grep -c "\.png$")" = 6 ] && head -c 8 "$T/run_png/figures/bode.png" | grep -q PNG'
  expect run-png-no-figures "excludes" -- "$ZW" run "$T/good.csv" -o "$T/run_png2" --png --no-figures
fi
mkdir "$T/empty_dir"
"$ZW" run "$T/good.csv" -o "$T/empty_dir" >/dev/null 2>"$T/stderr"; rc=$?
check "run-empty-folder (exit $rc)" '[ $rc -eq 0 ] && [ -f "$T/empty_dir/report.html" ] && [ -z "$(ls -a "$T" | grep empty_dir.tmp-)" ]'
# Two runs into one new folder at once: one wins whole, the other fails.
"$ZW" simulate --model "$M" -o "$T/other.csv" --seconds 10 --seed 7 2>/dev/null
"$ZW" run "$T/good.csv" -o "$T/race" >/dev/null 2>"$T/race1.err" & p1=$!
"$ZW" run "$T/other.csv" -o "$T/race" >/dev/null 2>"$T/race2.err" & p2=$!
wait $p1; r1=$?; wait $p2; r2=$?
winner=""; [ $r1 -eq 0 ] && winner=good.csv; [ $r2 -eq 0 ] && winner=other.csv
cat "$T/race1.err" "$T/race2.err" | grep -i error > "$T/stderr"
check "run-concurrent-no-mix (exits $r1 $r2)" "[ \$((r1 + r2)) -eq 2 ] && grep -q '\"log\": \".*$winner\"' '$T/race/summary.json' && grep -q 'filled by another process\|is not empty' '$T/race1.err' '$T/race2.err' && [ -z \"\$(leftovers)\" ]"

# ---- 3. signals remove temporary files; a full disk fails the write
# Started through python to undo the SIG_IGN for SIGINT that a background job inherits.
nosigign() { exec $PY -c "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); os.execv(sys.argv[1], sys.argv[1:])" "$@"; }
for sig in TERM INT; do
  nosigign "$ZW" simulate --model "$M" -o "$T/big_$sig.csv" --seconds 3000 2>/dev/null & pid=$!
  for _ in $(seq 1 600); do [ -n "$(ls "$T" | grep "big_$sig.csv.tmp-")" ] && break; sleep 0.05; done
  kill -$sig $pid; wait $pid; rc=$?
  check "sig$sig-removes-temp (exit $rc)" "[ $rc -gt 128 ] && [ -z \"\$(leftovers)\" ] && [ ! -e '$T/big_$sig.csv' ]"
done
"$ZW" run "$T/good.csv" -o "$T/run_sig" >/dev/null 2>&1 & pid=$!
for _ in $(seq 1 600); do [ -n "$(ls -a "$T" | grep "run_sig.tmp-")" ] && break; sleep 0.02; done
kill -TERM $pid; wait $pid
check sigTERM-run-removes-folder '[ ! -e "$T/run_sig" ] && [ -z "$(ls -a "$T" | grep run_sig)" ]'
mkdir "$T/full"
if [ "$(id -u)" = 0 ] && mount -t tmpfs -o size=64k tmpfs "$T/full" 2>/dev/null; then
  expect full-disk-frf-h5 "(disk full|No space|cannot write)" -- "$ZW" estimate "$T/good.h5" -o "$T/full/frf.h5"
  check full-disk-nothing-left '[ -z "$(ls -A "$T/full")" ]'
  expect full-disk-frf-csv "(disk full|No space|failed writing)" -- "$ZW" estimate "$T/good.h5" -o "$T/full/frf.csv"
  expect full-disk-log-h5 "(disk full|No space|cannot write)" -- "$ZW" simulate --model "$M" -o "$T/full/log.h5" --seconds 10
  expect full-disk-log-csv "(disk full|No space|failed writing)" -- "$ZW" simulate --model "$M" -o "$T/full/log.csv" --seconds 10
  check full-disk-nothing-left-2 '[ -z "$(ls -A "$T/full")" ]'
  head -c $((60 * 1024)) /dev/zero > "$T/full/filler" 2>/dev/null  # room for HDF5's first writes only
  expect full-disk-export-h5 "(disk full|No space|cannot write|could not close)" -- "$ZW" export "$M" --format hdf5 --period 0.001 -o "$T/full/m.h5"
  check full-disk-export-nothing-left '[ "$(ls -A "$T/full")" = filler ]'
  rm -f "$T/full/filler"
  umount "$T/full"
else
  echo "skip full-disk cases (needs root and tmpfs)"; skipped=$((skipped+1))
fi

# ---- 4. inputs: regular files only, shapes, caps, no external data
mkfifo "$T/good_fifo.csv"
expect in-fifo-log "good_fifo.csv: the log is a FIFO" -- "$ZW" estimate "$T/good_fifo.csv" -o "$T/x1.csv"
expect in-dev-zero-log "/dev/zero: the log is a character device" -- "$ZW" estimate /dev/zero -o "$T/x2.csv"
expect in-dev-zero-model "/dev/zero: the model file is a character device" -- "$ZW" boundary /dev/zero -o "$T/x3.csv"
expect in-fifo-model "the model file is a FIFO" -- "$ZW" export "$T/good_fifo.csv" -o "$T/x4.json"
expect in-fifo-fit "is a FIFO" -- "$ZW" fit "$T/good_fifo.csv" -o "$T/x5.json"
expect in-dir-log "the log is a folder" -- "$ZW" estimate "$T/adir" -o "$T/x6.csv"
expect in-dev-zero-filter "/dev/zero: the velocity filter file is a character device" -- "$ZW" boundary "$M" --velocity-filter-coeffs /dev/zero -o "$T/x28.csv"
expect in-fifo-filter "the velocity filter file is a FIFO" -- "$ZW" boundary "$M" --velocity-filter-coeffs "$T/good_fifo.csv" -o "$T/x29.csv"
expect in-fifo-scene "scene file is a FIFO" -- "$ZW" check "$T/good_fifo.csv" --model "$M" --delay 2
# The old reader mapped names to positions (H_re -> 8) but counted distinct
# names (3), so rows of 3 fields passed and were read at index 8: past the row.
{ echo "f_hz,H_re,H_im,H_re,H_re,H_re,H_re,H_re,H_re"; for i in $(seq 1 50); do echo "$i,1,2"; done; } > "$T/dup.csv"
expect frf-csv-duplicate-column "line 1: column 'H_re' appears twice" -- "$ZW" fit "$T/dup.csv" --rate 1000 -o "$T/x7.json"
awk -F, 'NR==5{$0=$0",9"}1' "$T/frf.csv" > "$T/extra.csv"
expect frf-csv-extra-field "line 5 has 14 fields, the header has 13" -- "$ZW" fit "$T/extra.csv" -o "$T/x8.json"
$PY - "$T" <<'PY'
import sys, shutil, h5py, numpy as np
t = sys.argv[1]
def log(name):
    f = h5py.File(f"{t}/{name}", "w")
    rng = np.random.default_rng(1)
    f["/input/torque"] = rng.standard_normal(20000)
    f["/output/position"] = rng.standard_normal(20000)
    return f
with log("attr_array.h5") as f:
    f.attrs["sample_rate_hz"] = np.array([1000.0, 2000.0])
with log("attr_string.h5") as f:
    f.attrs["sample_rate_hz"] = "fast"
shutil.copy(f"{t}/frf.h5", f"{t}/frf_attr_array.h5")
with h5py.File(f"{t}/frf_attr_array.h5", "a") as f:
    del f.attrs["bin_correlation"]
    f.attrs["bin_correlation"] = np.ones(40)
open(f"{t}/raw.bin", "wb").write(np.random.default_rng(2).standard_normal(20000).tobytes())
with h5py.File(f"{t}/external_storage.h5", "w") as f:
    f.attrs["sample_rate_hz"] = 1000.0
    f.create_dataset("/input/torque", shape=(20000,), dtype="<f8", external=[(f"{t}/raw.bin", 0, 160000)])
    f["/output/position"] = np.zeros(20000)
with h5py.File(f"{t}/external_zero.h5", "w") as f:
    f.attrs["sample_rate_hz"] = 1000.0
    f.create_dataset("/input/torque", shape=(10**8,), dtype="<f8", external=[("/dev/zero", 0, h5py.h5f.UNLIMITED)])
    f["/output/position"] = np.zeros(10)
with h5py.File(f"{t}/target.h5", "w") as f:
    f["/data"] = np.random.default_rng(3).standard_normal(20000)
with log("external_link.h5") as f:
    f.attrs["sample_rate_hz"] = 1000.0
    del f["/input/torque"]
    f["/input/torque"] = h5py.ExternalLink(f"{t}/target.h5", "/data")
with h5py.File(f"{t}/external_group.h5", "w") as f:
    f.attrs["sample_rate_hz"] = 1000.0
    f["/input"] = h5py.ExternalLink(f"{t}/good.h5", "/input")
    f["/output/position"] = np.zeros(10000)
PY
expect h5-attr-array "attribute sample_rate_hz has 2 values; it must be one number" -- "$ZW" estimate "$T/attr_array.h5" -o "$T/x9.csv"
expect h5-attr-string "attribute sample_rate_hz is not a number" -- "$ZW" estimate "$T/attr_string.h5" -o "$T/x10.csv"
expect frf-h5-attr-array "attribute bin_correlation has 40 values" -- "$ZW" fit "$T/frf_attr_array.h5" -o "$T/x11.json"
expect h5-external-storage "torque: its data are stored in external files" -- "$ZW" estimate "$T/external_storage.h5" -o "$T/x12.csv"
expect h5-external-dev-zero "torque: its data are stored in external files|more than zwidth reads" -- "$ZW" estimate "$T/external_zero.h5" -o "$T/x13.csv"
expect h5-external-link "/input/torque: is an external link" -- "$ZW" estimate "$T/external_link.h5" -o "$T/x14.csv"
expect h5-external-link-group "external_group.h5:/input: is an external link" -- "$ZW" estimate "$T/external_group.h5" -o "$T/x15.csv"
expect h5-odd-float-layout "f_hz: not stored as plain numbers" -- "$ZW" fit "$SRC/tests/fuzz/hdf5_frf/odd_float_layout_oom.h5" -o "$T/x27.json"
deep() { $PY -c "import sys; n=int(sys.argv[1]); sys.stdout.write(sys.argv[2] + '['*n + ']'*n + sys.argv[3])" "$@"; }
deep 100000 "" "" > "$T/deep.json"
expect json-deep-model "nested deeper than 64 levels" -- "$ZW" boundary "$T/deep.json" -o "$T/x16.csv"
deep 100000 '{"objects": ' '}' > "$T/deep_scene.json"
expect json-deep-scene "nested deeper than 64 levels" -- "$ZW" check "$T/deep_scene.json" --model "$M" --delay 2
sed 's/"m":/"fit": '"$(deep 1000 '' '')"', "m":/' "$M" > "$T/deep_fit.json"
expect json-deep-fit-key "nested deeper than 64 levels" -- "$ZW" export "$T/deep_fit.json" -o "$T/x17.json"
$PY -c "import json; m=json.load(open('$M')); m['delay_samples']=4294967298; json.dump(m, open('$T/delay_wrap.json','w'))"
expect delay-4294967298 "delay_samples' = 4294967298 is outside \[0, 1000\]" -- "$ZW" boundary "$T/delay_wrap.json" -o "$T/x18.csv"
$PY -c "import json; m=json.load(open('$M')); m['delay_samples']=2147483647; json.dump(m, open('$T/delay_max.json','w'))"
expect delay-int-max "delay_samples' = 2147483647 is outside" -- "$ZW" boundary "$T/delay_max.json" -o "$T/x19.csv"
$PY -c "import json; m=json.load(open('$M')); m['delay_samples']=-3; json.dump(m, open('$T/delay_neg.json','w'))"
expect delay-negative "delay_samples' = -3 is outside" -- "$ZW" boundary "$T/delay_neg.json" -o "$T/x20.csv"
$PY -c "
import json,sys; m=json.load(open('$M')); m['modes']=m['modes']*33; json.dump(m, open('$T/many_modes.json','w'))"
expect modes-cap "has 66 entries, more than 64" -- "$ZW" boundary "$T/many_modes.json" -o "$T/x21.csv"
expect simulate-delay-cap "--delay-samples 2147483647 is more than 1000" -- "$ZW" simulate --model "$M" --delay-samples 2147483647 -o "$T/x26.csv"
expect simulate-sample-cap "more than simulate writes \(4e7\)" -- "$ZW" simulate --model "$M" --seconds 1e6 -o "$T/x22.csv"

# ---- 5. non-finite results are errors, with the stage named
awk -F, 'NR>1{$3=$3*1e306}1' OFS=, "$T/good.csv" > "$T/huge_output.csv"
expect nonfinite-frf "huge_output.csv: the frequency response has non-finite values.*input scaled out of range" -- "$ZW" estimate "$T/huge_output.csv" -o "$T/x23.csv"
expect nonfinite-frf-run "the frequency response has non-finite values" -- "$ZW" run "$T/huge_output.csv" -o "$T/x24"
check nonfinite-run-no-folder '[ ! -e "$T/x24" ]'
sed 's/"m": 1.168e-3/"m": 1e-300/' "$M" > "$T/tiny_m.json"
echo '{"objects":[{"name":"wall","K":1e12,"B":0}]}' > "$T/scene.json"
expect model-implausible-m "key 'm' = 1e-300 is outside the plausible range" -- "$ZW" check "$T/scene.json" --model "$T/tiny_m.json" --delay 2
sed 's/"omega": 479.166/"omega": 1e300/' "$M" > "$T/huge_omega.json"
expect model-implausible-omega "modes\[0\].omega' = 1e\+300 is outside the plausible range" -- "$ZW" boundary "$T/huge_omega.json" -o "$T/x25.csv"

echo "$pass passed, $fail failed, $skipped groups skipped"
[ $fail -eq 0 ]
