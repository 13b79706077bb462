#!/usr/bin/env bash
# Issue 30: under `ulimit -v 150000`, `fit` wrote its output and never exited:
# each OpenBLAS pool thread reserves a 128 MiB buffer at start, the mmap()
# fails under the limit, OpenBLAS retries it for ever, and its destructor joins
# that thread at exit. zwidth now runs OpenBLAS with one thread whatever the
# environment says (apps/main.cc). Each case runs `fit` (a response and a log)
# under the limit with a 60 s timeout and OPENBLAS_NUM_THREADS=8 in the
# environment, with the system's BLAS and, when one is found, OpenBLAS's
# (Debian's libopenblas0-pthread folder, or ZWIDTH_TEST_OPENBLAS_DIR). Without
# any OpenBLAS the test is skipped (exit 77): the hang is OpenBLAS's.
# Usage: blas_exit_test.sh ZWIDTH SRC
set -u
ZW=$(realpath "$1"); SRC=$(realpath "$2")
source "$SRC/tests/cli_lib.sh"
LOG=$SRC/datasets/phantom/phantom_30s.csv
"$ZW" estimate "$LOG" -o "$T/frf.csv" 2>/dev/null || { bad "estimate"; exit 1; }
fit_limited() {  # fit_limited NAME BLAS_DIR INPUT
  local name=$1 dir=$2 in=$3 out="$T/$1.json"
  ( ulimit -v 150000
    env ${dir:+LD_LIBRARY_PATH=$dir} OPENBLAS_NUM_THREADS=8 timeout -k 5 60 "$ZW" fit "$in" -o "$out" \
      >"$T/$name.out" 2>&1 ); local rc=$?
  if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then bad "$name: still running after 60 s (exit $rc)"; return; fi
  if [ $rc -ne 0 ]; then bad "$name: exit $rc"; tail -3 "$T/$name.out"; return; fi
  if ! $PY -c "import json,sys; m=json.load(open(sys.argv[1])); assert m['m'] > 0" "$out"; then
    bad "$name: $out is not a model"; return; fi
  ok "$name: exit 0 under ulimit -v 150000, model written"
}
fit_limited system-blas "" "$T/frf.csv"
OB=${ZWIDTH_TEST_OPENBLAS_DIR:-/usr/lib/x86_64-linux-gnu/openblas-pthread}
if [ -e "$OB/libblas.so.3" ]; then
  fit_limited openblas-frf "$OB" "$T/frf.csv"
  fit_limited openblas-log "$OB" "$LOG"
else
  echo "skip: no OpenBLAS at $OB (set ZWIDTH_TEST_OPENBLAS_DIR to a folder with its libblas.so.3)"
  [ $fail -eq 0 ] && exit 77
fi
echo "blas_exit: $pass passed, $fail failed"
[ $fail -eq 0 ]
