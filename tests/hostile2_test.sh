#!/usr/bin/env bash
# Hostile round two (issue 30), from outside the process: every case builds its
# own input here (python3 with NumPy/SciPy/h5py for .mat and HDF5 files, the
# shell for the rest). Classes: (1) NaN, inf and empty values of numeric flags,
# file values checked like flags, bounds on delays, scenes, hands and filters,
# the same log twice; (2) MATLAB v5/v7/v7.3 and HDF5 files that are truncated,
# bombs, sparse, struct arrays, v4, LZF, locked, UTF-16 text; (3) temporary
# files under SIGPIPE and SIGXFSZ, full disk on stdout, modes kept; (5) control
# characters and non-UTF-8 names. Each refusal: exit 2, a message naming the
# problem, nothing written. Usage: hostile2_test.sh ZWIDTH SRC
set -u
ZW=$(realpath "$1"); SRC=$(realpath "$2")
source "$SRC/tests/cli_lib.sh"
"$ZW" simulate --model "$M" -o "$T/good.csv" --seconds 10 2>/dev/null
"$ZW" simulate --model "$M" -o "$T/good.h5" --seconds 10 2>/dev/null
"$ZW" estimate "$T/good.h5" -o "$T/frf.csv" 2>/dev/null
no_temps() { [ -z "$(find "$1" -name '*.tmp-*' 2>/dev/null | head -1)" ]; }

# ---- (1) numeric flags: NaN, inf, empty -> exit 2 naming the flag
expect period-nan "--period.*not a finite number" "$T/o1" -- "$ZW" boundary "$M" --period nan -o "$T/o1"
expect b-max-nan "--b-max.*not a finite" "$T/o2" -- "$ZW" boundary "$M" --b-max nan -o "$T/o2"
expect b-step-nan "--b-step.*not a finite" "$T/o3" -- "$ZW" boundary "$M" --b-step nan -o "$T/o3"
expect b-min-inf "--b-min.*not a finite" "$T/o4" -- "$ZW" boundary "$M" --b-min inf -o "$T/o4"
expect delays-empty "--delays.*empty" "$T/o5" -- "$ZW" boundary "$M" --delays "" -o "$T/o5"
expect vfilter-nan "--velocity-filter-hz.*not a finite" "$T/o7" -- "$ZW" boundary "$M" --velocity-filter-hz nan -o "$T/o7"
expect f-max-nan "--f-max.*not a finite" "$T/o8" -- "$ZW" filter-sweep "$M" --delay 2 --f-max nan -o "$T/o8"
expect area-nan "--area-b-max.*not a finite" "$T/o9" -- "$ZW" filter-sweep "$M" --delay 2 --measure area --area-b-max nan -o "$T/o9"
expect export-period-nan "--period.*not a finite" "$T/o10" -- "$ZW" export "$M" --format matlab --period nan -o "$T/o10"
expect relay-damping-nan "--damping.*not a finite" "$T/o11" -- "$ZW" relay "$M" --delay 2 --damping nan -o "$T/o11"
expect relay-seconds-inf "--seconds.*not a finite" "$T/o12" -- "$ZW" relay "$M" --delay 2 --damping 0 --seconds inf -o "$T/o12"
expect sim-rms-nan "--torque-rms.*not a finite" "$T/o13.csv" -- "$ZW" simulate --model "$M" --torque-rms nan -o "$T/o13.csv"
expect est-fmin-nan "--fmin.*not a finite" "$T/o14.csv" -- "$ZW" estimate "$T/good.csv" --fmin nan -o "$T/o14.csv"
expect est-scale-empty "--input-scale.*empty" "$T/o15.csv" -- "$ZW" estimate "$T/good.csv" --input-scale "" -o "$T/o15.csv"
expect fit-coh-nan "--min-coherence.*not a finite" "$T/o16.json" -- "$ZW" fit "$T/frf.csv" --min-coherence nan -o "$T/o16.json"
expect excite-rate-inf "--rate.*not a finite" "$T/o17.csv" -- "$ZW" excite --rate inf -o "$T/o17.csv"
expect run-rfilter-nan "--report-filter-hz.*not a finite" "$T/o18" -- "$ZW" run "$T/good.csv" --report-filter-hz nan -o "$T/o18"
expect compare-delays-empty "--delays.*empty" "" -- "$ZW" compare "$M" --delays ""
expect check-delay-empty "--delay.*empty" "" -- "$ZW" check "$M" --model "$M" --delay ""
# ---- values from files, as strictly as the flags
$PY - "$M" "$T" <<'PYEOF'
import json, sys
m = json.load(open(sys.argv[1])); T = sys.argv[2]
for name, v in [("rate", 1000), ("tiny", 1e-9), ("neg", -0.001)]:
    m2 = dict(m); m2["sample_period_s"] = v; json.dump(m2, open(f"{T}/period_{name}.json", "w"))
PYEOF
expect model-period-rate "sample_period_s.*1000.*for 1000 Hz write 0.001" "$T/o20" -- "$ZW" boundary "$T/period_rate.json" -o "$T/o20"
expect model-period-tiny "sample_period_s.*must lie in" "$T/o21" -- "$ZW" boundary "$T/period_tiny.json" -o "$T/o21"
expect model-period-neg "sample_period_s.*must lie in" "" -- "$ZW" check "$M" --model "$T/period_neg.json" --delay 2
# ---- bounds on user-given loops and values
expect delays-5000 "a loop delay must lie in \[0, 1000\]" "$T/o22" -- "$ZW" boundary "$M" --delays 5000 -o "$T/o22"
expect delay-5000-check "--delay = 5000" "" -- "$ZW" check "$M" --model "$M" --delay 5000
expect delay-relay "--delay = 2000" "$T/o23" -- "$ZW" relay "$M" --delay 2000 --damping 0 -o "$T/o23"
expect many-delays "more than the 64" "$T/o24" -- "$ZW" boundary "$M" --delays "$(seq -s, 1 65)" -o "$T/o24"
expect run-delays "delay must lie in" "$T/o25" -- "$ZW" run "$T/good.csv" --delays 1001 -o "$T/o25"
expect hand-huge "hand.*1e12" "$T/o26" -- "$ZW" boundary "$M" --hand 1e300,0,0 -o "$T/o26"
expect hand-huge-k "hand.*1e12" "$T/o6" -- "$ZW" boundary "$M" --hand 0,0,1e13 -o "$T/o6"
expect filter-empty "list is empty" "$T/o27" -- "$ZW" boundary "$M" --velocity-filter-coeffs "b:;a:" -o "$T/o27"
expect filter-empty-b "empty" "$T/o28" -- "$ZW" boundary "$M" --velocity-filter-coeffs "b: ;a:1" -o "$T/o28"
expect filter-overflow "exceeds 1e12" "$T/o29" -- "$ZW" boundary "$M" --velocity-filter-coeffs "b:1e300,1e300;a:1" -o "$T/o29"
$PY - "$T" <<'PYEOF'
import json, sys
T = sys.argv[1]
json.dump({"objects": [{"name": f"o{i}", "K": 1.0, "B": 0.001} for i in range(100001)]}, open(f"{T}/big_scene.json", "w"))
lines = open(f"{T}/frf.csv").read().splitlines()
h = lines[0].split(","); i = h.index("H_std"); j = h.index("coherence")
for name, col, val in [("std0", i, "0"), ("coh2", j, "2")]:
    rows = [lines[0]] + [",".join(val if k == col and r == 3 else x for k, x in enumerate(l.split(","))) for r, l in enumerate(lines[1:])]
    open(f"{T}/frf_{name}.csv", "w").write("\n".join(rows) + "\n")
PYEOF
expect scene-too-big "more than 100000 objects" "" -- "$ZW" check "$T/big_scene.json" --model "$M" --delay 2
expect frf-std0 "H_std = 0.*must be > 0" "$T/o30.json" -- "$ZW" fit "$T/frf_std0.csv" -o "$T/o30.json"
expect frf-coh2 "coherence = 2.*outside \[0, 1\]" "$T/o31.json" -- "$ZW" fit "$T/frf_coh2.csv" -o "$T/o31.json"
# ---- the same log twice: refused (averaging it shrinks every std by 1/sqrt(2))
cp "$T/good.csv" "$T/copy.csv"; ln "$T/good.csv" "$T/hard.csv"
expect same-log "same samples as" "$T/o32.csv" -- "$ZW" estimate "$T/good.csv" "$T/good.csv" -o "$T/o32.csv"
expect same-log-copy "copy.csv holds the same samples as" "$T/o33.csv" -- "$ZW" estimate "$T/good.csv" "$T/copy.csv" -o "$T/o33.csv"
expect same-log-link "same samples" "$T/o34.json" -- "$ZW" fit "$T/good.csv" "$T/hard.csv" -o "$T/o34.json"
expect same-log-formats "same samples" "$T/o35.csv" -- "$ZW" estimate "$T/good.h5" "$T/good.h5" -o "$T/o35.csv"
"$ZW" simulate --model "$M" -o "$T/other.csv" --seconds 10 --seed 7 2>/dev/null
if "$ZW" estimate "$T/good.csv" "$T/other.csv" -o "$T/two.csv" 2>/dev/null; then ok "two different runs still averaged"; else bad "two different runs refused"; fi

# ---- (2) MATLAB and HDF5 files
$PY - "$T" <<'PYEOF'
import sys, struct, zlib, numpy as np, scipy.io as sio, scipy.sparse as sp
T = sys.argv[1]
n = 5000; t = np.arange(n) / 1000.0
rng = np.random.default_rng(1); u = rng.standard_normal(n); y = np.cumsum(np.cumsum(u)) * 1e-6
good = {"t": t, "torque": u, "position": y}
sio.savemat(f"{T}/v5.mat", good, do_compression=False)
sio.savemat(f"{T}/v7.mat", good, do_compression=True)
for name in ["v5", "v7"]:
    b = open(f"{T}/{name}.mat", "rb").read(); open(f"{T}/{name}_cut.mat", "wb").write(b[:len(b) - 3000])
sio.savemat(f"{T}/sparse.mat", {"t": t, "torque": sp.csc_matrix(u.reshape(-1, 1)), "position": y})
s = np.empty((1, 2), dtype=[("torque", "O"), ("position", "O"), ("t", "O")])
for k in range(2): s[0, k] = (u, y, t)
sio.savemat(f"{T}/structarr.mat", {"s": s})
sio.savemat(f"{T}/v4.mat", good, format="4")
# A zlib bomb: a compressed variable whose header declares 3e8 doubles.
def small(tp, data):  # a sub-element, padded to 8
    pad = (8 - len(data) % 8) % 8
    return struct.pack("<II", tp, len(data)) + data + b"\0" * pad
N = 300_000_000
body = (small(6, struct.pack("<II", 6, 0)) + small(5, struct.pack("<ii", N, 1)) + small(1, b"torque")
        + struct.pack("<II", 9, N * 8) + b"\0" * 4096)
matrix = struct.pack("<II", 14, len(body) - 4096 + N * 8) + body
comp = zlib.compress(matrix, 9)
hdr = b"MATLAB 5.0 MAT-file, zwidth test".ljust(116, b" ") + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
open(f"{T}/bomb.mat", "wb").write(hdr + struct.pack("<II", 15, len(comp)) + comp)
open(f"{T}/utf16.csv", "w", encoding="utf-16").write("t,torque,position\n" + "".join(f"{a},{b},{c}\n" for a, b, c in zip(t, u, y)))
PYEOF
expect mat-v5-truncated "truncated" "$T/m1.csv" -- "$ZW" estimate "$T/v5_cut.mat" -o "$T/m1.csv"
expect mat-v7-truncated "truncated" "$T/m2.csv" -- "$ZW" estimate "$T/v7_cut.mat" -o "$T/m2.csv"
expect mat-sparse "sparse matrix" "$T/m3.csv" -- "$ZW" estimate "$T/sparse.mat" -o "$T/m3.csv"
expect mat-struct-array "array of 2 structs" "$T/m4.csv" -- "$ZW" estimate "$T/structarr.mat" --input-column s.torque --output-column s.position --time-column s.t -o "$T/m4.csv"
expect mat-v4 "MATLAB v4 file" "$T/m5.csv" -- "$ZW" estimate "$T/v4.mat" -o "$T/m5.csv"
start=$(date +%s%N)
expect mat-bomb "more than zlib can expand" "$T/m6.csv" -- "$ZW" estimate "$T/bomb.mat" -o "$T/m6.csv"
ms=$(( ($(date +%s%N) - start) / 1000000 )); [ $ms -lt 5000 ] && ok "bomb refused in $ms ms" || bad "bomb took $ms ms"
expect utf16 "UTF-16 text file.*iconv" "$T/m7.csv" -- "$ZW" estimate "$T/utf16.csv" -o "$T/m7.csv"
for f in v5 v7; do
  if "$ZW" estimate "$T/$f.mat" -o "$T/$f.frf.csv" --window-length 512 2>/dev/null; then ok "valid $f.mat still read"; else bad "valid $f.mat refused"; fi
done
if $PY -c "import h5py" 2>/dev/null; then
$PY - "$T" <<'PYEOF'
import sys, numpy as np, h5py, os
T = sys.argv[1]
n = 5000; t = np.arange(n) / 1000.0
rng = np.random.default_rng(2); u = rng.standard_normal(n); y = np.cumsum(np.cumsum(u)) * 1e-6
def mat73(name, build):
    p = f"{T}/{name}.mat"
    with h5py.File(p, "w", userblock_size=512) as f: build(f)
    hdr = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, zwidth test".ljust(116, b" ") + b"\0" * 8 + b"\x00\x02IM"
    with open(p, "r+b") as f: f.write(hdr + b"\0" * (512 - len(hdr)))
def plain(f):
    f["t"] = t.reshape(1, -1); f["torque"] = u.reshape(1, -1); f["position"] = y.reshape(1, -1)
mat73("v73", plain)
with h5py.File(f"{T}/other.h5", "w") as g: g["position"] = y
def extlink(f):
    f["t"] = t; f["torque"] = u; f["position"] = h5py.ExternalLink(f"{T}/other.h5", "/position")
mat73("v73_extlink", extlink)
np.asarray(y, dtype="<f8").tofile(f"{T}/raw.bin")
def extstore(f):
    f["t"] = t; f["torque"] = u; f.create_dataset("position", shape=(n,), dtype="<f8", external=[(f"{T}/raw.bin", 0, n * 8)])
mat73("v73_extstore", extstore)
def huge(f):
    for name in ["t", "torque", "position"]:
        f.create_dataset(name, shape=(300_000_000,), dtype="<f8", chunks=(65536,))
mat73("v73_huge", huge)
with h5py.File(f"{T}/lzf.h5", "w") as f:
    f["time"] = t; f.create_dataset("input/torque", data=u, compression="lzf"); f["output/position"] = y
PYEOF
  if "$ZW" estimate "$T/v73.mat" -o "$T/v73.frf.csv" --window-length 512 2>/dev/null; then ok "valid v7.3 .mat read"; else bad "valid v7.3 .mat refused"; "$ZW" estimate "$T/v73.mat" -o "$T/v73.frf.csv" --window-length 512; fi
  expect v73-extlink "external link" "$T/h1.csv" -- "$ZW" estimate "$T/v73_extlink.mat" -o "$T/h1.csv"
  expect v73-extstore "external files" "$T/h2.csv" -- "$ZW" estimate "$T/v73_extstore.mat" -o "$T/h2.csv"
  expect v73-huge "declares 300000000 samples" "$T/h3.csv" -- "$ZW" estimate "$T/v73_huge.mat" -o "$T/h3.csv"
  expect hdf5-lzf "LZF" "$T/h4.csv" -- "$ZW" estimate "$T/lzf.h5" -o "$T/h4.csv"
  # A writer's lock (HDF5 takes flock(LOCK_EX) on a file open for writing).
  $PY -c "import fcntl,sys,time; f=open(sys.argv[1],'rb'); fcntl.flock(f, fcntl.LOCK_EX); open(sys.argv[2],'w').close(); time.sleep(30)" "$T/good.h5" "$T/locked" &
  lp=$!; for _ in $(seq 50); do [ -f "$T/locked" ] && break; sleep 0.1; done
  expect hdf5-locked "another program has it open for writing" "$T/h5.csv" -- "$ZW" estimate "$T/good.h5" -o "$T/h5.csv"
  kill $lp; wait $lp 2>/dev/null
else
  echo "skip: h5py not importable (the v7.3 and LZF cases)"
fi

# ---- (3) temporary files: SIGPIPE, SIGXFSZ; full disk on stdout; modes
mkdir -p "$T/tmpdir"
TMPDIR="$T/tmpdir" "$ZW" boundary "$M" --b-points 20000 -o - 2>/dev/null | head -c 100 >/dev/null
[ -z "$(ls -A "$T/tmpdir")" ] && ok "-o - | head leaves nothing in TMPDIR" || { bad "-o - | head left $(ls "$T/tmpdir")"; rm -f "$T/tmpdir"/*; }
mkdir -p "$T/fsz"
( ulimit -f 8; "$ZW" boundary "$M" --b-points 20000 -o "$T/fsz/b.csv" 2>/dev/null ); rc=$?
[ $rc -ne 0 ] && no_temps "$T/fsz" && [ ! -e "$T/fsz/b.csv" ] && ok "SIGXFSZ: exit $rc, no temporary" || bad "SIGXFSZ: exit $rc, left $(ls -A "$T/fsz")"
printf '{"objects":[{"name":"a","K":1,"B":0.001}]}' > "$T/scene.json"
for c in "check $T/scene.json --model $M --delay 2 --json" "check $T/scene.json --model $M --delay 2" \
         "relay $M --delay 2 --damping 0 --seconds 2 --json" "compare $M --reference table1" "boundary $M -o -"; do
  "$ZW" $c >/dev/full 2>"$T/stderr"; rc=$?
  { [ $rc -eq 1 ] || [ $rc -eq 2 ]; } && grep -q "standard output" "$T/stderr" && ok "> /dev/full: ${c%% *} exits $rc" || bad "> /dev/full: ${c%% *} exits $rc"
done
printf '{"objects":[{"name":"a","K":1e9,"B":0.001}]}' > "$T/unstable.json"
"$ZW" check "$T/unstable.json" --model "$M" --delay 2 >/dev/null 2>&1; rc=$?
[ $rc -eq 3 ] && ok "check: an unstable object still exits 3" || bad "check unstable: exit $rc"
echo old > "$T/mode.csv"; chmod 600 "$T/mode.csv"
"$ZW" boundary "$M" --b-points 20 -o "$T/mode.csv" 2>/dev/null
[ "$(stat -c %a "$T/mode.csv")" = 600 ] && ok "overwriting a 0600 file keeps 0600" || bad "mode became $(stat -c %a "$T/mode.csv")"

# ---- (5) control characters and non-UTF-8 names
$PY - "$T" <<'PYEOF'
import json, sys
json.dump({"objects": [{"name": "evil\nforged: stable\u001b[2J\u001b[31m", "K": 1.0, "B": 0.001}, {"name": "b\r", "K": 2.0, "B": 0.001}]},
          open(f"{sys.argv[1]}/ansi.json", "w"))
PYEOF
"$ZW" check "$T/ansi.json" --model "$M" --delay 2 >"$T/ansi.out" 2>&1  # a delay line, then one line per object
if grep -q $'\e' "$T/ansi.out" || grep -q $'\r' "$T/ansi.out" || [ "$(wc -l < "$T/ansi.out")" -ne 3 ]; then
  bad "scene names reach the terminal raw"; cat -A "$T/ansi.out"
else ok "scene names shown escaped: $(head -1 "$T/ansi.out" | cut -c1-60)"; fi
"$ZW" boundary "$T/x"$'\e[31m'"y.json" -o "$T/o40" 2>"$T/stderr"
! grep -q $'\e' "$T/stderr" && grep -q '\\x1b' "$T/stderr" && ok "an ESC in a file name is shown as \\x1b" || bad "ESC in a file name printed raw"
L1="$T/log_"$'\xe9'".csv"; cp "$T/good.csv" "$L1"
if "$ZW" fit "$L1" --modes 2 -o "$T/latin1.json" >/dev/null 2>"$T/stderr" && $PY -c "import json,sys; json.load(open(sys.argv[1]))" "$T/latin1.json"; then
  ok "fit of a Latin-1 file name: $(grep -o '"source": "[^"]*"' "$T/latin1.json")"
else bad "fit of a Latin-1 file name"; tail -2 "$T/stderr"; fi
if "$ZW" run "$L1" --no-figures --modes 2 --delays 2 -o "$T/latin1_run" >/dev/null 2>"$T/stderr" &&
   $PY -c "import json,sys; json.load(open(sys.argv[1]))" "$T/latin1_run/summary.json"; then
  ok "run of a Latin-1 file name"
else bad "run of a Latin-1 file name"; tail -2 "$T/stderr"; fi
no_temps "$T" && ok "no temporary left anywhere" || bad "temporaries left: $(find "$T" -name '*.tmp-*' | head -3)"
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
