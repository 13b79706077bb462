// figures/ of `zwidth run`: the .dat files gnuplot reads and figures.gp. The
// .dat files are figure data only (the results are model.json, frf.csv,
// boundary.csv and summary.json): each plotted line keeps the rows that a
// kFigureWidthPx x kFigureHeightPx figure can show (report/polyline.h), every
// column gnuplot draws is written out (no `using` expressions, which gnuplot
// evaluates row by row under a signal handler), and the stable region of each
// delay is a few polygons instead of one segment per B.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "io/reference_models.h"
#include "model/error.h"
#include "report/polyline.h"
#include "report/report_internal.h"

namespace zwidth::report {
namespace fs = std::filesystem;
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// A file of figures/, written straight into the run's temporary folder (new
// and ours; OutputFolder::Commit moves it into place with the rest) and not
// synced to disk, like the SVGs gnuplot writes beside it: the figure data are
// made again by running again. A write error (a full disk) is an InputError,
// as for every output; the temporary folder is then removed.
void WriteFigureFile(const fs::path& path, const std::string& content) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) throw InputError("cannot create '" + path.string() + "': " + std::strerror(errno));
  const char* p = content.data();
  size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n < 0 ? std::strerror(errno) : "nothing written";
      ::close(fd);
      throw InputError("failed writing '" + path.string() + "': " + why + " (disk full?); nothing was written");
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::close(fd) != 0) {
    throw InputError("failed writing '" + path.string() + "': " + std::strerror(errno) + " (disk full?); nothing was written");
  }
}

// Appends v as printf's %.10g (what the .dat files always held).
void Num(std::string& s, double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 10);
  s.append(buf, r.ptr);
}

// Appends the rows `kept` of the columns (x, cols...), one line each. A row
// where break_on is NaN is written as one blank line (a break of gnuplot's
// line within the block) instead; never two in a row nor at the block's ends.
// Without a row written, one row of nan keeps the block (gnuplot's index
// counts blocks).
void Rows(std::string& s, const std::vector<size_t>& kept, const std::vector<const std::vector<double>*>& cols,
          const std::vector<double>* break_on = nullptr) {
  bool open = false, pending_break = false;
  for (size_t i : kept) {
    if (break_on && std::isnan((*break_on)[i])) {
      pending_break = open;
      continue;
    }
    if (pending_break) s += '\n';
    pending_break = false;
    open = true;
    for (size_t c = 0; c < cols.size(); ++c) {
      if (c) s += ' ';
      Num(s, (*cols[c])[i]);
    }
    s += '\n';
  }
  if (!open) {
    for (size_t c = 0; c < cols.size(); ++c) s += c ? " nan" : "nan";
    s += '\n';
  }
}

// bode.dat, four blocks (index 0..3):
//   0: f_hz |H| phase_deg, measured in the fitted band (blank lines at gaps)
//   1: f_hz |H| phase_deg, measured, not used by the fit (points, all kept)
//   2: f_hz |G| phase_G_deg, the fitted model
//   3: f_hz coherence (coherence_ru coherence_ry for a joint estimate)
std::string BodeDat(const analysis::RunAnalysis& a) {
  const ident::CombinedResponse& r = a.input.response;
  const ident::FrequencyResponse& frf = r.frf;
  const analysis::BodeData& bd = a.figures->bode;
  const bool joint = r.method == ident::CombinedMethod::kJoint;
  const size_t n = frf.f_hz.size();
  auto used = [&](size_t k) { return k < frf.used_by_fit.size() && frf.used_by_fit[k]; };
  std::vector<double> h_in(n), ph_in(n);
  for (size_t k = 0; k < n; ++k) {
    h_in[k] = used(k) ? bd.H_abs[k] : kNaN;
    ph_in[k] = used(k) ? bd.H_phase_deg[k] : kNaN;
  }
  const PixelAxis fx = AxisSpanning(frf.f_hz, kFigureWidthPx, true);
  auto mag = [&](const std::vector<double>& v) { return DrawnSeries{&v, AxisSpanning(v, kFigureHeightPx, true)}; };
  auto lin = [&](const std::vector<double>& v) { return DrawnSeries{&v, AxisSpanning(v, kFigureHeightPx, false)}; };
  auto coh = [&](const std::vector<double>& v) { return DrawnSeries{&v, AxisSpanning(v, kFigureHeightPx, false, 0.0, 1.05)}; };
  std::string s;
  s += "# f_hz |H| phase_deg: measured, in the fitted band (blank lines at gaps)\n";
  Rows(s, ThinPolylines(frf.f_hz, fx, {mag(h_in), lin(ph_in)}, kThinTolerancePx), {&frf.f_hz, &h_in, &ph_in}, &h_in);
  s += "\n\n# f_hz |H| phase_deg: measured, not used by the fit\n";
  std::vector<size_t> unused;
  for (size_t k = 0; k < n; ++k) {
    if (!used(k)) unused.push_back(k);
  }
  Rows(s, unused, {&frf.f_hz, &bd.H_abs, &bd.H_phase_deg});
  s += "\n\n# f_hz |G| phase_G_deg: the fitted model (exact ZOH)\n";
  Rows(s, ThinPolylines(frf.f_hz, fx, {mag(bd.G_abs), lin(bd.G_phase_deg)}, kThinTolerancePx),
       {&frf.f_hz, &bd.G_abs, &bd.G_phase_deg});
  if (joint) {
    s += "\n\n# f_hz coherence_ru coherence_ry\n";
    Rows(s, ThinPolylines(frf.f_hz, fx, {coh(r.coherence_ru), coh(r.coherence_ry)}, kThinTolerancePx),
         {&frf.f_hz, &r.coherence_ru, &r.coherence_ry});
  } else {
    s += "\n\n# f_hz coherence\n";
    Rows(s, ThinPolylines(frf.f_hz, fx, {coh(frf.coherence)}, kThinTolerancePx), {&frf.f_hz, &frf.coherence});
  }
  return s;
}

// kcr_*.dat, one block per delay: B K_cr f_cr K_cr_std, and for the model
// K_cr -+ 2 K_cr_std (the region figure's band). The model's from the
// boundary rows, the others' (curves) with K_cr_std nan; rows thinned for the
// K_cr(B) and f_cr(B) lines (and the band), K on [0, k_clip] as the region
// figure shows it.
std::string KcrDat(const analysis::RunAnalysis& a, const std::vector<std::vector<stability::CriticalPoint>>* curves,
                   double k_clip) {
  const analysis::PlantStability& st = a.stability;
  const size_t nB = st.b_grid.size();
  const PixelAxis bx = AxisSpanning(st.b_grid, kFigureWidthPx, false);
  std::string s;
  std::vector<double> K(nB), f(nB), sd(nB), lo(nB), hi(nB);
  for (size_t i = 0; i < st.delays.size(); ++i) {
    for (size_t k = 0; k < nB; ++k) {
      const io::BoundaryRow& row = st.rows[i * nB + k];
      const stability::CriticalPoint& c = curves ? (*curves)[i][k] : row.point;
      K[k] = c.K_cr;
      f[k] = c.f_cr_hz;
      sd[k] = curves ? kNaN : row.K_cr_std;
      lo[k] = K[k] - 2 * sd[k];
      hi[k] = K[k] + 2 * sd[k];
    }
    auto k_axis = [&](const std::vector<double>& v) { return DrawnSeries{&v, AxisSpanning(v, kFigureHeightPx, false, 0.0, k_clip)}; };
    if (curves) {
      // Only K_cr(B) is drawn of the reference's and the rigid body's.
      Rows(s, ThinPolylines(st.b_grid, bx, {k_axis(K)}, kThinTolerancePx), {&st.b_grid, &K, &f, &sd});
    } else {
      const DrawnSeries fs{&f, AxisSpanning(f, kFigureHeightPx, true)};
      Rows(s, ThinPolylines(st.b_grid, bx, {k_axis(K), fs, k_axis(lo), k_axis(hi)}, kThinTolerancePx),
           {&st.b_grid, &K, &f, &sd, &lo, &hi});
    }
    s += "\n\n";
  }
  return s;
}

// The stable K intervals of one delay as bands: an interval at B_k continues
// the band of an overlapping interval at B_(k-1). Each band is a block (B
// K_lo K_hi, thinned) that gnuplot fills as one polygon; a band of one B is
// widened to half a grid step on each side (the segment drawn before).
void AppendBands(std::string& s, const std::vector<double>& b_grid, const std::vector<io::BoundaryRow>& rows,
                 size_t first, double k_clip, bool* any) {
  struct Band {
    std::vector<double> B, lo, hi;
    bool extended = false;
  };
  const size_t nB = b_grid.size();
  const PixelAxis bx = AxisSpanning(b_grid, kFigureWidthPx, false);
  std::vector<Band> open, done;
  for (size_t k = 0; k < nB; ++k) {
    for (Band& b : open) b.extended = false;
    std::vector<Band> started;
    for (const stability::KInterval& iv : rows[first + k].intervals) {
      const double hi = std::min(iv.K_hi, k_clip);
      Band* into = nullptr;
      for (Band& b : open) {
        if (!b.extended && iv.K_lo <= b.hi.back() && b.lo.back() <= hi) {
          into = &b;
          break;
        }
      }
      if (!into) into = &started.emplace_back();
      into->B.push_back(b_grid[k]);
      into->lo.push_back(iv.K_lo);
      into->hi.push_back(hi);
      into->extended = true;
    }
    for (Band& b : open) {
      if (!b.extended) done.push_back(std::move(b));
    }
    std::erase_if(open, [](const Band& b) { return !b.extended; });
    for (Band& b : started) open.push_back(std::move(b));
  }
  for (Band& b : open) done.push_back(std::move(b));
  const double half_step = nB > 1 ? 0.5 * (b_grid.back() - b_grid.front()) / static_cast<double>(nB - 1) : 0.0;
  for (Band& b : done) {
    if (b.B.size() == 1) {
      b.B = {std::max(b.B[0] - half_step, b_grid.front()), std::min(b.B[0] + half_step, b_grid.back())};
      b.lo.push_back(b.lo[0]);
      b.hi.push_back(b.hi[0]);
    }
    if (*any) s += '\n';
    *any = true;
    const DrawnSeries lo{&b.lo, AxisSpanning(b.lo, kFigureHeightPx, false, 0.0, k_clip)};
    const DrawnSeries hi{&b.hi, AxisSpanning(b.hi, kFigureHeightPx, false, 0.0, k_clip)};
    Rows(s, ThinPolylines(b.B, bx, {lo, hi}, kThinTolerancePx), {&b.B, &b.lo, &b.hi});
  }
}

// region_model.dat: the stable set per delay (one block each), as bands;
// +inf drawn at *k_clip = 1.2 x the largest finite K of the table.
std::string RegionDat(const analysis::PlantStability& st, double* k_clip_out) {
  double k_clip = 0.0;
  for (const auto& r : st.rows) {
    for (const auto& iv : r.intervals) k_clip = std::max(k_clip, std::isfinite(iv.K_hi) ? iv.K_hi : iv.K_lo);
  }
  k_clip = k_clip > 0.0 ? 1.2 * k_clip : 1.0;
  *k_clip_out = k_clip;
  std::string s;
  for (size_t i = 0; i < st.delays.size(); ++i) {
    s += "# delay " + std::to_string(st.delays[i]) + ": B K_lo K_hi, one band per block (K_hi = +inf drawn at ";
    Num(s, k_clip);
    s += ")\n";
    bool any = false;
    AppendBands(s, st.b_grid, st.rows, i * st.b_grid.size(), k_clip, &any);
    if (!any) s += "nan nan nan\n";
    s += "\n\n";
  }
  return s;
}

// loop_region.dat (two blocks per delay: the filtered loop's region, then the
// raw one's; B K_lo 0 K_hi-K_lo, gnuplot's vectors; +inf drawn at k_clip) and
// loop_passive.dat (B K_P raw, K_P filtered, one block per delay). Returns the
// loop figure's upper K.
double WriteLoopDat(const analysis::FigureData& f, double k_clip, const fs::path& fig) {
  double k_clip_loop = k_clip;
  for (const analysis::LoopFigureDelay& d : f.loop) {
    for (size_t k = 0; k < d.B.size(); ++k) {
      for (const auto* ivs : {&d.raw[k], &d.filtered[k]}) {
        for (const auto& iv : *ivs) {
          if (std::isfinite(iv.K_hi)) k_clip_loop = std::max(k_clip_loop, 1.05 * iv.K_hi);
        }
      }
    }
  }
  std::string o, q;
  for (const analysis::LoopFigureDelay& d : f.loop) {
    for (int which = 1; which >= 0; --which) {
      o += which ? "# filtered: B K_lo 0 K_hi-K_lo\n" : "# raw: B K_lo 0 K_hi-K_lo\n";
      bool any = false;
      for (size_t k = 0; k < d.B.size(); ++k) {
        for (const auto& iv : (which ? d.filtered : d.raw)[k]) {
          const double hi = std::min(iv.K_hi, k_clip);
          Num(o, d.B[k]);
          o += ' ';
          Num(o, iv.K_lo);
          o += " 0 ";
          Num(o, hi - iv.K_lo);
          o += '\n';
          any = true;
        }
      }
      if (!any) o += "nan nan nan nan\n";
      o += "\n\n";
    }
    const PixelAxis bx = AxisSpanning(d.B, kFigureWidthPx, false);
    auto k_axis = [&](const std::vector<double>& v) {
      return DrawnSeries{&v, AxisSpanning(v, kFigureHeightPx, false, 0.0, k_clip_loop)};
    };
    Rows(q, ThinPolylines(d.B, bx, {k_axis(d.K_passive_raw), k_axis(d.K_passive_filtered)}, kThinTolerancePx),
         {&d.B, &d.K_passive_raw, &d.K_passive_filtered});
    q += "\n\n";
  }
  WriteFigureFile(fig / "loop_region.dat", o);
  WriteFigureFile(fig / "loop_passive.dat", q);
  return k_clip_loop;
}

// Table II (the paper's relay points) at the delays drawn.
std::string Table2Dat(const std::vector<int>& delays) {
  std::string s;
  for (const io::Table2Point& p : io::Table2Points()) {
    if (std::find(delays.begin(), delays.end(), p.delay_samples) == delays.end()) continue;
    s += std::to_string(p.delay_samples);
    for (double v : {p.B, p.K_cr, p.f_cr_hz}) {
      s += ' ';
      Num(s, v);
    }
    s += '\n';
  }
  return s;
}

}  // namespace

std::string WriteFigureFiles(const analysis::RunAnalysis& a, const fs::path& fig, bool png) {
  const analysis::FigureData& f = *a.figures;
  fs::create_directories(fig);
  double k_clip = 1.0;
  const std::string region = RegionDat(a.stability, &k_clip);
  WriteFigureFile(fig / "bode.dat", BodeDat(a));
  WriteFigureFile(fig / "kcr_model.dat", KcrDat(a, nullptr, k_clip));
  if (a.input.reference) WriteFigureFile(fig / "kcr_reference.dat", KcrDat(a, &f.kcr_reference, kInf));
  WriteFigureFile(fig / "kcr_rigid.dat", KcrDat(a, &f.kcr_rigid, kInf));
  WriteFigureFile(fig / "region_model.dat", region);
  const double k_clip_loop = WriteLoopDat(f, k_clip, fig);
  const bool table1 = a.input.reference && a.input.reference_is_table1;  // drawn only beside Table I
  if (table1) WriteFigureFile(fig / "table2.dat", Table2Dat(a.options.delays));
  const FigureScriptOptions so{a.options.delays, a.input.model.plant.delay_samples, a.input.response.method,
                               a.input.response.method == ident::CombinedMethod::kJoint,
                               a.options.linear, a.input.reference.has_value(), table1,
                               k_clip, k_clip_loop, a.options.report_filter_hz, png};
  std::string script = FigureScript(so);
  WriteFigureFile(fig / "figures.gp", script);
  return script;
}

}  // namespace zwidth::report
