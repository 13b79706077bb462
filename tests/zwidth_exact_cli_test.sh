#!/bin/bash
# Issue 31 from the command line: the 8-section family of the issue (omega_i =
# 300 * 1.08^i rad/s, damping ratio 0.025, v_i = 0.93 omega_i, Table I's m and
# b), written here. `check` passes the walls {K = 1, B = 0} and {K = 1, B = 0.02}
# (the closed loop's eigenvalues: largest |z| 0.9985 at K = 1, B = 0), and
# `boundary` gives K_cr(0) = 2.46406 and says that the eigenvalues decided.
# Usage: zwidth_exact_cli_test.sh ZWIDTH SRC
ZW=$1; SRC=$2
source "$SRC/tests/cli_lib.sh"
$PY - "$T/fam8.json" <<'PYEOF'
import json, sys
modes = []
for i in range(8):
    w = 300 * 1.08 ** i; v = 0.93 * w
    modes.append({"omega": w, "c": 0.05 * w, "v": v, "d": 0.05 * v})
json.dump({"m": 1.168e-3, "b": 0.00584, "modes": modes, "delay_samples": 0, "sample_period_s": 0.001},
          open(sys.argv[1], "w"))
PYEOF
echo '{"objects":[{"name":"wall","K":1,"B":0},{"name":"damped","K":1,"B":0.02}]}' >"$T/scene.json"
"$ZW" check "$T/scene.json" --model "$T/fam8.json" --delay 2 >"$T/stdout" 2>&1; rc=$?
if [ $rc -eq 0 ] && ! grep -q UNSTABLE "$T/stdout"; then ok "check-walls-of-8-sections"; else bad "check-walls-of-8-sections: exit $rc"; cat "$T/stdout"; fi
echo '{"objects":[{"name":"stiff","K":3,"B":0}]}' >"$T/stiff.json"
"$ZW" check "$T/stiff.json" --model "$T/fam8.json" --delay 2 >"$T/stdout" 2>&1; rc=$?
if [ $rc -eq 3 ]; then ok "check-stiff-wall-of-8-sections-unstable"; else bad "check-stiff-wall: exit $rc"; cat "$T/stdout"; fi
"$ZW" boundary "$T/fam8.json" --delays 2 --b-points 20 -o "$T/b.csv" --summary "$T/s.json" >"$T/stdout" 2>&1; rc=$?
k=$($PY -c "import json,sys; print(json.load(open(sys.argv[1]))['delays'][0]['K_cr_at_zero_B'])" "$T/s.json" 2>/dev/null)
m=$($PY -c "import json,sys; print(json.load(open(sys.argv[1]))['delays'][0]['stability_test']['method'])" "$T/s.json" 2>/dev/null)
if [ $rc -eq 0 ] && $PY -c "import sys; sys.exit(0 if abs(float('$k') - 2.46406) < 5e-6 else 1)" && [ "$m" = eigenvalues ] \
   && grep -q "closed loop's eigenvalues" "$T/stdout"; then ok "boundary-8-sections K_cr(0) = $k by $m"
else bad "boundary-8-sections: exit $rc, K_cr(0) = $k, method $m"; cat "$T/stdout"; fi
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
