#!/usr/bin/env bash
# An install that stands alone. Usage: install_test.sh BUILD_DIR SOURCE_DIR [install|deb]
#   install: `cmake --install` into a temporary prefix;
#   deb:     `cpack -G DEB`: the packages zwidth, libzwidth-dev and python3-zwidth, each checked
#            (lintian: no error; copyright, changelog, contents, Depends against what the files
#            need), then `dpkg -x` of all three into one root (no root install, no chroot).
# Checks that every part is where it belongs, then, with the source tree and the build tree
# hidden (empty tmpfs mounted over them in a private mount namespace, when unshare is allowed),
# runs `zwidth --version`, a small pipeline of commands, and imports the Python module from
# the prefix and uses it; for the packages also every example of every command's --help, the
# completion and the man page (tests/cli_help_test.sh on the installed files), and
# tests/consumer built against the -dev package's CMake config. Exit 77 (skip) for the Python
# part when python3/NumPy are missing.
set -euo pipefail
BUILD=$(cd "$1" && pwd); SRC=$(cd "$2" && pwd); MODE=${3:-install}
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
WITH_PYTHON=0; [ -f "$BUILD/python/zwidth/__init__.py" ] && WITH_PYTHON=1

# has_dep FIELD PACKAGE: PACKAGE is one of the alternatives of FIELD (a Depends line).
has_dep() { tr ',|' '\n\n' <<<"$1" | sed 's/(.*//; s/:any//; s/ //g' | grep -qx -- "$2"; }
# provides_dep DEPENDS PKG: PKG provides a name that DEPENDS lists (a virtual package such as
# liblapack.so.3, which the BLAS/LAPACK alternative selected here, e.g. OpenBLAS, provides).
provides_dep() {
  local v
  for v in $(dpkg-query -W -f='${Provides}' "$2" 2>/dev/null | tr ',' '\n' | sed 's/(.*//; s/ //g'); do
    has_dep "$1" "$v" && return 0
  done
  return 1
}
# owner FILE: the Debian package that holds FILE (through links, and /lib = /usr/lib).
owner() {
  local f r; r=$(realpath "$1")
  for f in "$1" "$r" "/usr${r#/usr}" "${r#/usr}"; do
    dpkg -S "$f" 2>/dev/null | head -1 | cut -d: -f1 && return 0
  done
  return 1
}

if [ "$MODE" = deb ]; then
  (cd "$T" && cpack -G DEB --config "$BUILD/CPackConfig.cmake" -B "$T/pkg" >"$T/cpack.log" 2>&1) ||
    { tail -20 "$T/cpack.log"; fail "cpack -G DEB"; }
  ldconfig -p | grep -E 'x86-64|x86_64|64bit|AArch64|aarch64' >"$T/ldcache" || ldconfig -p >"$T/ldcache"
  want="libzwidth-dev zwidth"; [ "$WITH_PYTHON" = 1 ] && want="libzwidth-dev python3-zwidth zwidth"
  got=$(for d in "$T"/pkg/*.deb; do dpkg-deb -f "$d" Package; done | sort | xargs)
  [ "$got" = "$want" ] || fail "packages: '$got', expected '$want'"
  for d in "$T"/pkg/*.deb; do
    name=$(dpkg-deb -f "$d" Package); R="$T/one/$name"
    echo "package: $(basename "$d") ($(du -k "$d" | cut -f1) KB)"
    dpkg-deb -f "$d" Version Section Depends Recommends Suggests | sed 's/^/  /'
    mkdir -p "$R" "$T/root"; dpkg-deb -x "$d" "$R"; dpkg-deb -x "$d" "$T/root"
    dpkg-deb -c "$d" | awk '$1 !~ /^d/ {print $6}' | sed 's|^\./||' >"$T/$name.files"
    if command -v lintian >/dev/null; then
      lintian --tag-display-limit 0 "$d" 2>/dev/null >"$T/lintian.txt" || true
      sed 's/^/  lintian: /' "$T/lintian.txt"
      ! grep -q '^E:' "$T/lintian.txt" || fail "lintian reports errors on $name"
      echo "  lintian: $(grep -c '^E:' "$T/lintian.txt") errors, $(grep -c '^W:' "$T/lintian.txt") warnings"
    else
      echo "  skip: lintian is not installed (apt-get install lintian)"
    fi
    # Debian's copyright (machine-readable) and changelog, for this package and version.
    doc="$R/usr/share/doc/$name"
    head -1 "$doc/copyright" | grep -qx 'Format: https://www.debian.org/doc/packaging-manuals/copyright-format/1.0/' ||
      fail "$name: usr/share/doc/$name/copyright is not in the machine-readable format"
    zcat "$doc/changelog.gz" >"$T/changelog"
    v=$(dpkg-parsechangelog -l "$T/changelog" -S Version)
    [ "$v" = "$(dpkg-deb -f "$d" Version)" ] || fail "$name: changelog.gz's version $v is not the package's"
    # What the ELF files need (their NEEDED libraries' packages) is in Depends.
    deps=$(dpkg-deb -f "$d" Depends)
    while read -r f; do
      file -b "$R/$f" | grep -q '^ELF' || continue
      for lib in $(readelf -d "$R/$f" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
        path=$(awk -v l="$lib" '$1 == l {print $NF; exit}' "$T/ldcache")
        pkg=$(owner "$path") || fail "$name: no package holds $lib ($path), which $f needs"
        has_dep "$deps" "${pkg%%:*}" || provides_dep "$deps" "${pkg%%:*}" ||
          fail "$name: $f needs $lib ($pkg), not in Depends: $deps"
      done
    done <"$T/$name.files"
  done
  # BLAS and LAPACK by their reference interfaces, satisfied by any Debian BLAS: Depends name
  # liblapack3 | liblapack.so.3 (and libblas3 | libblas.so.3 when libblas.so.3 is NEEDED),
  # never the implementation selected at build time (libatlas3-base, libopenblas...).
  for d in "$T"/pkg/zwidth_*.deb "$T"/pkg/python3-zwidth_*.deb; do
    [ -e "$d" ] || continue
    deps=$(dpkg-deb -f "$d" Depends)
    grep -qF "liblapack3 | liblapack.so.3" <<<"$deps" || fail "$(basename "$d"): Depends lack 'liblapack3 | liblapack.so.3': $deps"
    ! grep -qE '(^|[ ,])libblas3([ ,]|$)' <<<"$deps" || grep -qF "libblas3 | libblas.so.3" <<<"$deps" ||
      fail "$(basename "$d"): Depends name libblas3 without its alternative libblas.so.3: $deps"
    ! grep -qE 'libatlas|libopenblas|libblis|libmkl' <<<"$deps" || fail "$(basename "$d"): Depends name a BLAS implementation: $deps"
  done
  echo "Depends: liblapack3 | liblapack.so.3 (BLAS through it), no BLAS implementation named"
  # Each file in one package only; the runtime, development and Python parts where they belong.
  dup=$(cat "$T"/*.files | sort | uniq -d)
  [ -z "$dup" ] || fail "files in two packages: $dup"
  for f in usr/bin/zwidth usr/share/man/man1/zwidth.1.gz usr/share/bash-completion/completions/zwidth \
           usr/share/zwidth/phantom/table1.json usr/share/zwidth/phantom/table2.csv; do
    grep -qx "$f" "$T/zwidth.files" || fail "zwidth does not hold $f"
  done
  grep -q '/zwidth/zwidth-fit.so$' "$T/zwidth.files" || fail "zwidth does not hold the plugins"
  ! grep -qE '^usr/include/|\.a$|/cmake/' "$T/zwidth.files" || fail "zwidth holds development files"
  grep -q '^usr/include/zwidth/stability/zwidth.h$' "$T/libzwidth-dev.files" || fail "libzwidth-dev lacks the headers"
  grep -q '/libzwidth_stability\.a$' "$T/libzwidth-dev.files" || fail "libzwidth-dev lacks the static libraries"
  grep -q '/cmake/zwidth/zwidthConfig\.cmake$' "$T/libzwidth-dev.files" || fail "libzwidth-dev lacks the CMake package"
  ! grep -qE '^usr/bin/|\.so$' "$T/libzwidth-dev.files" || fail "libzwidth-dev holds runtime files"
  if [ "$WITH_PYTHON" = 1 ]; then
    ext=$(grep -o 'dist-packages/zwidth/_zwidth\.cpython-[0-9]*' "$T/python3-zwidth.files") ||
      fail "python3-zwidth lacks the extension"
    abi=${ext##*cpython-}; major=${abi:0:1}; minor=${abi:1}
    pydeps=$(dpkg-deb -f "$T"/pkg/python3-zwidth_*.deb Depends)
    for want in "python3 (>= $major.$minor~)" "python3 (<< $major.$((minor + 1)))" python3-numpy; do
      grep -qF "$want" <<<"$pydeps" || fail "python3-zwidth (built for CPython $major.$minor) lacks '$want' in Depends: $pydeps"
    done
    echo "python3-zwidth: built for CPython $major.$minor, and says so in Depends"
  fi
  echo "packages: lintian without errors, copyright and changelog each, contents split, Depends cover the ELF files' libraries"
  P="$T/root/usr"
else
  cmake --install "$BUILD" --prefix "$T/prefix" >/dev/null
  P="$T/prefix"
fi

PY=lib/python3/dist-packages
for f in bin/zwidth include/zwidth/model/plant.h include/zwidth/stability/zwidth.h include/zwidth/io/export.h \
         share/zwidth/phantom/table1.json share/zwidth/phantom/table2.csv share/doc/zwidth/README.md \
         share/doc/zwidth/python.md; do
  [ -e "$P/$f" ] || fail "$f is not installed"
done
[ -n "$(find "$P/lib" -name libzwidth_stability.a)" ] || fail "libzwidth_stability.a is not installed"
for f in zwidthConfig.cmake zwidthTargets.cmake; do
  [ -n "$(find "$P/lib" -path "*/cmake/zwidth/$f")" ] || fail "the CMake package's $f is not installed"
done
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
# Consumers write <zwidth/model/plant.h> with <prefix>/include alone on the path: no installed
# header includes one of ours in the source tree's short form ("model/plant.h").
bare=$(grep -rlE '#include "(model|ident|fit|stability|io|analysis|report)/' "$P/include/zwidth" || true)
[ -z "$bare" ] || fail "installed headers include the short form instead of \"zwidth/...\": $bare"
(cd "$P/include" && find zwidth -name '*.h' | sort | sed 's|^\(.*\)|#include <\1>|') >"$T/all_headers.cc"
[ "$(wc -l <"$T/all_headers.cc")" -ge 20 ] || fail "fewer than 20 public headers are installed"
${CXX:-c++} -std=c++20 -fsyntax-only -I"$P/include" -isystem /usr/include/eigen3 \
  "$T/all_headers.cc" || fail "an installed header does not compile with only <prefix>/include"
if [ "$WITH_PYTHON" = 1 ]; then
  ls "$P/$PY"/zwidth/_zwidth*.so >/dev/null 2>&1 || fail "the Python extension is not installed"
else
  echo "note: this build has no Python module (python3-dev or pybind11-dev missing)"
fi
echo "installed: bin, libraries, headers, CMake package, Python module, Table I/II, docs"

# The smoke test, run where neither the source tree nor the build tree can be read.
cat >"$T/smoke.sh" <<'SMOKE'
set -euo pipefail
P=$1; SRC=$2; BUILD=$3; W=$4; WITH_PYTHON=$5; MODE=$6; KIT=$7
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
if [ "$MODE" = deb ]; then
  # Every example of every command, the completion and the man page, on the installed files
  # (the examples' Table I: the installed one).
  bash "$KIT/tests/cli_help_test.sh" "$P/bin/zwidth" "$KIT" "$P/share/bash-completion/completions/zwidth" \
    "$P/share/man/man1/zwidth.1.gz" >help.txt 2>&1 || { grep -v '^ok' help.txt; echo "FAIL: cli_help_test.sh on the packages"; exit 1; }
  echo "CLI of the packages: $(tail -1 help.txt) (tests/cli_help_test.sh: examples, completion, man page)"
  # A C++ consumer against the -dev package's CMake config, and its Depends against what
  # that configure found: the package of each file it used must be one apt installs with
  # libzwidth-dev (its Depends, recursively: Ceres's config finds BLAS through SuiteSparse).
  # FindHDF5 also looks for h5diff, which nothing needs (hdf5-tools, not a dependency).
  { cmake -S "$KIT/consumer" -B consumer-build -DCMAKE_PREFIX_PATH="$P" -DCMAKE_BUILD_TYPE=Release &&
    cmake --build consumer-build -j2 && ./consumer-build/consumer; } >consumer.log 2>&1 ||
    { tail -20 consumer.log; echo "FAIL: tests/consumer against the -dev package"; exit 1; }
  grep -q "^zwidth_DIR:PATH=$P/" consumer-build/CMakeCache.txt || { echo "FAIL: the consumer did not use $P's zwidth"; exit 1; }
  # examples/: C++ only (no C compiler, no HDF5), against the -dev package; the model-only
  # example links neither libhdf5 nor libmatio.
  { cmake -S "$KIT/examples" -B examples-build -DCMAKE_PREFIX_PATH="$P" -DCMAKE_BUILD_TYPE=Release &&
    cmake --build examples-build -j2 &&
    ./examples-build/example_model_zwidth "$P/share/zwidth/phantom/table1.json" 2; } >examples.log 2>&1 ||
    { tail -20 examples.log; echo "FAIL: examples/ (LANGUAGES CXX) against the -dev package"; exit 1; }
  if readelf -d examples-build/example_model_zwidth | grep NEEDED | grep -qE 'hdf5|matio'; then
    echo "FAIL: example_model_zwidth links HDF5 or matio"; exit 1
  fi
  echo "C++: examples/ (LANGUAGES CXX) built and ran against the -dev package; the model-only one links no HDF5 or matio"
  source "$KIT/deps.sh"; n=0
  while IFS='=' read -r key path; do
    case $path in "$W"/*|"$P"/*|"$KIT"/*) continue ;; esac  # the consumer's own folders, the packages'
    # A package's config folder (Ceres_DIR): its config file; other folders are shared.
    [ -d "$path" ] && path=$(find "$path" -maxdepth 1 -type f \( -name '*Config.cmake' -o -name '*-config.cmake' \) | head -1)
    [ -f "$path" ] || continue
    pkg=$(owner "$path") || { echo "FAIL: no package holds $path (${key%%:*})"; exit 1; }
    grep -qx -- "$pkg" "$KIT/dev.closure" ||
      { echo "FAIL: find_package(zwidth) used $path (${key%%:*}) of $pkg, which libzwidth-dev's Depends do not bring: $(cat "$KIT/dev.depends")"; exit 1; }
    n=$((n + 1))
  done < <(grep -E '^[A-Za-z0-9_]+(_DIR|_LIBRARY[A-Za-z0-9_]*|_EXECUTABLE|_INCLUDE_DIR[A-Za-z0-9_]*):[A-Z]+=/|^pkgcfg_lib_' \
             consumer-build/CMakeCache.txt | grep -vE '^(CMAKE_|zwidth_DIR|HDF5_DIFF_EXECUTABLE)' | sed 's/:[A-Z]*=/=/')
  [ "$n" -ge 5 ] || { echo "FAIL: only $n dependency files in the consumer's cache"; exit 1; }
  echo "C++: tests/consumer built and ran against the -dev package; the $n files its configure found are in packages libzwidth-dev depends on"
fi
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
mkdir -p "$T/work" "$T/kit/tests" "$T/kit/datasets"
# What the smoke needs from the source tree, copied before it is hidden.
cp "$SRC/tests/cli_help_test.sh" "$SRC/tests/cli_lib.sh" "$T/kit/tests/"
# cli_help_test.sh collects the exit statuses the sources use (main.cc, the commands, the signal handler).
mkdir -p "$T/kit/apps" "$T/kit/io"
cp "$SRC"/apps/*.cc "$T/kit/apps/"
cp "$SRC/io/atomic_file.cc" "$T/kit/io/"
cp -r "$SRC/tests/consumer" "$T/kit/consumer"
cp -r "$SRC/examples" "$T/kit/examples"
ln -s "$P/share/zwidth/phantom" "$T/kit/datasets/phantom"
declare -f owner >"$T/kit/deps.sh"
if [ "$MODE" = deb ]; then
  dpkg-deb -f "$T"/pkg/libzwidth-dev_*.deb Depends >"$T/kit/dev.depends"
  # The packages apt installs with libzwidth-dev: its Depends (first alternatives too), recursively.
  apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks --no-replaces \
    --no-enhances $(tr ',|' '\n\n' <"$T/kit/dev.depends" | sed 's/(.*//; s/ //g') 2>/dev/null |
    grep -v '^ ' | sort -u >"$T/kit/dev.closure"
fi
if unshare --mount true 2>/dev/null; then
  unshare --mount bash -c 'mount -t tmpfs none "$1" && mount -t tmpfs none "$2" 2>/dev/null; shift 2; bash "$@"' \
    _ "$SRC" "$BUILD" "$T/smoke.sh" "$P" "$SRC" "$BUILD" "$T/work" "$WITH_PYTHON" "$MODE" "$T/kit"
else
  bash "$T/smoke.sh" "$P" "$SRC" "$BUILD" "$T/work" "$WITH_PYTHON" "$MODE" "$T/kit"
fi
