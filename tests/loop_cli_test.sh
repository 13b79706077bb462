#!/usr/bin/env bash
# The haptic-loop flags (issue 16) refused with exit 2, a message naming the
# flag, and no output file; a valid filter file accepted. Usage: loop_cli_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
pass=0; fail=0
M=$SRC/datasets/phantom/table1.json
expect() {  # NAME PATTERN -- args of boundary
  local name=$1 pattern=$2; shift 3
  "$ZW" boundary "$M" -o "$T/out.csv" "$@" >"$T/stdout" 2>"$T/stderr"; local rc=$?
  if [ $rc -ne 2 ]; then echo "FAIL $name: exit $rc, expected 2"; cat "$T/stderr"; fail=$((fail+1)); return; fi
  if ! grep -qiE -e "$pattern" "$T/stderr"; then echo "FAIL $name: stderr lacks /$pattern/"; cat "$T/stderr"; fail=$((fail+1)); return; fi
  if ls "$T/out.csv"* >/dev/null 2>&1; then echo "FAIL $name: left an output"; fail=$((fail+1)); return; fi
  echo "ok   $name: $(head -c 150 "$T/stderr" | tr '\n' ' ')"; pass=$((pass+1))
}
expect cutoff-over-nyquist "velocity-filter-hz.*Nyquist" -- --velocity-filter-hz 600
expect cutoff-negative "velocity-filter-hz" -- --velocity-filter-hz -5
expect both-filters "not both" -- --velocity-filter-hz 50 --velocity-filter-coeffs 'b:1;a:1'
expect unstable-filter "filter_a.*unit circle" -- --velocity-filter-coeffs 'b:0.5;a:1,-1.5'
expect a0-not-one "a0 must be 1" -- --velocity-filter-coeffs 'b:0.5;a:2,-0.5'
expect not-a-number "not a finite number" -- --velocity-filter-coeffs 'b:0.5;a:1,x'
expect missing-file "no such readable file" -- --velocity-filter-coeffs "$T/none.txt"
expect hand-two-numbers "three numbers" -- --hand 1,2
expect hand-negative "must be >= 0" -- --hand 1,-2,3
printf 'b:0.2,0.2;\na:1,-0.6\n' > "$T/f.txt"
if "$ZW" boundary "$M" -o "$T/ok.csv" --delays 4 --velocity-filter-coeffs "$T/f.txt" --hand 1e-4,0.002,0.5 >/dev/null 2>&1 \
   && head -1 "$T/ok.csv" | grep -q K_passive; then
  echo "ok   filter file and hand accepted"; pass=$((pass+1))
else
  echo "FAIL filter file and hand"; fail=$((fail+1))
fi
# relay with the haptic loop: two hands refused (exit 2); one filter and one hand
# give K_cr within 1e-3 of the exact answer of the same loop (printed beside).
if "$ZW" relay "$M" --delay 4 --damping 0.005 --hand 0,0,0 --hand 1e-4,0,0 >/dev/null 2>"$T/stderr"; then
  echo "FAIL relay two hands accepted"; fail=$((fail+1))
elif [ $? -eq 2 ] && grep -q "at most one --hand" "$T/stderr"; then
  echo "ok   relay two hands refused"; pass=$((pass+1))
else
  echo "FAIL relay two hands: $(cat "$T/stderr")"; fail=$((fail+1))
fi
if "$ZW" relay "$M" --delay 4 --damping 0.005 --velocity-filter-hz 50 --hand 1e-3,2e-3,0.5 --seconds 20 --json \
     2>/dev/null | python3 -c 'import json,sys; j=json.load(sys.stdin); \
       sys.exit(0 if j["status"]=="refined" and abs(j["K_cr"]/j["K_cr_exact"]-1)<1e-3 \
                and abs(j["f_cr_hz"]/j["f_cr_exact_hz"]-1)<1e-3 else 1)'; then
  echo "ok   relay with filter and hand matches the exact loop"; pass=$((pass+1))
else
  echo "FAIL relay with filter and hand"; fail=$((fail+1))
fi
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
