// report.html of `zwidth run`: one self-contained file. The answer first (the
// verdict, the Z-width table with units, the region figure), the details
// after; the gnuplot figures inlined as SVG elements (their ids prefixed per
// figure, since gnuplot names its markers alike in every file), and, when
// libjs-dygraphs was found at build time, interactive figures (zoom, values
// on hover, +-2 sigma bands as dygraphs' custom bars) drawn by the inlined
// library from data inlined as JSON. Nothing is loaded from elsewhere, so the
// file works alone, offline, e-mailed or printed.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <locale>
#include <ctime>
#include <map>
#include <set>
#include <numbers>
#include <sstream>
#include <string_view>

#include <nlohmann/json.hpp>

#include "analysis/compare.h"
#include "io/provenance.h"
#include "io/stability_files.h"
#include "model/units.h"
#include "report/report_internal.h"

namespace zwidth::report {
namespace internal {
extern const std::string_view kDygraphJs;   // empty when libjs-dygraphs was absent at build time
extern const std::string_view kDygraphCss;
}  // namespace internal
namespace {

std::string Html(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;"; else if (c == '>') o += "&gt;"; else if (c == '&') o += "&amp;"; else o += c;
  }
  return o;
}

std::string Num(double v, const char* fmt = "%.5g") {
  char b[64];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

const char* kStyle = R"css(
body{font-family:sans-serif;max-width:1000px;margin:auto;padding:0 12px;color:#111}
pre{background:#f4f4f4;padding:8px;white-space:pre-wrap;overflow-wrap:anywhere}
.verdict{padding:10px 14px;border-radius:6px;margin:12px 0;font-size:1.15em}
.verdict.good{background:#e5f5e5;border:2px solid #2a8a2a}
.verdict.poor{background:#fde8e8;border:3px solid #c0282b}
.verdict.poor b{color:#c0282b}
table.zw{border-collapse:collapse;margin:8px 0}
table.zw th,table.zw td{border:1px solid #bbb;padding:4px 8px;text-align:right}
table.zw th{background:#eee}
.figure{margin:10px 0}
.figure svg{max-width:100%;height:auto}
.chart{width:100%;height:360px}
.provenance{font-size:.85em;color:#444}
table,.figure,pre,.verdict{break-inside:avoid;page-break-inside:avoid}
h2{break-after:avoid;page-break-after:avoid}
@media print{.chart,.interactive{display:none}body{max-width:none}}
)css";

// A gnuplot SVG as an element of the page: the XML prolog and DOCTYPE cut,
// every id (and every reference to one) prefixed with `prefix`.
std::string InlineSvg(const std::string& svg, const std::string& prefix) {
  const size_t start = svg.find("<svg");
  if (start == std::string::npos) return "";
  std::string s = svg.substr(start);
  std::set<std::string> known;  // the figure's own ids
  for (size_t p = s.find(" id="); p != std::string::npos; p = s.find(" id=", p + 4)) {
    const char q = p + 4 < s.size() ? s[p + 4] : '\0';
    if (q != '\'' && q != '"') continue;
    const size_t e = s.find(q, p + 5);
    if (e == std::string::npos) break;
    known.insert(s.substr(p + 5, e - p - 5));
  }
  std::string out;
  out.reserve(s.size() + known.size() * 8);
  // One pass: an id='X' or a #X reference to a known id gets the prefix.
  for (size_t i = 0; i < s.size(); ++i) {
    const bool id_attr = s.compare(i, 5, " id='") == 0 || s.compare(i, 5, " id=\"") == 0;
    if (id_attr || s[i] == '#') {
      const size_t from = id_attr ? i + 5 : i + 1;
      size_t e = from;
      while (e < s.size() && (std::isalnum(static_cast<unsigned char>(s[e])) || s[e] == '_' || s[e] == '-')) ++e;
      if (e > from && known.contains(s.substr(from, e - from))) {
        out.append(s, i, from - i);
        out += prefix;
        i = from - 1;
        continue;
      }
    }
    out += s[i];
  }
  return out;
}

void Figure(const std::map<std::string, std::string>& svgs, const std::string& name, const std::string& caption,
            std::ostringstream& h) {
  auto it = svgs.find(name);
  if (it == svgs.end()) return;
  h << "<div class='figure' id='figure-" << name << "'>" << InlineSvg(it->second, "f" + name + "_")
    << (caption.empty() ? "" : "<p>" + caption + "</p>") << "</div>\n";
}

// The verdict, first and marked.
void VerdictSection(const analysis::RunAnalysis& a, std::ostringstream& h) {
  const fit::FitResult& fr = a.input.fit;
  const bool good = fr.quality == fit::FitQuality::kGood;
  h << "<div class='verdict " << (good ? "good" : "poor") << "' id='verdict'><b>Fit quality: "
    << (good ? "good" : "POOR") << "</b>";
  if (!good) {
    h << ": the Z-width below comes from a model that does not explain the log; do not rely on it.<ul>";
    for (const auto& r : a.input.model.fit.value("quality_reasons", nlohmann::json::array())) {
      h << "<li>" << Html(r.is_string() ? r.get<std::string>() : r.dump()) << "</li>";
    }
    h << "</ul>See the fit's report below for its reasons and advice.";
  }
  h << "</div>\n";
}

std::string PlusMinus(double v, double sd) {
  return std::isfinite(sd) ? Num(v) + " &plusmn; " + Num(sd, "%.2g") : Num(v);
}

// The Z-width table: one row per delay, units in the header, reopened bands below.
void ZWidthTable(const analysis::RunAnalysis& a, std::ostringstream& h) {
  const analysis::PlantStability& st = a.stability;
  const model::UnitLabels& u = model::Units(a.options.linear);
  h << "<table class='zw' id='zwidth-table'><tr><th>loop delay + model delay = total [samples]</th><th>K_CR(B = 0) [" << u.K
    << "]</th><th>B_t [" << u.B << "]</th><th>K_CR^max [" << u.K << "]</th><th>B_max_from_zero [" << u.B
    << "]</th><th>B_max [" << u.B << "]</th></tr>\n";
  for (size_t i = 0; i < st.summaries.size(); ++i) {
    const auto& s = st.summaries[i];
    const auto& sd = st.stds[i];
    h << "<tr><td>" << io::DelayText(st.delays[i], a.input.model.plant.delay_samples) << "</td><td>" << PlusMinus(s.K_cr_at_zero_B, sd.K_cr_at_zero_B) << "</td><td>"
      << PlusMinus(s.B_t, sd.B_t) << "</td><td>" << PlusMinus(s.K_cr_max, sd.K_cr_max) << "</td><td>"
      << Num(s.B_max_from_zero) << "</td><td>" << PlusMinus(s.B_max, sd.B_max) << "</td></tr>\n";
    for (const auto& band : s.reopened_bands) {
      h << "<tr><td></td><td colspan='5' style='text-align:left'>reopened band: B in (" << Num(band.B_lo) << ", "
        << Num(band.B_hi) << ") " << u.B << ", largest stable K " << Num(band.K_max) << " " << u.K << "</td></tr>\n";
    }
    for (const auto& j : s.frequency_jumps) {
      h << "<tr><td></td><td colspan='5' style='text-align:left'>f_CR jumps at B = " << Num(j.B) << " " << u.B
        << ": K_CR " << Num(j.K_before) << " &rarr; " << Num(j.K_after) << " " << u.K << ", f_CR "
        << Num(j.f_before_hz) << " &rarr; " << Num(j.f_after_hz) << " Hz" << (j.B == s.B_t ? " (B_t)" : "")
        << "</td></tr>\n";
    }
  }
  h << "</table>\n<p>B_t: where K_CR(B) peaks and the critical frequency f_CR jumps (the paper's section III); "
       "every jump of f_CR is listed under its delay.</p>\n";
}

// The loop a table was computed on, in words.
std::string LoopDescription(const stability::LoopOptions& l) {
  if (!l.HasFilter() && l.hand.IsNone()) return "the paper's loop: raw backward difference, nobody holding the device";
  std::ostringstream d;
  d.imbue(std::locale::classic());
  d.precision(6);
  if (l.HasFilter()) {
    d << "velocity filter F(z) with b =";
    for (double x : l.filter_b) d << " " << x;
    d << ", a =";
    for (double x : l.filter_a) d << " " << x;
  } else {
    d << "raw backward difference";
  }
  if (!l.hand.IsNone()) d << "; hand M = " << l.hand.M << ", B = " << l.hand.B << ", K = " << l.hand.K;
  else d << "; nobody holding the device";
  return d.str();
}

void ZWidthSection(const analysis::RunAnalysis& a, std::ostringstream& h) {
  const analysis::PlantStability& st = a.stability;
  h << "<h2>Z-width (eq. 2)</h2>\n<p>On " << Html(LoopDescription(a.options.loop)) << ".</p>\n";
  ZWidthTable(a, h);
  h << "<p>K_CR(B): the largest K of the stable interval from K = 0+ at damping B; B_max_from_zero: where that "
    << "interval closes (the paper's B_max); B_max: the largest B at which some K &gt; 0 is stable. "
    << "&plusmn; one std by the delta method from the fit's parameter covariance"
    << (st.has_std ? "" : " (not available: the fit has no covariance)")
    << ". boundary.csv lists every stable K interval per B.</p>\n";
  if (!st.friction_amplitudes.empty()) {
    h << "<p>Friction (Coulomb " << a.input.model.friction->MeanCoulomb() << " " << model::Units(a.options.linear).input
      << " at the motor): outside the linear "
      << "Z-width a wall is still stable for oscillations below the describing-function amplitude A* "
      << "(docs/friction.md; boundary.csv's A_star column):</p>\n<ul>\n";
    for (int d : st.delays) {
      h << "<li>" << Html(analysis::FrictionSummaryLine(st.friction_amplitudes, d, st.friction_options, model::Units(a.options.linear))) << "</li>\n";
    }
    h << "</ul>\n";
  }
}

// The interactive figures' data: the Bode magnitude and phase (measured in the
// bins the fit used, +-2 std; model +-2 std) and K_CR(B) per delay (+-2 std).
nlohmann::json ChartData(const analysis::RunAnalysis& a) {
  using nlohmann::json;
  const ident::FrequencyResponse& frf = a.input.response.frf;
  const analysis::BodeData& bd = a.figures->bode;
  const bool band = !bd.G_log_abs_std.empty();
  json mag = json::array(), ph = json::array();
  auto bar = [](double lo, double mid, double hi) {
    return std::isfinite(mid) ? json::array({lo, mid, hi}) : json(nullptr);
  };
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    const bool used = k < frf.used_by_fit.size() && frf.used_by_fit[k];
    const double sd = k < frf.H_std.size() ? frf.H_std[k] : 0.0;
    const double hm = bd.H_abs[k];
    const double hs = sd / std::max(hm, 1e-300) * 180 / std::numbers::pi;  // phase std of the measured [deg]
    const double gl = band ? bd.G_log_abs_std[k] : 0.0, gp = band ? bd.G_phase_std_deg[k] : 0.0;
    mag.push_back({frf.f_hz[k], used ? bar(std::max(hm - 2 * sd, hm * 1e-3), hm, hm + 2 * sd) : json(nullptr),
                   bar(bd.G_abs[k] * std::exp(-2 * gl), bd.G_abs[k], bd.G_abs[k] * std::exp(2 * gl))});
    ph.push_back({frf.f_hz[k], used ? bar(bd.H_phase_deg[k] - 2 * hs, bd.H_phase_deg[k], bd.H_phase_deg[k] + 2 * hs)
                                    : json(nullptr),
                  bar(bd.G_phase_deg[k] - 2 * gp, bd.G_phase_deg[k], bd.G_phase_deg[k] + 2 * gp)});
  }
  const analysis::PlantStability& st = a.stability;
  const size_t nB = st.b_grid.size();
  json kcr = json::array();
  json labels = json::array({"B"});
  for (int d : st.delays) labels.push_back("delay " + std::to_string(d));
  for (size_t k = 0; k < nB; ++k) {
    json row = json::array({st.b_grid[k]});
    for (size_t i = 0; i < st.delays.size(); ++i) {
      const io::BoundaryRow& r = st.rows[i * nB + k];
      const double K = r.point.K_cr, s = std::isfinite(r.K_cr_std) ? r.K_cr_std : 0.0;
      row.push_back(std::isfinite(K) ? json::array({std::max(K - 2 * s, 0.0), K, K + 2 * s}) : json(nullptr));
    }
    kcr.push_back(row);
  }
  const model::UnitLabels& u = model::Units(a.options.linear);
  return {{"mag", mag},
          {"phase", ph},
          {"kcr", kcr},
          {"kcr_labels", labels},
          {"units", {{"K", u.K}, {"B", u.B}, {"H", u.H}}},
          {"model_band", band}};
}

// Draws the charts of ChartData with dygraphs: log axes for the Bode
// magnitude, custom bars (low, value, high) for every +-2 std band.
const char* kChartScript = R"js(
(function(){
var d=JSON.parse(document.getElementById('zwidth-chart-data').textContent);
function g(id,rows,labels,opt){var el=document.getElementById(id);if(!el)return;
 var o={labels:labels,customBars:true,legend:'always',labelsSeparateLines:true,connectSeparatedPoints:false};
 for(var k in opt)o[k]=opt[k];el.zwidthGraph=new Dygraph(el,rows,o);}
// Tick labels of 2 significant digits, in exponent form past 1e-3..1e4 (toPrecision
// alone writes 5e-5 as 0.000050, wider than the axis's label column).
var e3=function(v){var a=Math.abs(v);return a!==0&&(a<1e-3||a>=1e4)?Number(v).toExponential(1):Number(v).toPrecision(2);};
g('chart-bode-mag',d.mag,['f [Hz]','measured','model'],{logscale:true,axes:{x:{logscale:true},
 y:{axisLabelFormatter:e3,valueFormatter:function(v){return Number(v).toPrecision(5);},pixelsPerLabel:40,axisLabelWidth:60}},
 xlabel:'f [Hz]',ylabel:'|H| ['+d.units.H+']',drawPoints:true,strokeWidth:1,series:{measured:{strokeWidth:0,pointSize:2}}});
g('chart-bode-phase',d.phase,['f [Hz]','measured','model'],{axes:{x:{logscale:true}},xlabel:'f [Hz]',
 ylabel:'phase [deg]',drawPoints:true,strokeWidth:1,series:{measured:{strokeWidth:0,pointSize:2}}});
g('chart-kcr',d.kcr,d.kcr_labels,{xlabel:'B ['+d.units.B+']',ylabel:'K_CR ['+d.units.K+']',
 axes:{y:{axisLabelFormatter:e3,axisLabelWidth:60}}});
})();
)js";

void InteractiveSection(const analysis::RunAnalysis& a, std::ostringstream& h) {
  if (!a.figures) return;
  if (internal::kDygraphJs.empty()) {
    h << "<p class='interactive'>No interactive figures: zwidth was built without libjs-dygraphs.</p>\n";
    return;
  }
  h << "<h2 class='interactive'>Interactive figures</h2>\n<p class='interactive'>Drag to zoom, double-click to "
    << "reset, hover for values. Shaded: &plusmn;2 std (the measured response's per-bin std; the model's from its "
    << "parameter covariance" << (a.figures->bode.G_log_abs_std.empty() ? ", not available for this model" : "")
    << "; K_CR's by the delta method).</p>\n"
    << "<div class='chart interactive' id='chart-kcr'></div>\n<div class='chart interactive' id='chart-bode-mag'>"
    << "</div>\n<div class='chart interactive' id='chart-bode-phase'></div>\n";
  std::string data = ChartData(a).dump();
  // JSON inside <script>: "</" would end the element.
  for (size_t p = data.find("</"); p != std::string::npos; p = data.find("</", p)) data.replace(p, 2, "<\\/");
  h << "<script type='application/json' id='zwidth-chart-data'>" << data << "</script>\n<script>"
    << internal::kDygraphJs << "</script>\n<script>" << kChartScript << "</script>\n";
}

void FitSection(const analysis::RunAnalysis& a, const std::string& fit_report, std::ostringstream& h) {
  const fit::FitResult& fr = a.input.fit;
  const ident::FrequencyResponse& frf = a.input.response.frf;
  h << "<h2>Fit</h2>\n<pre>" << Html(fit_report.empty() ? analysis::FitReport(fr) : fit_report) << "</pre>\n"
    << "<p>Log <code>" << Html(a.input.source) << "</code>: " << a.input.total_samples << " samples at "
    << frf.sample_rate_hz << " Hz; "
    << (frf.error_correlation.empty()
            ? "Welch " + std::to_string(frf.num_averages) + " averages of " + std::to_string(frf.window_length) + " samples"
            : "local model per bin, " + std::to_string(frf.num_averages) + " residual degrees of freedom")
    << "; " << Html(ident::ToString(a.input.response.method)) << " (estimator " << Html(frf.estimator) << "); "
    << frf.f_hz.size() << " bins from "
    << frf.f_hz.front() << " to " << frf.f_hz.back() << " Hz.</p>\n<h2>Fitted model (eq. 1)</h2>\n<pre>"
    << Html(analysis::ParameterTable(a.input.model, a.options.linear)) << "</pre>\n<p>" << Html(fr.BriefReport())
    << ". Residual: exact ZOH response weighted by the Welch per-bin std. "
    << "Sections in canonical order (pole pairs by omega, zero pairs by v).</p>\n";
  for (const auto& w : fr.warnings) h << "<p><b>Warning:</b> " << Html(w) << "</p>\n";
}

// The comparison and the margin note.
void ComparisonSection(const analysis::RunAnalysis& a, std::ostringstream& h) {
  const analysis::PlantStability& st = a.stability;
  const bool own_loop = a.options.loop.HasFilter() || !a.options.loop.hand.IsNone();
  if (a.comparison) {
    h << "<h2>Comparison with the reference ("
      << Html(a.input.reference_is_table1 ? "Table I, built in" : a.input.reference_name) << ")</h2>\n"
      << (own_loop ? "<p>Both models on the paper's loop (raw backward difference, nobody holding the device), as the "
                     "reference was measured; the Z-width above is on this run's loop.</p>\n"
                   : "")
      << "<pre>" << Html(a.comparison->text) << "</pre>\n";
  } else {
    h << "<p>No reference comparison (pass <code>--reference table1</code> or a model JSON to compare).</p>\n";
  }
  h << "<p>The paper's gain-margin reading of eq. (4) differs from the exact K_CR in " << st.margin_disagreements
    << " of " << st.rows.size() << " B values: mostly past B_max_from_zero, where margin() stays positive although K -> 0+ is unstable "
    << "(see boundary.csv, column margin_agrees).</p>\n";
}

// The delays of the Z-width figures: each loop delay, the model's, their sum.
std::string DelayCaption(const analysis::RunAnalysis& a) {
  std::string c = "Delays:";
  for (size_t i = 0; i < a.options.delays.size(); ++i) {
    c += (i ? "; " : " ") + io::DelayText(a.options.delays[i], a.input.model.plant.delay_samples);
  }
  return c + " (the loop's, the fitted model's input delay, and the total the Z-width is computed for).";
}

std::string LoopCaption(const analysis::RunAnalysis& a) {
  std::ostringstream c;
  c.imbue(std::locale::classic());
  c << "Blue: the (B, K) the device renders stably with the raw backward difference; orange: with a "
    << a.options.report_filter_hz << " Hz first-order velocity low-pass. Lines: the passivity boundary K_P(B) "
    << "(Colgate and Schenkel, with the model's damping b = " << a.input.model.plant.b << "): below it the wall stays "
    << "passive, so it stays stable against any passive hand, which the stable region alone does not promise "
    << (a.options.loop.hand.IsNone() ? "(it assumes nobody holds the device)"
                                     : "(it assumes the run's hand, in both colours)")
    << ". Passivity is bounded by the physical damping b (for the rigid "
    << "body without delay or filter: b > K T/2 + |B|), so on a lightly damped device its region hugs the "
    << "origin: rendering beyond it relies on the stable region and on the hand being no worse than assumed.";
  return c.str();
}

void NoFiguresNote(const analysis::RunAnalysis& a, bool have_figures, std::ostringstream& h) {
  if (have_figures) return;
  if (!a.figures) {
    h << "<p>No figures (<code>--no-figures</code>).</p>\n";
  } else {
    h << "<p>No static figures: they need gnuplot (Debian package <code>gnuplot-nox</code>): install it and run "
      << "<code>cd figures && gnuplot figures.gp</code>, or rerun zwidth run.</p>\n";
  }
}

// The provenance every JSON file carries (io/provenance.h), with the inputs' SHA-256.
void ProvenanceSection(const analysis::RunAnalysis& a, const std::string& command_line, std::ostringstream& h) {
  const nlohmann::json p = io::ProvenanceJson();
  const std::string command = command_line.empty() ? p["command"].get<std::string>() : command_line;
  h << "<h2>Provenance</h2>\n<p class='provenance'>zwidth " << Html(p["zwidth_version"].get<std::string>())
    << ", report written " << Html(p["utc_date"].get<std::string>())
    << (command.empty() ? "" : "; command: <code>" + Html(command) + "</code>") << "; logs:";
  for (const auto& l : a.input.logs) h << " <code>" << Html(l) << "</code>";
  h << ".</p>\n";
  if (!p["inputs"].empty()) {
    h << "<p class='provenance'>inputs (SHA-256):";
    for (const auto& in : p["inputs"]) {
      h << " <code>" << Html(in["path"].get<std::string>()) << "</code> " << Html(in["sha256"].get<std::string>()) << ";";
    }
    h << "</p>\n";
  }
}

}  // namespace

std::string HtmlEscaped(const std::string& s) { return Html(s); }
std::string ReportStyle() { return kStyle; }

std::string RunHtml(const analysis::RunAnalysis& a, const std::map<std::string, std::string>& svgs,
                    const std::string& fit_report, const std::string& command_line) {
  std::ostringstream h;
  h.imbue(std::locale::classic());  // '.' decimals, no grouping, whatever std::locale::global says
  h << "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>zwidth report</title><style>" << kStyle
    << internal::kDygraphCss << "</style></head><body>\n<h1>zwidth report</h1>\n";
  VerdictSection(a, h);
  ZWidthSection(a, h);
  Figure(svgs, "region", Html(DelayCaption(a)), h);
  InteractiveSection(a, h);
  NoFiguresNote(a, !svgs.empty(), h);
  FitSection(a, fit_report, h);
  Figure(svgs, "bode", "", h);
  Figure(svgs, "coherence", "", h);
  ComparisonSection(a, h);
  if (a.table2) {
    h << "<h2>Table II: the paper's relay points</h2>\n<p>The relay experiment's measured points beside this "
      << "model's linear Z-width and its relay simulated with Coulomb friction (docs/friction.md):</p>\n<pre>"
      << Html(analysis::Table2Text(*a.table2)) << "</pre>\n";
  }
  Figure(svgs, "kcr", Html(DelayCaption(a)), h);
  Figure(svgs, "loop", Html(LoopCaption(a)), h);
  Figure(svgs, "rigid", "", h);
  ProvenanceSection(a, command_line, h);
  h << "</body></html>\n";
  return h.str();
}

}  // namespace zwidth::report
