#!/usr/bin/env bash
# The real EMPS log (../shared/real-data/EMPS: closed loop, friction, jittered
# time stamps, N and m): zwidth must read it and fit its rigid body. The
# benchmark's model has M ~ 95.1 kg; viscous friction is biased by Coulomb
# friction and the position loop in this log, so only M is checked (10%).
# Exit 77 (skipped) where ../shared is absent. Usage: emps_check.sh ZWIDTH SRC
set -u
ZW=$1; E=$2/../shared/real-data/EMPS
[ -f "$E/EMPS_train.csv" ] || { echo "skipped: $E not found"; exit 77; }
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
"$ZW" fit "$E/EMPS_train.csv" --input-column input --output-column output --fmin 2 --fmax 20 \
  --modes 0 --units linear -o "$T/emps.json" > "$T/out" 2>&1 || { cat "$T/out"; echo "0 passed, 1 failed"; exit 1; }
python3 - "$T/emps.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
ok = abs(m["m"] / 95.1 - 1) < 0.10 and m["b"] > 0
print(f"EMPS rigid body: M = {m['m']:.2f} (reference 95.1), Fv = {m['b']:.1f} (reference 203.5, biased here)")
print("1 passed, 0 failed" if ok else "0 passed, 1 failed")
sys.exit(0 if ok else 1)
PY
