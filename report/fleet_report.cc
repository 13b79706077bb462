#include "report/fleet_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <locale>
#include <map>
#include <sstream>

#include "io/model_json.h"
#include "io/provenance.h"
#include "model/plant.h"
#include "model/sample_period.h"
#include "model/units.h"
#include "report/histogram.h"
#include "report/report_internal.h"
#include "stability/zwidth.h"

namespace zwidth::report {
namespace {

using Row = std::map<std::string, std::string>;
const double kNan = std::numeric_limits<double>::quiet_NaN();

double Cell(const Row& r, const std::string& c) {
  auto it = r.find(c);
  if (it == r.end() || it->second.empty()) return kNan;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  return end && *end == '\0' ? v : kNan;
}
std::string Get(const Row& r, const std::string& c) {
  auto it = r.find(c);
  return it == r.end() ? "" : it->second;
}
std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}
// An axis tick on an axis of ticks `step` apart reaching `reach` (the larger
// |end|): 3 significant digits, more where 3 would print two ticks alike (a
// narrow range far from 0: 329.9, 330.0, 330.1, not 330 three times).
std::string Tick(double v, double step, double reach) {
  int digits = 3;
  if (step > 0 && reach > 0) digits = std::clamp(static_cast<int>(std::ceil(std::log10(reach / step))) + 1, 3, 8);
  char b[40];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

// The unit's fitted model from its row (nullopt when a value is missing).
std::optional<model::Plant> PlantOf(const Row& r, double* period_s) {
  model::Plant p;
  p.m = Cell(r, "m");
  p.b = Cell(r, "b");
  const double modes = Cell(r, "modes"), delay = Cell(r, "delay_samples"), rate = Cell(r, "sample_rate_hz");
  if (!std::isfinite(modes) || !std::isfinite(delay) || !(rate > 0)) return std::nullopt;
  p.delay_samples = static_cast<int>(delay);
  for (int i = 1; i <= static_cast<int>(modes); ++i) {
    const std::string k = "mode" + std::to_string(i) + "_";
    p.modes.push_back({Cell(r, k + "omega"), Cell(r, k + "c"), Cell(r, k + "v"), Cell(r, k + "d")});
  }
  std::string why;
  if (!p.IsValid(&why)) return std::nullopt;
  *period_s = model::SamplePeriod(rate);
  return p;
}

// K_CR(B) on the paper's loop at `delay` over bs; empty when the plant cannot be analysed.
std::vector<double> Region(const model::Plant& p, double period_s, int delay, const std::vector<double>& bs) {
  std::vector<double> k;
  try {
    const stability::ZWidth z(p, period_s, delay);
    for (double b : bs) k.push_back(z.At(b).K_cr);
  } catch (const std::exception&) {
    k.clear();
  }
  return k;
}

// The units the table's values are in: the ok units' "units" cell when they
// agree, else linear with the batch's --units linear or a linear design,
// else rotary (a table of an older zwidth wrote no units column).
const model::UnitLabels& TableUnits(const io::BatchTable& t, const io::Design* design, bool linear_flag,
                                    bool* mixed) {
  std::string seen;
  for (const Row& r : t.rows) {
    if (Get(r, "status") != "ok" || Get(r, "units").empty()) continue;
    if (seen.empty()) seen = Get(r, "units");
    else if (seen != Get(r, "units")) seen = "mixed";
  }
  *mixed = seen == "mixed";
  if (seen == "linear" || seen == "rotary") return model::Units(seen == "linear");
  return model::Units(linear_flag || (design && design->model.linear));
}

// A value column's unit: "m [kg]", "d2_K_cr_max [N/m]"; the column alone
// where it has none (a count, a distance).
std::string ColumnLabel(const std::string& c, const model::UnitLabels& u) {
  // The columns are analysis::IsValueColumn's: m, b, mode<i>_*, d<d>_<figure>.
  const char* unit = nullptr;
  if (c == "m") unit = u.m;
  else if (c == "b") unit = u.b;
  else if (c.starts_with("mode")) unit = "rad/s";
  else if (c.ends_with("_K_cr_at_zero_B") || c.ends_with("_K_cr_max")) unit = u.K;
  else if (c.ends_with("_B_t") || c.ends_with("_B_max") || c.ends_with("_B_max_from_zero")) unit = u.B;
  return unit ? c + " [" + unit + "]" : c;
}

// A plot's frame: data [x0, x1] x [y0, y1] on a w x h canvas with margins for the labels.
struct Frame {
  double x0, x1, y0, y1;
  double w = 430, h = 260, left = 76, right = 22, top = 12, bottom = 40;
  int x_ticks = 4;  // intervals between the x ticks (a narrow frame: 2)
  double X(double x) const { return left + (x - x0) / (x1 - x0) * (w - left - right); }
  double Y(double y) const { return h - bottom - (y - y0) / (y1 - y0) * (h - top - bottom); }
};

void Axes(const Frame& f, const std::string& xlabel, const std::string& ylabel, std::ostringstream& s) {
  s << "<rect x='" << f.left << "' y='" << f.top << "' width='" << f.w - f.left - f.right << "' height='"
    << f.h - f.top - f.bottom << "' fill='none' stroke='#444'/>\n";
  const double x_step = (f.x1 - f.x0) / f.x_ticks, y_step = (f.y1 - f.y0) / 4;
  const double x_reach = std::max(std::abs(f.x0), std::abs(f.x1)), y_reach = std::max(std::abs(f.y0), std::abs(f.y1));
  for (int i = 0; i <= f.x_ticks; ++i) {
    // The last x tick ends at the frame's right edge (centred, it left the canvas).
    const double x = f.x0 + x_step * i;
    s << "<text x='" << f.X(x) << "' y='" << f.h - f.bottom + 14 << "' font-size='10' text-anchor='"
      << (i == f.x_ticks ? "end" : "middle") << "'>" << Tick(x, x_step, x_reach) << "</text>\n";
  }
  for (int i = 0; i <= 4; ++i) {
    const double y = f.y0 + y_step * i;
    s << "<text x='" << f.left - 4 << "' y='" << f.Y(y) + 3 << "' font-size='10' text-anchor='end'>"
      << Tick(y, y_step, y_reach) << "</text>\n";
  }
  s << "<text x='" << (f.left + f.w - f.right) / 2 << "' y='" << f.h - 6 << "' font-size='11' text-anchor='middle'>"
    << HtmlEscaped(xlabel) << "</text>\n<text x='12' y='" << (f.top + f.h - f.bottom) / 2
    << "' font-size='11' text-anchor='middle' transform='rotate(-90 12 " << (f.top + f.h - f.bottom) / 2 << ")'>"
    << HtmlEscaped(ylabel) << "</text>\n";
}

std::string Polyline(const Frame& f, const std::vector<double>& xs, const std::vector<double>& ys, const char* style) {
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s << "<polyline fill='none' " << style << " points='";
  for (size_t i = 0; i < xs.size(); ++i) {
    if (!std::isfinite(ys[i])) continue;
    s << f.X(xs[i]) << "," << f.Y(std::clamp(ys[i], f.y0, f.y1)) << " ";
  }
  s << "'/>\n";
  return s.str();
}

// Every ok unit's K_CR(B) at `delay` (grey; outliers orange, failures red) and the design's (black, thick).
void RegionFigure(const io::BatchTable& t, const analysis::Population& pop, const io::Design* design, int delay,
                  const model::UnitLabels& u, std::ostringstream& h) {
  const std::string k = "d" + std::to_string(delay) + "_";
  std::vector<double> bmax, kmax;
  for (const Row& r : t.rows) {
    if (Get(r, "status") != "ok") continue;
    if (double b = Cell(r, k + "B_max_from_zero"); std::isfinite(b) && b > 0) bmax.push_back(b);
    if (double x = Cell(r, k + "K_cr_max"); std::isfinite(x) && x > 0) kmax.push_back(x);
  }
  std::optional<model::Plant> dp;
  double dT = 1e-3;
  if (design) {
    io::ModelFile m = design->model;
    std::string note;
    try {
      dT = io::ResolveModelPeriod(std::nullopt, &m, &note);
      dp = m.plant;
    } catch (const std::exception&) {
    }
  }
  if (bmax.empty() || kmax.empty()) return;
  std::sort(bmax.begin(), bmax.end());
  std::sort(kmax.begin(), kmax.end());
  // The axes: 2 x the units' median (a wild unit does not squash the others; it leaves the frame).
  Frame f{0, 2.0 * bmax[bmax.size() / 2], 0, 2.0 * kmax[kmax.size() / 2]};
  std::vector<double> bs;
  for (int i = 0; i <= 60; ++i) bs.push_back(f.x1 * i / 60);
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << f.w << "' height='" << f.h << "' viewBox='0 0 " << f.w
    << " " << f.h << "'>\n";
  Axes(f, std::string("B [") + u.B + "]", std::string("K_CR [") + u.K + "], delay " + std::to_string(delay), s);
  std::string bad;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const Row& r = t.rows[i];
    if (Get(r, "status") != "ok") continue;
    double T = 0;
    const std::optional<model::Plant> p = PlantOf(r, &T);
    if (!p) continue;
    const std::vector<double> kc = Region(*p, T, delay, bs);
    if (kc.empty()) continue;
    const bool outlier = i < pop.units.size() && pop.units[i].outlier, fail = Get(r, "verdict") == "fail";
    const std::string line = Polyline(f, bs, kc, fail ? "stroke='#c0282b' stroke-width='1.2'"
                                                 : outlier ? "stroke='#e08a00' stroke-width='1.2'"
                                                           : "stroke='#8899aa' stroke-opacity='0.35' stroke-width='1'");
    if (fail || outlier) bad += line; else s << line;
  }
  s << bad;  // drawn over the others
  if (dp) {
    const std::vector<double> kc = Region(*dp, dT, delay, bs);
    if (!kc.empty()) s << Polyline(f, bs, kc, "stroke='#000' stroke-width='2.5'");
  }
  s << "</svg>\n";
  h << "<div class='figure'>" << s.str() << "<br><small>Delay " << delay << ": every unit's K_CR(B) (grey; "
    << "outliers orange, failures red)" << (dp ? ", the design's (black)" : "") << "; stable below the curve.</small></div>\n";
}

// A histogram of one column over the ok units, with its median (blue), +-1 MAD sigma (shaded)
// and the specs' bounds (red dashes), over a robust range (report/histogram.h): a wild unit is
// a labelled count beyond the edge (orange), not the axis' end.
void Histogram(const io::BatchTable& t, const analysis::PopulationColumn& c, const std::vector<analysis::BatchSpec>& specs,
               const model::UnitLabels& u, std::ostringstream& h) {
  std::vector<double> v;
  for (const Row& r : t.rows) {
    if (Get(r, "status") != "ok") continue;
    if (double x = Cell(r, c.column); std::isfinite(x)) v.push_back(x);
  }
  if (v.size() < 2) return;
  std::vector<double> marks;
  for (const analysis::BatchSpec& s : specs) if (s.column == c.column) marks.push_back(s.bound);
  const HistogramBins hb = RobustHistogram(v, c.median, c.mad_sigma, marks);
  const double lo = hb.lo, hi = hb.hi;
  const int bins = static_cast<int>(hb.counts.size());
  // Counts: the 4 ticks on whole units (the top a multiple of 4 above the tallest bin).
  if (hb.counts.empty()) return;
  const int tallest = *std::max_element(hb.counts.begin(), hb.counts.end());
  Frame f{lo, hi, 0, 4.0 * std::ceil((tallest + 1) / 4.0)};
  f.w = 300, f.h = 180, f.x_ticks = 2;
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << f.w << "' height='" << f.h << "'>\n";
  const double band0 = std::clamp(c.median - c.mad_sigma, lo, hi), band1 = std::clamp(c.median + c.mad_sigma, lo, hi);
  s << "<rect x='" << f.X(band0) << "' y='" << f.top << "' width='" << std::max(0.0, f.X(band1) - f.X(band0))
    << "' height='" << f.h - f.top - f.bottom << "' fill='#cde' />\n";
  for (int i = 0; i < bins; ++i) {
    if (!hb.counts[i]) continue;
    const double x0 = lo + (hi - lo) * i / bins, x1 = lo + (hi - lo) * (i + 1) / bins;
    s << "<rect x='" << f.X(x0) << "' y='" << f.Y(hb.counts[i]) << "' width='" << f.X(x1) - f.X(x0) << "' height='"
      << f.Y(0) - f.Y(hb.counts[i]) << "' fill='#557' />\n";
  }
  auto vline = [&](double x, const char* style) {
    if (x < lo || x > hi) return;
    s << "<line x1='" << f.X(x) << "' x2='" << f.X(x) << "' y1='" << f.top << "' y2='" << f.Y(0) << "' " << style << "/>\n";
  };
  vline(c.median, "stroke='#06c' stroke-width='2'");
  for (double m : marks) vline(m, "stroke='#c0282b' stroke-width='1.5' stroke-dasharray='4,3'");
  // The units beyond the range, at its edges.
  if (hb.below) {
    s << "<text x='" << f.left + 3 << "' y='" << f.top + 11 << "' font-size='10' fill='#e08a00'>&#9664; " << hb.below
      << " below</text>\n";
  }
  if (hb.above) {
    s << "<text x='" << f.w - f.right - 3 << "' y='" << f.top + 11 << "' font-size='10' fill='#e08a00' "
      << "text-anchor='end'>" << hb.above << " above &#9654;</text>\n";
  }
  Axes(f, ColumnLabel(c.column, u), "units", s);
  s << "</svg>";
  std::string note;
  if (hb.below) note += std::to_string(hb.below) + " below the range (min " + Num(hb.min) + ")";
  if (hb.above) note += (note.empty() ? "" : ", ") + std::to_string(hb.above) + " above it (max " + Num(hb.max) + ")";
  for (double m : marks) {
    if (m < lo || m > hi) note += (note.empty() ? "" : ", ") + std::string("spec bound ") + Num(m) + " off the axis";
  }
  h << "<div class='hist'>" << s.str() << (note.empty() ? "" : "<br><small>" + HtmlEscaped(note) + "</small>")
    << "</div>\n";
}

}  // namespace

std::string FleetHtml(const io::BatchTable& t, const analysis::Population& pop, const io::Design* design,
                      const analysis::BatchOptions& options, const std::string& command_line) {
  std::ostringstream h;
  h.imbue(std::locale::classic());
  std::map<std::string, int> verdicts;
  size_t errors = 0, outliers = 0;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    verdicts[Get(t.rows[i], "verdict")]++;
    errors += Get(t.rows[i], "status") != "ok";
    outliers += i < pop.units.size() && pop.units[i].outlier;
  }
  const std::string title = design && !design->name.empty() ? "zwidth fleet report: " + design->name : "zwidth fleet report";
  h << "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>" << HtmlEscaped(title) << "</title><style>"
    << ReportStyle() << ".hist{display:inline-block;margin:2px}table.zw td.l{text-align:left}</style></head><body>\n<h1>"
    << HtmlEscaped(title) << "</h1>\n";
  const bool good = errors == 0 && verdicts["fail"] == 0 && outliers == 0;
  h << "<div class='verdict " << (good ? "good" : "poor") << "'><b>" << t.rows.size() << " units</b>: "
    << t.rows.size() - errors << " analysed, " << errors << " failed to analyse";
  if (!options.specs.empty()) {
    h << "; verdicts: " << verdicts["pass"] << " pass, " << verdicts["marginal"] << " marginal, " << verdicts["fail"]
      << " fail";
  }
  h << "; " << outliers << " outlier(s) of the population";
  if (pop.status != analysis::PopulationStatus::kOk) h << " (" << HtmlEscaped(pop.message) << ")";
  h << ".</div>\n";
  // Failures and outliers.
  h << "<h2>Failures and outliers</h2>\n<table class='zw'><tr><th>serial</th><th>status</th><th>verdict</th>"
    << "<th>outlier D&sup2;</th><th>reasons</th></tr>\n";
  size_t listed = 0;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const Row& r = t.rows[i];
    const bool outlier = i < pop.units.size() && pop.units[i].outlier;
    const std::string v = Get(r, "verdict");
    if (Get(r, "status") == "ok" && v != "fail" && v != "marginal" && !outlier) continue;
    ++listed;
    std::string why = Get(r, "error");
    for (const std::string& x : {Get(r, "verdict_reasons"), outlier ? "outlier: " + pop.units[i].reasons : std::string()}) {
      if (!x.empty()) why += (why.empty() ? "" : "<br>") + HtmlEscaped(x);
    }
    h << "<tr><td class='l'>" << HtmlEscaped(Get(r, "serial")) << "</td><td>" << HtmlEscaped(Get(r, "status"))
      << "</td><td>" << HtmlEscaped(v) << "</td><td>"
      << (i < pop.units.size() && std::isfinite(pop.units[i].distance2) ? Num(pop.units[i].distance2) : "")
      << "</td><td class='l'>" << (Get(r, "error").empty() ? why : HtmlEscaped(Get(r, "error"))) << "</td></tr>\n";
  }
  h << "</table>\n";
  if (!listed) h << "<p>None: every unit analysed, passed and lies within its population.</p>\n";
  h << "<p>Outlier: robust Mahalanobis D&sup2; (population median and Gnanadesikan-Kettenring covariance from MADs, "
    << "plus the unit's own variance) above " << Num(pop.threshold) << ", chi-square's quantile for "
    << pop.distance_columns.size() << " columns; or another number of modes than the population's (docs/fleet.md).</p>\n";
  // Regions.
  h << "<h2>Regions</h2>\n";
  bool mixed = false;
  const model::UnitLabels& units = TableUnits(t, design, options.run.linear, &mixed);
  if (mixed) {
    h << "<p><b>The units mix rotary and linear axes</b> (the table's <code>units</code> column): their values "
      << "share these axes and the population's statistics, which then mean nothing; batch each kind apart. "
      << "The axes below are labelled " << units.word << ".</p>\n";
  }
  for (int d : options.run.delays) RegionFigure(t, pop, design, d, units, h);
  // Distributions and the population table.
  h << "<h2>Distributions</h2>\n<p>Over the analysed units: blue line the median, shaded &plusmn;1 MAD sigma, red "
    << "dashes the specs' bounds; the axis spans the median &plusmn; "
    << Num(HistogramOptions{}.mad_multiple) << " MAD sigma (clipped to the values), the "
    << "units beyond it are counted at its edges (orange).</p>\n";
  for (const analysis::PopulationColumn& c : pop.columns) Histogram(t, c, options.specs, units, h);
  h << "<h2>Population</h2>\n<table class='zw'><tr><th>column</th><th>units</th><th>median</th><th>MAD sigma</th>"
    << "<th>min</th><th>max</th><th>in D&sup2;</th></tr>\n";
  for (const analysis::PopulationColumn& c : pop.columns) {
    h << "<tr><td class='l'>" << HtmlEscaped(ColumnLabel(c.column, units)) << "</td><td>" << c.units << "</td><td>" << Num(c.median)
      << "</td><td>" << Num(c.mad_sigma) << "</td><td>" << Num(c.min) << "</td><td>" << Num(c.max) << "</td><td>"
      << (c.in_distance ? "yes" : "no") << "</td></tr>\n";
  }
  h << "</table>\n";
  const nlohmann::json p = io::ProvenanceJson();
  h << "<h2>Provenance</h2>\n<p class='provenance'>zwidth " << HtmlEscaped(p["zwidth_version"].get<std::string>())
    << ", written " << HtmlEscaped(p["utc_date"].get<std::string>())
    << (command_line.empty() ? "" : "; command: <code>" + HtmlEscaped(command_line) + "</code>")
    << (design ? "; design model: <code>" + HtmlEscaped(design->model_name) + "</code>" : "") << ".</p>\n";
  h << "</body></html>\n";
  return h.str();
}

}  // namespace zwidth::report
