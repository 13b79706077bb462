#!/usr/bin/env bash
# report.html in a real browser (headless Chromium), from a copy of the file
# alone in an empty folder: every figure drawn (the gnuplot SVGs inlined, the
# interactive dygraphs charts drawn on canvases), nothing loaded from another
# file, the Z-width table with units above the first figure, a poor fit's
# report visibly marked, and a print to PDF that keeps the Z-width table on
# one page. The DOM is read after the page's scripts ran (--dump-dom with a
# virtual time budget) and checked by tests/report_dom_check.py.
# Usage: report_browser_test.sh ZWIDTH SRC
set -u
ZW=$1; SRC=$2
source "$SRC/tests/cli_lib.sh"
CHROME=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$CHROME" ]; then echo "chromium is not installed (scripts/setup installs it): skipped"; exit 0; fi
LOG=$SRC/datasets/phantom/phantom_30s.h5
browse() {  # browse HTML OUT.dom: the DOM after the scripts ran
  timeout 120 "$CHROME" --headless=new --no-sandbox --disable-gpu --no-first-run --user-data-dir="$T/profile" \
    --virtual-time-budget=15000 --dump-dom "file://$1" > "$2" 2>"$T/chrome.log"
}
for kind in good poor; do
  flags=(); [ $kind = poor ] && flags=(--modes 0)
  if ! "$ZW" run "$LOG" -o "$T/run_$kind" --delays 2,4,8 --reference table1 "${flags[@]}" >"$T/run.log" 2>&1; then
    bad "$kind: zwidth run failed"; cat "$T/run.log"; continue
  fi
  mkdir -p "$T/alone_$kind"; cp "$T/run_$kind/report.html" "$T/alone_$kind/"
  browse "$T/alone_$kind/report.html" "$T/$kind.dom"
  if "$PY" "$SRC/tests/report_dom_check.py" "$T/$kind.dom" "$kind" "$T/run_$kind/summary.json"; then
    ok "$kind: the DOM of report.html alone"
  else
    bad "$kind: the DOM of report.html alone"
  fi
done
# Printed: the Z-width table on one page (its header and every delay's row).
if command -v pdftotext >/dev/null; then
  timeout 120 "$CHROME" --headless=new --no-sandbox --disable-gpu --no-first-run --user-data-dir="$T/profile" \
    --no-pdf-header-footer --print-to-pdf="$T/report.pdf" "file://$T/alone_good/report.html" 2>>"$T/chrome.log"
  pdftotext -layout "$T/report.pdf" "$T/report.txt"
  if "$PY" "$SRC/tests/report_dom_check.py" --pdf-text "$T/report.txt" "$T/run_good/summary.json"; then
    ok "print: the Z-width table on one page"
  else
    bad "print: the Z-width table split or missing"
  fi
else
  bad "pdftotext (poppler-utils) is not installed: scripts/setup installs it"
fi
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
