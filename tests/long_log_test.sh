#!/usr/bin/env bash
# Stress: logs from 1 second to 1 hour. A 1 s log is refused for a 4096 window
# given (with a suggestion), estimated with a 512 one and with the default; a 1 h log at 1 kHz
# (3.6 M samples, HDF5 and CSV) is estimated in one streaming pass whose peak
# memory stays far below the log's size. Usage: long_log_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2; M=$SRC/datasets/phantom/table1.json
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail=0; pass=0
check() { if eval "$2"; then echo "ok   $1"; pass=$((pass+1)); else echo "FAIL $1"; fail=$((fail+1)); fi; }
"$ZW" simulate --model "$M" -o "$T/1s.csv" --seconds 1 2>/dev/null
"$ZW" estimate "$T/1s.csv" --window-length 4096 -o "$T/a.csv" 2>"$T/err"; rc=$?
check "1 s log refused for a 4096 window given (exit 2, suggests 512)" '[ $rc -eq 2 ] && grep -q "window-length 512" "$T/err"'
# The default window follows the length (ident::DefaultWindowLength): 256 samples (512 would leave 1).
"$ZW" estimate "$T/1s.csv" -o "$T/a.csv" 2>"$T/err"; rc=$?
check "1 s log estimated with the default window (256 samples, 6 segments)" '[ $rc -eq 0 ] && grep -q "256-sample segment" "$T/err" && grep -q "6 segments" "$T/err"'
check "1 s log estimated with a 512 window" '"$ZW" estimate "$T/1s.csv" --window-length 512 --fmin 2 -o "$T/b.csv" 2>/dev/null'
# Peak memory of the same command on a 10 s log: the libraries' baseline.
"$ZW" simulate --model "$M" -o "$T/10s.h5" --seconds 10 2>/dev/null
base_kb=$( { /usr/bin/time -f "%M" "$ZW" estimate "$T/10s.h5" -o "$T/s.csv" 2>&1 >/dev/null; } | tail -1)
for ext in h5 csv; do
  "$ZW" simulate --model "$M" -o "$T/1h.$ext" --seconds 3600 2>/dev/null
  size_kb=$(( $(stat -c %s "$T/1h.$ext") / 1024 ))
  peak_kb=$( { /usr/bin/time -f "%M" "$ZW" estimate "$T/1h.$ext" -o "$T/h.csv" 2>&1 >/dev/null; } | tail -1)
  echo "     1 h $ext log: $size_kb KiB on disk; estimate peak RSS $peak_kb KiB (10 s log: $base_kb KiB)"
  # Holding the hour in memory would add 3.6 M x 16 bytes = 56 MiB.
  check "1 h $ext log estimated in bounded memory (< 8 MiB over the 10 s baseline)" '[ -s "$T/h.csv" ] && [ "$peak_kb" -lt $((base_kb + 8192)) ]'
  rm -f "$T/1h.$ext"
done
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
