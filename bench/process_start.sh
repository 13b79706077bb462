#!/usr/bin/env bash
# Whole-process time of zwidth commands (process start included), 30 runs
# each: mean elapsed and CPU (perf stat -r 30, children counted; without
# perf, the elapsed mean of 30 runs), and the shared objects each maps.
# Usage: process_start.sh ZWIDTH SOURCE_DIR   (scripts/bench runs it)
set -euo pipefail
ZW=$1; SRC=$(cd "$2" && pwd)
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
M=$SRC/datasets/phantom/table1.json
"$ZW" estimate "$SRC/datasets/phantom/phantom_30s.h5" -o "$T/frf.csv" 2>/dev/null
measure() {  # measure LABEL -- command...
  local label=$1; shift 2
  local libs; libs=$(LD_DEBUG=files "$@" 2>&1 >/dev/null | grep -c "generating link map" || true)
  if command -v perf >/dev/null && perf stat -r 1 true >/dev/null 2>&1; then
    perf stat -r 30 -x, -e task-clock "$@" >/dev/null 2>"$T/perf.txt"
    local cpu; cpu=$(awk -F, '/task-clock/ {printf "%.1f", $1}' "$T/perf.txt")
    local wall; wall=$(perf stat -r 30 "$@" 2>&1 >/dev/null | awk '/elapsed/ {printf "%.1f +- %.1f", $1 * 1000, $3 * 1000}')
    printf "%-44s %16s ms %8s ms %5s\n" "$label" "$wall" "$cpu" "$libs"
  else
    local t0 t1; t0=$(date +%s%N); for _ in $(seq 30); do "$@" >/dev/null 2>&1; done; t1=$(date +%s%N)
    printf "%-44s %16s ms %8s ms %5s\n" "$label" "$(( (t1 - t0) / 30000000 ))" "-" "$libs"
  fi
}
printf "%-44s %19s %11s %5s\n" "command" "elapsed" "CPU" "libs"
measure "--help" -- "$ZW" --help
measure "boundary table1 (1 delay, 20 B)" -- "$ZW" boundary "$M" --delays 2 --b-points 20 -o "$T/b.csv"
measure "export table1 --format json" -- "$ZW" export "$M" --format json -o "$T/m.json"
measure "export table1 --format hdf5 (HDF5 plugin)" -- "$ZW" export "$M" --format hdf5 -o "$T/m.h5"
measure "estimate phantom_30s.csv" -- "$ZW" estimate "$SRC/datasets/phantom/phantom_30s.csv" -o "$T/f.csv"
measure "estimate phantom_30s.h5 (plugin, fork)" -- "$ZW" estimate "$SRC/datasets/phantom/phantom_30s.h5" -o "$T/f.csv"
