"""Checks of report.html's DOM as headless Chromium left it (report_browser_test.sh).

  report_dom_check.py DOM good|poor SUMMARY.json
  report_dom_check.py --pdf-text REPORT.txt SUMMARY.json

The expected figures are the run's: one inline SVG per gnuplot figure, a
canvas per interactive chart; the Z-width table's rows are compared with the
run's summary.json (K_CR at B = 0 per delay, as the table prints it, %.5g).
"""
import json
import re
import sys
from html.parser import HTMLParser

FIGURES = ["region", "bode", "coherence", "kcr", "loop", "rigid"]
CHARTS = ["chart-kcr", "chart-bode-mag", "chart-bode-phase"]


class Dom(HTMLParser):
    def __init__(self):
        super().__init__()
        self.stack = []          # (tag, id, classes)
        self.order = []          # ids of interest in document order
        self.svg_drawn = {}      # figure name -> number of drawing elements in its svg
        self.canvases = {}       # chart id -> canvases inside
        self.external = []       # src/href attributes that load another file
        self.th = []             # the Z-width table's header cells
        self.rows = []           # its rows' cell texts
        self.verdict = None
        self.text_in = None

    def ancestors(self, attr):
        return [e[1] for e in self.stack if e[1]]

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        ident, cls = a.get("id", ""), a.get("class", "") or ""
        for key in ("src", "href", "xlink:href"):
            v = a.get(key)
            if v and not v.startswith(("#", "data:", "javascript:")) and tag not in ("a",):
                self.external.append((tag, key, v))
        if tag == "link" and a.get("rel") == "stylesheet":
            self.external.append((tag, "href", a.get("href")))
        if ident == "zwidth-table" or ident.startswith("figure-") or ident in CHARTS:
            self.order.append(ident)
        if ident == "verdict":
            self.verdict = cls
        ids = self.ancestors("id")
        fig = next((i[len("figure-"):] for i in ids if i.startswith("figure-")), None)
        if fig and tag in ("path", "polyline", "polygon", "line", "rect", "circle"):
            self.svg_drawn[fig] = self.svg_drawn.get(fig, 0) + 1
        chart = next((i for i in ids if i in CHARTS), None)
        if chart and tag == "canvas":
            self.canvases[chart] = self.canvases.get(chart, 0) + 1
        if "zwidth-table" in ids or ident == "zwidth-table":
            if tag == "tr":
                self.rows.append([])
            if tag in ("th", "td"):
                self.text_in = tag
                (self.th if tag == "th" else self.rows[-1]).append("")
        if tag not in ("br", "img", "meta", "link", "input", "hr", "use", "col"):
            self.stack.append((tag, ident, cls))

    def handle_endtag(self, tag):
        if tag in ("th", "td"):
            self.text_in = None
        for i in range(len(self.stack) - 1, -1, -1):
            if self.stack[i][0] == tag:
                del self.stack[i:]
                break

    def handle_data(self, data):
        if self.text_in == "th":
            self.th[-1] += data
        elif self.text_in == "td" and self.rows and self.rows[-1]:
            self.rows[-1][-1] += data


def expected_rows(summary_path):
    s = json.load(open(summary_path))
    return [(e["delay_samples"], "%.5g" % e["K_cr_at_zero_B"]) for e in s["boundary"]]


def check_dom(path, kind, summary_path):
    d = Dom()
    d.feed(open(path, encoding="utf-8").read())
    errors = []
    for f in FIGURES:
        if d.svg_drawn.get(f, 0) < 5:
            errors.append(f"figure {f}: {d.svg_drawn.get(f, 0)} drawing elements")
    for c in CHARTS:
        if d.canvases.get(c, 0) < 1:
            errors.append(f"chart {c}: not drawn (no canvas)")
    if d.external:
        errors.append(f"loads other files: {d.external[:5]}")
    if "zwidth-table" not in d.order or any(o.startswith("figure-") or o in CHARTS
                                           for o in d.order[:d.order.index("zwidth-table")] if "zwidth-table" in d.order):
        errors.append(f"the Z-width table is not above the first figure: {d.order[:4]}")
    header = " ".join(d.th)
    for unit in ("[N m/rad]", "[N m s/rad]", "[samples]"):
        if unit not in header:
            errors.append(f"the Z-width table's header lacks {unit}: {header}")
    rows = [r for r in d.rows if r and r[0].strip()]
    want = expected_rows(summary_path)
    # The delay cell: "loop d + model m = t samples" (issue 29): the loop's delay d and t = d + m.
    cells = [re.fullmatch(r"loop (\d+) \+ model (\d+) = (\d+) samples", r[0].strip()) for r in rows]
    if not all(c and int(c[1]) + int(c[2]) == int(c[3]) for c in cells):
        errors.append(f"delay cells not 'loop d + model m = d+m samples': {[r[0] for r in rows]}")
    got = [(int(c[1]) if c else -1, r[1].split("\u00b1")[0].strip()) for c, r in zip(cells, rows)]
    if got != want:
        errors.append(f"Z-width rows {got} != summary.json's {want}")
    if kind == "poor" and (d.verdict is None or "poor" not in d.verdict):
        errors.append(f"a poor fit's verdict is not marked poor: class={d.verdict}")
    if kind == "good" and (d.verdict is None or "good" not in d.verdict):
        errors.append(f"verdict class {d.verdict}")
    for e in errors:
        print("  " + e)
    return not errors


def check_pdf_text(path, summary_path):
    pages = open(path, encoding="utf-8").read().split("\f")
    head = [i for i, p in enumerate(pages) if "loop delay" in p]
    if not head:
        print("  no page has the Z-width table's header")
        return False
    page = pages[head[0]]
    missing = [k for _, k in expected_rows(summary_path) if k not in page]
    if missing:
        print(f"  page {head[0] + 1} has the header but not the rows with K_CR(0) = {missing}")
        return False
    return True


if __name__ == "__main__":
    if sys.argv[1] == "--pdf-text":
        sys.exit(0 if check_pdf_text(sys.argv[2], sys.argv[3]) else 1)
    sys.exit(0 if check_dom(sys.argv[1], sys.argv[2], sys.argv[3]) else 1)
