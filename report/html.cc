// report.html of `zwidth run`.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "analysis/compare.h"
#include "report/report_internal.h"

namespace zwidth::report {
namespace {

std::string Html(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;"; else if (c == '>') o += "&gt;"; else if (c == '&') o += "&amp;"; else o += c;
  }
  return o;
}

// The verdict, the estimate and the fitted model.
void FitSection(const analysis::RunAnalysis& a, const std::string& fit_report, std::ostringstream& h) {
  const fit::FitResult& fr = a.input.fit;
  const ident::FrequencyResponse& frf = a.input.response.frf;
  h << "<p><b>Fit quality: " << fit::ToString(fr.quality) << "</b>"
    << (fr.quality == fit::FitQuality::kGood ? "" : ": the Z-width below comes from a model that does not explain the log; do not rely on it") << "</p>\n<pre>" << Html(fit_report.empty() ? analysis::FitReport(fr) : fit_report) << "</pre>\n"
    << "<p>Log <code>" << Html(a.input.source) << "</code>: " << a.input.total_samples << " samples at "
    << frf.sample_rate_hz << " Hz; "
    << (frf.error_correlation.empty()
            ? "Welch " + std::to_string(frf.num_averages) + " averages of " + std::to_string(frf.window_length) + " samples"
            : "local model per bin, " + std::to_string(frf.num_averages) + " residual degrees of freedom")
    << "; " << Html(ident::ToString(a.input.response.method)) << " (estimator " << Html(frf.estimator) << ")" << "; " << frf.f_hz.size() << " bins from " << frf.f_hz.front() << " to " << frf.f_hz.back()
    << " Hz.</p>\n<h2>Fitted model (eq. 1)</h2>\n<pre>" << Html(analysis::ParameterTable(a.input.model, a.options.linear)) << "</pre>\n<p>"
    << Html(fr.BriefReport()) << ". Residual: exact ZOH response weighted by the Welch per-bin std. "
    << "Sections in canonical order (pole pairs by omega, zero pairs by v).</p>\n";
  for (const auto& w : fr.warnings) h << "<p><b>Warning:</b> " << Html(w) << "</p>\n";
}

// The Z-width table: one line per delay, its reopened bands below it.
std::string ZWidthTable(const analysis::PlantStability& st) {
  std::ostringstream z;
  char line[256];
  std::snprintf(line, sizeof line, "%-6s %18s %18s %18s %12s %18s\n", "delay", "K_cr(B=0)", "B_t", "K_cr^max",
                "B_max_0", "B_max");
  z << line;
  auto pm = [&](double v, double sd) {
    char b[64];
    if (std::isfinite(sd)) std::snprintf(b, sizeof b, "%.5g +- %.2g", v, sd);
    else std::snprintf(b, sizeof b, "%.5g", v);
    return std::string(b);
  };
  for (size_t i = 0; i < st.summaries.size(); ++i) {
    const auto& s = st.summaries[i];
    const auto& sd = st.stds[i];
    std::snprintf(line, sizeof line, "%-6d %18s %18s %18s %12.5g %18s\n", st.delays[i],
                  pm(s.K_cr_at_zero_B, sd.K_cr_at_zero_B).c_str(), pm(s.B_t, sd.B_t).c_str(),
                  pm(s.K_cr_max, sd.K_cr_max).c_str(), s.B_max_from_zero, pm(s.B_max, sd.B_max).c_str());
    z << line;
    for (const auto& band : s.reopened_bands) {
      std::snprintf(line, sizeof line, "       reopened band: B in (%.5g, %.5g), largest stable K %.5g\n",
                    band.B_lo, band.B_hi, band.K_max);
      z << line;
    }
  }
  return z.str();
}

// The loop a table was computed on, in words.
std::string LoopDescription(const stability::LoopOptions& l) {
  if (!l.HasFilter() && l.hand.IsNone()) return "the paper's loop: raw backward difference, nobody holding the device";
  std::ostringstream d;
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

// The comparison, the margin note and the Z-width.
void StabilitySection(const analysis::RunAnalysis& a, std::ostringstream& h) {
  const analysis::PlantStability& st = a.stability;
  const bool own_loop = a.options.loop.HasFilter() || !a.options.loop.hand.IsNone();
  if (a.comparison) {
    h << "<h2>Comparison with the reference ("
      << Html(a.input.reference_is_table1 ? "Table I, built in" : a.input.reference_name) << ")</h2>\n"
      << (own_loop ? "<p>Both models on the paper's loop (raw backward difference, nobody holding the device), as the "
                     "reference was measured; the Z-width below is on this run's loop.</p>\n"
                   : "")
      << "<pre>" << Html(a.comparison->text) << "</pre>\n";
  } else {
    h << "<p>No reference comparison (pass <code>--reference table1</code> or a model JSON to compare).</p>\n";
  }
  h << "<p>The paper's gain-margin reading of eq. (4) differs from the exact K_CR in " << st.margin_disagreements
    << " of " << st.rows.size() << " B values: mostly past B_max_from_zero, where margin() stays positive although K -> 0+ is unstable "
    << "(see boundary.csv, column margin_agrees).</p>\n";
  h << "<h2>Z-width (eq. 2)</h2>\n<p>On " << Html(LoopDescription(a.options.loop)) << ".</p>\n<pre>"
    << Html(ZWidthTable(st)) << "</pre>\n<p>B_max_0: where the stable interval "
    << "from K = 0+ closes (the paper's B_max); B_max: the largest B at which some K &gt; 0 is stable. "
    << "+- one std by the delta method from the fit's parameter covariance"
    << (st.has_std ? "" : " (not available: the fit has no covariance)") << ". boundary.csv lists every stable "
    << "K interval per B.</p>\n";
}

void FiguresSection(const analysis::RunAnalysis& a, bool have_figures, std::ostringstream& h) {
  if (have_figures) {
    for (const char* name : {"bode", "coherence", "kcr", "region", "loop", "rigid"}) {
      h << "<p><img src='figures/" << name << ".svg' alt='" << name << "'></p>\n";
      if (std::string(name) == "loop") {
        h << "<p>Blue: the (B, K) the device renders stably with the raw backward difference; orange: with a "
          << a.options.report_filter_hz << " Hz first-order velocity low-pass. Lines: the passivity boundary K_P(B) "
          << "(Colgate and Schenkel, with the model's damping b = " << a.input.model.plant.b << "): below it the wall stays "
          << "passive, so it stays stable against any passive hand, which the stable region alone does not promise "
          << (a.options.loop.hand.IsNone() ? "(it assumes nobody holds the device)"
                                           : "(it assumes the run's hand, in both colours)")
          << ". Passivity is bounded by the physical damping b (for the rigid "
          << "body without delay or filter: b > K T/2 + |B|), so on a lightly damped device its region hugs the "
          << "origin: rendering beyond it relies on the stable region and on the hand being no worse than assumed.</p>\n";
      }
    }
  } else if (!a.figures) {
    h << "<p>No figures (<code>--no-figures</code>).</p>\n";
  } else {
    h << "<p>Figures need gnuplot (Debian package <code>gnuplot-nox</code>): install it and run "
      << "<code>cd figures && gnuplot figures.gp</code>, or rerun zwidth run.</p>\n";
  }
}

}  // namespace

std::string RunHtml(const analysis::RunAnalysis& a, bool have_figures, const std::string& fit_report) {
  std::ostringstream h;
  h << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>zwidth report</title>"
    << "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}pre{background:#f4f4f4;padding:8px}"
    << "img{max-width:100%}</style></head><body>\n<h1>zwidth report</h1>\n";
  FitSection(a, fit_report, h);
  StabilitySection(a, h);
  FiguresSection(a, have_figures, h);
  h << "</body></html>\n";
  return h.str();
}

}  // namespace zwidth::report
