# Sourced by scripts/sanitize and scripts/fuzz: one clang build tree,
# build-san/, instrumented with AddressSanitizer + UndefinedBehaviorSanitizer
# and libFuzzer's coverage (fuzzer-no-link), holding both the tests and the
# fuzz targets, so that CI compiles the library once for both.
# -O2 with line tables only: ASan's reports keep file:line, and fit/fit.cc
# compiles in 81 s of CPU against 248 s for gcc -O2 -g1 and 342 s wall for
# gcc -O2 -g (2-core machine, 2026-11-27); -O1 compiles a little faster but
# runs the eigenvalue sweeps up to 14x slower than gcc -O2.
ZWIDTH_EXTRA_PACKAGES="clang libclang-rt-14-dev" source "$ZWIDTH_ROOT/scripts/setup" --packages-only
ZWIDTH_SAN_BUILD=$ZWIDTH_ROOT/build-san
if [ ! -f "$ZWIDTH_SAN_BUILD/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S "$ZWIDTH_ROOT" -B "$ZWIDTH_SAN_BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
    -DZWIDTH_SANITIZE=ON -DZWIDTH_BUILD_FUZZERS=ON -DZWIDTH_BUILD_TESTS=ON -DZWIDTH_BUILD_BENCHMARKS=OFF \
    ${ZWIDTH_SAN_CMAKE_ARGS:-}
fi
