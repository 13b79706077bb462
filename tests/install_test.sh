#!/usr/bin/env bash
# An install that stands alone. Usage: install_test.sh BUILD_DIR SOURCE_DIR [install|deb]
#   install: `cmake --install` into a temporary prefix;
#   deb:     `cpack -G DEB`, then `dpkg -x` of the package (no root install, no chroot).
# Checks that every part is where it belongs, then, with the source tree and the build tree
# hidden (empty tmpfs mounted over them in a private mount namespace, when unshare is allowed),
# runs `zwidth --version`, a small pipeline of commands, and imports the Python module from
# the prefix and uses it. Exit 77 (skip) for the Python part when python3/NumPy are missing.
set -euo pipefail
BUILD=$(cd "$1" && pwd); SRC=$(cd "$2" && pwd); MODE=${3:-install}
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

if [ "$MODE" = deb ]; then
  (cd "$T" && cpack -G DEB --config "$BUILD/CPackConfig.cmake" -B "$T/pkg" >"$T/cpack.log" 2>&1) ||
    { tail -20 "$T/cpack.log"; fail "cpack -G DEB"; }
  DEB=$(ls "$T"/pkg/*.deb)
  echo "package: $(basename "$DEB") ($(du -k "$DEB" | cut -f1) KB)"
  dpkg-deb -f "$DEB" Package Version Depends | sed 's/^/  /'
  dpkg-deb -x "$DEB" "$T/root"
  P="$T/root/usr"
else
  cmake --install "$BUILD" --prefix "$T/prefix" >/dev/null
  P="$T/prefix"
fi

PY=lib/python3/dist-packages
for f in bin/zwidth include/zwidth/model/plant.h include/zwidth/stability/zwidth.h include/zwidth/io/export.h \
         lib/cmake/zwidth/zwidthConfig.cmake lib/cmake/zwidth/zwidthTargets.cmake \
         share/zwidth/phantom/table1.json share/zwidth/phantom/table2.csv share/doc/zwidth/README.md \
         share/doc/zwidth/python.md; do
  [ -e "$P/$f" ] || fail "$f is not installed"
done
[ -n "$(find "$P/lib" -name libzwidth_stability.a)" ] || fail "libzwidth_stability.a is not installed"
# The executable's plugins (apps/plugins.cc): <libdir>/zwidth/, found from bin/zwidth's real path.
for f in zwidth-hdf5.so zwidth-fit.so; do
  [ -n "$(find "$P/lib" -path "*/zwidth/$f")" ] || fail "the plugin $f is not installed"
done
# Internal headers stay out, and every installed header compiles with only the
# installed ones (no public header reaches an internal or missing one).
for f in fit/fit_internal.h fit/bin_correlated_covariance.h io/io_internal.h io/log_internal.h io/isolated.h \
         io/hdf5_api.h fit/fit_api.h \
         io/h5_safety.h; do
  [ ! -e "$P/include/zwidth/$f" ] || fail "the internal header $f is installed"
done
(cd "$P/include/zwidth" && find . -name '*.h' | sort | sed 's|^\./\(.*\)|#include "\1"|') >"$T/all_headers.cc"
[ "$(wc -l <"$T/all_headers.cc")" -ge 20 ] || fail "fewer than 20 public headers are installed"
${CXX:-c++} -std=c++20 -fsyntax-only -I"$P/include/zwidth" -isystem /usr/include/eigen3 \
  $(pkg-config --cflags-only-I hdf5 2>/dev/null) "$T/all_headers.cc" || fail "an installed header does not compile alone"
if [ -f "$BUILD/python/zwidth/__init__.py" ]; then
  ls "$P/$PY"/zwidth/_zwidth*.so >/dev/null 2>&1 || fail "the Python extension is not installed"
  WITH_PYTHON=1
else
  echo "note: this build has no Python module (python3-dev or pybind11-dev missing)"; WITH_PYTHON=0
fi
echo "installed: bin, libraries, headers, CMake package, Python module, Table I/II, docs"

# The smoke test, run where neither the source tree nor the build tree can be read.
cat >"$T/smoke.sh" <<'SMOKE'
set -euo pipefail
P=$1; SRC=$2; BUILD=$3; W=$4; WITH_PYTHON=$5
if [ -e "$SRC/datasets/phantom/table1.json" ] || [ -e "$BUILD/bin/zwidth" ]; then
  echo "note: the source tree is still visible (no mount namespace)"
else
  echo "source tree and build tree hidden"
fi
cd "$W"
"$P/bin/zwidth" --version
"$P/bin/zwidth" --version | grep -q "^zwidth [0-9]" || { echo "FAIL: --version"; exit 1; }
"$P/bin/zwidth" simulate --model "$P/share/zwidth/phantom/table1.json" --seconds 20 -o log.h5 2>/dev/null
# fit on an .h5 log loads both plugins, from the prefix (not from the build tree).
LD_DEBUG=files "$P/bin/zwidth" fit log.h5 -o model.json 2>ld.txt >/dev/null || { grep -v '^ *[0-9]*:' ld.txt; exit 1; }
for f in zwidth-hdf5.so zwidth-fit.so; do
  grep -q "file=$P/.*/zwidth/$f .*generating link map" ld.txt || { echo "FAIL: $f not loaded from $P"; exit 1; }
done
if LD_DEBUG=files "$P/bin/zwidth" --help 2>&1 >/dev/null | grep -qE 'zwidth-(hdf5|fit)\.so|libhdf5|libcholmod'; then
  echo "FAIL: --help loads a plugin"; exit 1
fi
"$P/bin/zwidth" boundary model.json --delays 2 --b-step 0.01 -o b.csv --summary s.json >/dev/null
"$P/bin/zwidth" compare model.json --reference table1 >/dev/null || { echo "FAIL: compare with the built-in Table I"; exit 1; }
echo "CLI: simulate -> fit -> boundary ran from the prefix"
if [ "$WITH_PYTHON" = 0 ]; then echo "skip: no Python module in this build"; exit 77; fi
if ! /usr/bin/python3 -c "import numpy" 2>/dev/null; then echo "skip: no python3 with NumPy"; exit 77; fi
PYTHONPATH="$P/lib/python3/dist-packages" /usr/bin/python3 -s - "$P" <<'PYEOF'
import json, sys, zwidth
prefix = sys.argv[1]
assert zwidth.__file__.startswith(prefix), zwidth.__file__
m = zwidth.Model.load("model.json")
z = zwidth.ZWidth(m, delay_samples=2)
s = json.load(open("s.json"))["delays"][0]
assert z.summary() == s, (z.summary(), s)
K, f = z.critical(0.0)
t1 = zwidth.Model.table1()
print(f"python: zwidth {zwidth.__version__} from {zwidth.__file__}; K_cr(B=0) = {K:.6g} N m/rad "
      f"at {f:.4g} Hz, summary equals the CLI's; Table I built in (m = {t1.m})")
PYEOF
SMOKE
mkdir -p "$T/work"
if unshare --mount true 2>/dev/null; then
  unshare --mount bash -c 'mount -t tmpfs none "$1" && mount -t tmpfs none "$2" 2>/dev/null; shift 2; bash "$@"' \
    _ "$SRC" "$BUILD" "$T/smoke.sh" "$P" "$SRC" "$BUILD" "$T/work" "$WITH_PYTHON"
else
  bash "$T/smoke.sh" "$P" "$SRC" "$BUILD" "$T/work" "$WITH_PYTHON"
fi
