# Shared by the CLI shell tests (sourced after ZW, SRC are set): a temporary
# folder T, the pass/fail counters, ok/bad, and expect, which runs a command
# that must be refused: exit 2, a message matching PATTERN on stderr, and no
# file OUTPUT* left behind.
PY=/usr/bin/python3
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
pass=0; fail=0
M=$SRC/datasets/phantom/table1.json
ok() { echo "ok   $1"; pass=$((pass+1)); }
bad() { echo "FAIL $1"; fail=$((fail+1)); }
expect() {  # expect NAME PATTERN OUTPUT -- command...
  local name=$1 pattern=$2 out=$3; shift 4
  "$@" >"$T/stdout" 2>"$T/stderr"; local rc=$?
  if [ $rc -ne 2 ]; then bad "$name: exit $rc, expected 2"; cat "$T/stderr"; return; fi
  if ! grep -qiE -e "$pattern" "$T/stderr"; then bad "$name: stderr lacks /$pattern/"; cat "$T/stderr"; return; fi
  if [ -n "$out" ] && ls "$out"* >/dev/null 2>&1; then bad "$name: left $out"; return; fi
  ok "$name: $(head -c 200 "$T/stderr" | tr '\n' ' ')"
}
