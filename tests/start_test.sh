#!/usr/bin/env bash
# Process start: which shared libraries each command maps (apps/plugins.cc).
# Usage: start_test.sh ZWIDTH SOURCE_DIR
#  - the commands that read no HDF5/MATLAB file and fit nothing (--help,
#    --version, boundary, relay, check, compare on JSON models, export to
#    JSON) load neither libhdf5, libmatio, Ceres nor a plugin (LD_DEBUG=files,
#    the dynamic loader's own record of every file it maps);
#  - estimate on an .h5 log loads zwidth-hdf5.so (and libhdf5) but not Ceres
#    (Debian links Ceres statically: it is inside zwidth-fit.so, with glog,
#    cholmod, LAPACK... as shared libraries);
#    fit on a CSV response loads zwidth-fit.so (and Ceres) but not libhdf5;
#  - the plugins are found next to the executable's real path (through a
#    symbolic link too), and a missing, corrupt or foreign plugin is an error
#    naming the file that says to reinstall (exit 1), not a crash; commands
#    that need no plugin still work without them.
set -euo pipefail
ZW=$(readlink -f "$1"); SRC=$(cd "$2" && pwd)
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
M=$SRC/datasets/phantom/table1.json
LOG=$SRC/datasets/phantom/phantom_30s.h5
echo '{"objects": [{"name": "wall", "K": 1.0, "B": 0.01}]}' >"$T/scene.json"
HEAVY='lib(hdf5|matio|ceres|glog|cholmod|curl|gfortran)[^/]*\.so|zwidth-(hdf5|fit)\.so'

# The files a command maps: LD_DEBUG=files writes "file=NAME [0];  generating link map".
mapped() { LD_DEBUG=files "$@" 2>&1 >/dev/null | sed -n 's/.*file=\([^ ]*\) .*generating link map.*/\1/p' | sort -u; }

light() {  # light NAME -- command...: runs it, then checks that it mapped nothing heavy
  local name=$1; shift 2
  local rc=0; "$@" >"$T/out.txt" 2>&1 || rc=$?
  [ "$rc" = 0 ] || { cat "$T/out.txt"; fail "$name: exit $rc"; }
  local heavy; heavy=$(mapped "$@" | grep -E "$HEAVY" || true)
  [ -z "$heavy" ] || fail "$name loaded $(echo $heavy)"
  echo "ok: $name maps $(mapped "$@" | wc -l) shared objects, none of HDF5/matio/Ceres"
}
light help -- "$ZW" --help
light version -- "$ZW" --version
light boundary -- "$ZW" boundary "$M" --delays 2 --b-points 20 -o "$T/b.csv"
light relay -- "$ZW" relay "$M" --delay 2 --damping 0.01 --seconds 2
light check -- "$ZW" check "$T/scene.json" --model "$M" --delay 2
light compare -- "$ZW" compare "$M" --reference table1
light export-json -- "$ZW" export "$M" --format json -o "$T/m.json"

# Each heavy command loads what it needs and only that.
L=$(mapped "$ZW" estimate "$LOG" -o "$T/frf.csv")
echo "$L" | grep -q 'zwidth-hdf5\.so' || fail "estimate on .h5 did not load zwidth-hdf5.so"
echo "$L" | grep -q 'libhdf5' || fail "estimate on .h5 did not load libhdf5"
! echo "$L" | grep -qE 'libcholmod|libglog|zwidth-fit' || fail "estimate loaded Ceres"
L=$(mapped "$ZW" fit "$T/frf.csv" -o "$T/fit.json")
echo "$L" | grep -q 'zwidth-fit\.so' || fail "fit did not load zwidth-fit.so"
echo "$L" | grep -q 'libcholmod' || fail "fit did not load Ceres' libraries (cholmod)"
! echo "$L" | grep -qE 'libhdf5|zwidth-hdf5' || fail "fit on a CSV response loaded HDF5"
[ -s "$T/fit.json" ] || fail "fit wrote no model"
echo "ok: estimate on .h5 loads only the HDF5 plugin, fit on CSV only the fit plugin"

# Through a symbolic link elsewhere: the plugins are found from the real path.
mkdir -p "$T/elsewhere"; ln -s "$ZW" "$T/elsewhere/zwidth"
(cd "$T" && "$T/elsewhere/zwidth" export "$M" --format hdf5 -o "$T/m.h5") || fail "export through a symbolic link"
[ -s "$T/m.h5" ] || fail "export through a symbolic link wrote nothing"
echo "ok: a symbolic link to the executable finds the plugins"

# A copy of the executable without its plugins, then with broken ones.
PLUG=$(LD_DEBUG=files "$ZW" export "$M" --format hdf5 -o "$T/m2.h5" 2>&1 |
       sed -n 's/.*file=\([^ ]*zwidth-hdf5\.so\) .*generating link map.*/\1/p' | head -1)
[ -n "$PLUG" ] || fail "could not see where zwidth-hdf5.so is loaded from"
RELFILE=$(realpath --relative-to="$(dirname "$ZW")" "$PLUG")   # e.g. ../lib/zwidth/zwidth-hdf5.so
mkdir -p "$T/copy/bin"; cp "$ZW" "$T/copy/bin/zwidth"
ZC=$T/copy/bin/zwidth
expect_exit1() {  # expect_exit1 NAME PATTERN -- command...
  local name=$1 pattern=$2; shift 3
  set +e; "$@" >"$T/out.txt" 2>"$T/err.txt"; local rc=$?; set -e
  [ "$rc" = 1 ] || { cat "$T/err.txt"; fail "$name: exit $rc, expected 1"; }
  grep -qE "$pattern" "$T/err.txt" || { cat "$T/err.txt"; fail "$name: message does not match '$pattern'"; }
  grep -q reinstall "$T/err.txt" || { cat "$T/err.txt"; fail "$name: message does not say to reinstall"; }
  echo "ok: $name -> exit 1: $(head -c 200 "$T/err.txt")"
}
"$ZC" boundary "$M" --delays 2 --b-points 20 -o "$T/b2.csv" >/dev/null || fail "boundary without plugins"
cmp -s "$T/b.csv" "$T/b2.csv" || fail "boundary without plugins wrote another boundary"
expect_exit1 missing-hdf5 "zwidth-hdf5\.so" -- "$ZC" export "$M" --format hdf5 -o "$T/m3.h5"
expect_exit1 missing-fit "zwidth-fit\.so" -- "$ZC" fit "$T/frf.csv" -o "$T/fit2.json"
[ ! -e "$T/m3.h5" ] && [ ! -e "$T/fit2.json" ] || fail "a failed plugin load left an output"
mkdir -p "$(dirname "$T/copy/bin/$RELFILE")"
printf 'not an ELF file' >"$T/copy/bin/$RELFILE"
expect_exit1 corrupt-hdf5 "zwidth-hdf5\.so" -- "$ZC" estimate "$LOG" -o "$T/frf2.csv"
cp "$(dirname "$PLUG")/zwidth-fit.so" "$T/copy/bin/$RELFILE"   # an ELF module without the HDF5 entry point
expect_exit1 foreign-hdf5 "zwidth-hdf5\.so.*entry point" -- "$ZC" export "$M" --format hdf5 -o "$T/m4.h5"
cp "$PLUG" "$T/copy/bin/$RELFILE"
"$ZC" export "$M" --format hdf5 -o "$T/m5.h5" || fail "the copy with its plugin restored"
cmp -s <(h5dump "$T/m.h5" 2>/dev/null | tail -n +2) <(h5dump "$T/m5.h5" 2>/dev/null | tail -n +2) ||
  ! command -v h5dump >/dev/null || fail "the copy's HDF5 export differs"
echo "PASS"
