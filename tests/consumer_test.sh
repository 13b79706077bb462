#!/usr/bin/env bash
# Installs zwidth to a temporary prefix and builds against it with find_package(zwidth):
# 1. tests/consumer (LANGUAGES C CXX, COMPONENTS hdf5): Table I's K_CR^max and an HDF5 log
#    written and read back;
# 2. examples/ (LANGUAGES CXX only, no component): the C++ examples, run on Table I, each
#    line as the build tree's own build of them prints it; the model-only one links
#    neither libhdf5 nor libmatio (readelf -d: its NEEDED libraries; ldd: what it maps);
# 3. COMPONENTS hdf5 in a C++-only project: refused, naming the C language.
# The installed headers are reached as <zwidth/...> with only <prefix>/include on the path.
# Usage: consumer_test.sh BUILD_DIR SRC
set -euo pipefail
BUILD=$1; SRC=$2
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
cmake --install "$BUILD" --prefix "$T/prefix" >/dev/null
cmake -S "$SRC/tests/consumer" -B "$T/build" -DCMAKE_PREFIX_PATH="$T/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$T/build" -j2 >/dev/null
"$T/build/consumer" "$T"

cmake -S "$SRC/examples" -B "$T/examples" -DCMAKE_PREFIX_PATH="$T/prefix" -DCMAKE_BUILD_TYPE=Release >"$T/ex.log" 2>&1 ||
  { cat "$T/ex.log"; fail "examples/ (LANGUAGES CXX) does not configure against the installed package"; }
grep -q "^zwidth_DIR:PATH=$T/prefix/" "$T/examples/CMakeCache.txt" || fail "examples/ did not use the installed zwidth"
! grep -qE '^(HDF5_|MATIO_)' "$T/examples/CMakeCache.txt" || fail "a C++-only find_package(zwidth) looked for HDF5 or matio"
cmake --build "$T/examples" -j2 >"$T/ex.log" 2>&1 || { tail -20 "$T/ex.log"; fail "examples/ does not build"; }
TABLE1=$SRC/datasets/phantom/table1.json
"$T/examples/example_model_zwidth" "$TABLE1" 1 2 >"$T/installed.txt"
"$BUILD/bin/example_model_zwidth" "$TABLE1" 1 2 >"$T/tree.txt"
diff <(grep '^delay' "$T/installed.txt") <(grep '^delay' "$T/tree.txt") || fail "the installed example's Z-width differs"
[ "$(grep -c '^delay' "$T/installed.txt")" = 2 ] || fail "example_model_zwidth printed no Z-width"
needed=$(readelf -d "$T/examples/example_model_zwidth" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | xargs)
mapped=$(ldd "$T/examples/example_model_zwidth" | wc -l)
if grep -qE 'hdf5|matio|curl' <<<"$needed $(ldd "$T/examples/example_model_zwidth")"; then
  fail "example_model_zwidth (reads a model JSON) links HDF5 or matio: $needed"
fi
echo "C++-only consumer: examples/ built against the package; example_model_zwidth NEEDs $needed ($mapped lines of ldd): no HDF5, no matio"

mkdir -p "$T/cxxh5"
cat >"$T/cxxh5/CMakeLists.txt" <<'CM'
cmake_minimum_required(VERSION 3.20)
project(cxx_hdf5 LANGUAGES CXX)
find_package(zwidth REQUIRED COMPONENTS hdf5)
CM
if cmake -S "$T/cxxh5" -B "$T/cxxh5/b" -DCMAKE_PREFIX_PATH="$T/prefix" >"$T/cxxh5.log" 2>&1; then
  fail "COMPONENTS hdf5 configured in a project without C"
fi
grep -q "component hdf5 needs the C language" "$T/cxxh5.log" || { cat "$T/cxxh5.log"; fail "COMPONENTS hdf5 without C: no clear message"; }
echo "COMPONENTS hdf5 without C: refused, naming the C language"
