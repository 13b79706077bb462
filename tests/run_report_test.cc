// report::WriteRunReport: the files of a run written into its folder, on the
// analysis of a synthetic model (tests/run_input.h).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "analysis/run.h"
#include "io/atomic_file.h"
#include "report/run_report.h"
#include "stability/velocity_filter.h"
#include "tests/run_input.h"
#include "tests/test_util.h"

namespace zwidth {
namespace {

TEST(RunReport, WritesEveryFileIntoTheFolderAndNothingWithoutFigures) {
  const test::TempDir tmp("zwidth_run_report_");
  const std::filesystem::path dir = tmp.path() / "run";
  analysis::RunOptions o;
  o.figures = false;
  analysis::RunInput in = TestInput(0.0);
  in.model.fit = {{"quality_reasons", nlohmann::json::array()}};
  in.response.frf.estimator = "lrm";  // summary.json says which estimator made the response
  const analysis::RunAnalysis a = analysis::Analyse(std::move(in), o);
  {
    io::OutputFolder folder(dir.string(), false);
    const report::RunReport r = report::WriteRunReport(a, folder);
    EXPECT_EQ(r.figures, report::FiguresStatus::kNotRequested);
    folder.Commit();
  }
  EXPECT_EQ(nlohmann::json::parse(test::ReadFile(dir / "summary.json")).value("estimator", ""), "lrm");
  for (const char* f : {"model.json", "frf.csv", "boundary.csv", "summary.json", "report.html"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / f)) << f;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "figures"));
  const std::string text = test::ReadFile(dir / "report.html");
  EXPECT_NE(text.find("No figures"), std::string::npos);
  EXPECT_NE(text.find("On the paper's loop"), std::string::npos);  // the loop of the Z-width table, named
}

// With a hand and a velocity filter the report names the loop of its Z-width
// table (the tryout read two tables of one device and delay, on two loops,
// with nothing saying which was which).
TEST(RunReport, NamesTheLoopOfTheZWidthTable) {
  const test::TempDir tmp("zwidth_run_report_");
  const std::filesystem::path dir = tmp.path() / "run";
  analysis::RunOptions o;
  o.figures = false;
  o.loop.hand = {1e-3, 2e-3, 0.5};
  stability::SetLowPassFilter(100.0, 1e-3, &o.loop);
  analysis::RunInput in = TestInput(0.0);
  in.model.fit = {{"quality_reasons", nlohmann::json::array()}};
  const analysis::RunAnalysis a = analysis::Analyse(std::move(in), o);
  {
    io::OutputFolder folder(dir.string(), false);
    report::WriteRunReport(a, folder);
    folder.Commit();
  }
  const std::string text = test::ReadFile(dir / "report.html");
  EXPECT_NE(text.find("On velocity filter F(z) with b = "), std::string::npos);
  EXPECT_NE(text.find("hand M = 0.001, B = 0.002, K = 0.5"), std::string::npos);
}

// The blocks of a gnuplot data file (two blank lines apart), each a list of
// sub-blocks (one blank line apart) of rows of numbers; comments skipped.
using Rows = std::vector<std::vector<double>>;
std::vector<std::vector<Rows>> ReadBlocks(const std::filesystem::path& path) {
  std::vector<std::vector<Rows>> blocks(1, std::vector<Rows>(1));
  std::istringstream in(test::ReadFile(path));
  std::string line;
  int blanks = 0;
  while (std::getline(in, line)) {
    if (line.empty()) {
      ++blanks;
      continue;
    }
    if (line[0] == '#') continue;
    if (blanks >= 2) blocks.emplace_back(1);
    else if (blanks == 1) blocks.back().emplace_back();
    blanks = 0;
    std::istringstream ls(line);
    std::vector<double> row;
    std::string tok;
    while (ls >> tok) row.push_back(std::stod(tok));
    blocks.back().back().push_back(row);
  }
  return blocks;
}

// Distance from p to segment ab (by cases: beyond an end, or the height over ab).
double SegmentDistance(double px, double py, double ax, double ay, double bx, double by) {
  const double ux = bx - ax, uy = by - ay;
  if ((px - ax) * ux + (py - ay) * uy <= 0) return std::hypot(px - ax, py - ay);
  if ((px - bx) * ux + (py - by) * uy >= 0) return std::hypot(px - bx, py - by);
  return std::abs(ux * (py - ay) - uy * (px - ax)) / std::hypot(ux, uy);
}

// Point (x, y) inside the polygon (even-odd ray casting to +x) or within tol of its edges.
bool InsideOrNear(const std::vector<std::pair<double, double>>& poly, double x, double y, double tol) {
  bool in_poly = false;
  double edge = std::numeric_limits<double>::infinity();
  for (size_t p = 0, q = poly.size() - 1; p < poly.size(); q = p++) {
    const auto [x1, y1] = poly[p];
    const auto [x2, y2] = poly[q];
    if ((y1 > y) != (y2 > y) && x < x1 + (y - y1) * (x2 - x1) / (y2 - y1)) in_poly = !in_poly;
    edge = std::min(edge, SegmentDistance(x, y, x1, y1, x2, y2));
  }
  return in_poly || edge <= tol;
}

// The figure data of a run against what the analysis computed, in pixels of
// the 900 x 640 canvas (the data's own range across it; every panel is
// smaller, so a drawn pixel is smaller still): each model K_CR(B) lies within
// 0.2 px of the thinned line in kcr_model.dat, and each stable interval's
// middle lies inside (or within 0.2 px of) a band polygon of region_model.dat.
TEST(RunReport, FigureDataLieWithinAFifthOfAPixelOfWhatWasComputed) {
  const test::TempDir tmp("zwidth_run_report_fig_");
  const std::filesystem::path dir = tmp.path() / "run";
  analysis::RunOptions o;
  o.delays = {2, 6};
  analysis::RunInput in = TestInput(0.0);
  in.model.fit = {{"quality_reasons", nlohmann::json::array()}};
  const analysis::RunAnalysis a = analysis::Analyse(std::move(in), o);
  report::RunReport r;
  {
    io::OutputFolder folder(dir.string(), false);
    report::RunReportOptions ro;
    ro.draw_figures = false;
    r = report::WriteRunReport(a, folder, ro);
    folder.Commit();
  }
  EXPECT_EQ(r.figures, report::FiguresStatus::kNotDrawn);
  const analysis::PlantStability& st = a.stability;
  const size_t nB = st.b_grid.size();
  const double b_px = 900 / (st.b_grid.back() - st.b_grid.front());
  double k_clip = 0;
  for (const auto& row : st.rows) {
    for (const auto& iv : row.intervals) k_clip = std::max(k_clip, std::isfinite(iv.K_hi) ? iv.K_hi : iv.K_lo);
  }
  k_clip *= 1.2;
  const auto kcr = ReadBlocks(dir / "figures" / "kcr_model.dat");
  const auto region = ReadBlocks(dir / "figures" / "region_model.dat");
  ASSERT_EQ(kcr.size(), 2u);
  ASSERT_EQ(region.size(), 2u);
  size_t checked = 0;
  for (size_t i = 0; i < 2; ++i) {
    double k_lo = std::numeric_limits<double>::infinity(), k_hi = -k_lo;
    for (size_t k = 0; k < nB; ++k) {
      const double K = std::clamp(st.rows[i * nB + k].point.K_cr, 0.0, k_clip);
      if (std::isfinite(K)) k_lo = std::min(k_lo, K), k_hi = std::max(k_hi, K);
    }
    const double k_px = 640 / (k_hi - k_lo);
    ASSERT_EQ(kcr[i].size(), 1u);
    const Rows& line = kcr[i][0];
    EXPECT_LT(line.size(), nB / 2) << "thinned";
    for (size_t k = 0; k < nB; ++k) {
      const double B = st.b_grid[k], K = st.rows[i * nB + k].point.K_cr;
      if (!std::isfinite(K)) continue;
      double best = std::numeric_limits<double>::infinity();
      for (size_t j = 0; j + 1 < line.size(); ++j) {
        best = std::min(best, SegmentDistance(B * b_px, K * k_px, line[j][0] * b_px, line[j][1] * k_px,
                                              line[j + 1][0] * b_px, line[j + 1][1] * k_px));
      }
      EXPECT_LE(best, 0.2 + 1e-9) << "delay " << st.delays[i] << " B " << B;
      ++checked;
    }
    // Each band polygon: the upper edge (B, K_hi) forward, the lower (B, K_lo) back.
    std::vector<std::vector<std::pair<double, double>>> polys;
    for (const Rows& band : region[i]) {
      std::vector<std::pair<double, double>> poly;
      for (const auto& row : band) poly.push_back({row[0] * b_px, row[2] * 640 / k_clip});
      for (auto it = band.rbegin(); it != band.rend(); ++it) poly.push_back({(*it)[0] * b_px, (*it)[1] * 640 / k_clip});
      polys.push_back(poly);
    }
    for (size_t k = 0; k < nB; ++k) {
      for (const auto& iv : st.rows[i * nB + k].intervals) {
        const double x = st.b_grid[k] * b_px, y = 0.5 * (iv.K_lo + std::min(iv.K_hi, k_clip)) * 640 / k_clip;
        bool inside = false;
        for (const auto& poly : polys) inside = inside || InsideOrNear(poly, x, y, 0.2);
        EXPECT_TRUE(inside) << "delay " << st.delays[i] << " B " << st.b_grid[k] << " K " << iv.K_lo;
      }
    }
  }
  EXPECT_GT(checked, nB);
}

// The run's analysis with figure data (delays 2 and 6, no reference).
analysis::RunAnalysis FigureAnalysis() {
  analysis::RunOptions o;
  o.delays = {2, 6};
  analysis::RunInput in = TestInput(0.0);
  in.model.fit = {{"quality_reasons", nlohmann::json::array()}};
  return analysis::Analyse(std::move(in), o);
}

report::RunReport WriteWithFigures(const analysis::RunAnalysis& a, const std::filesystem::path& dir) {
  io::OutputFolder folder(dir.string(), false);
  const report::RunReport r = report::WriteRunReport(a, folder);
  folder.Commit();
  return r;
}

// An executable `name` in a directory of PATH (as execvp finds it; no shell).
bool OnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    if (!dir.empty() && ::access((std::filesystem::path(dir) / name).c_str(), X_OK) == 0) return true;
  }
  return false;
}

// gnuplot, started before the files are written, draws all six SVGs from the
// script it is handed; gnuplot.log holds no error (only the warning that the
// K_CR +- 2 sigma band has no points: the test model has no covariance).
TEST(RunReport, GnuplotDrawsEverySvg) {
  if (!OnPath("gnuplot")) GTEST_SKIP() << "gnuplot is not installed";
  const test::TempDir tmp("zwidth_run_report_gp_");
  const report::RunReport r = WriteWithFigures(FigureAnalysis(), tmp.path() / "run");
  EXPECT_EQ(r.figures, report::FiguresStatus::kDrawn);
  const std::filesystem::path fig = tmp.path() / "run" / "figures";
  for (const char* f : {"bode.svg", "coherence.svg", "kcr.svg", "region.svg", "loop.svg", "rigid.svg"}) {
    const std::string svg = test::ReadFile(fig / f);
    EXPECT_NE(svg.find("</svg>"), std::string::npos) << f;
  }
  std::istringstream log(test::ReadFile(fig / "gnuplot.log"));
  for (std::string line; std::getline(log, line);) {
    EXPECT_NE(line.find("warning: Skipping data file with no valid points"), std::string::npos) << line;
  }
  ASSERT_EQ(r.stages.size(), 3u);
  EXPECT_EQ(r.stages[2].name, "figures (gnuplot)");
}

// A gnuplot that fails at once (before reading its script: the write to it
// meets a closed pipe, whose SIGPIPE must not end this process) and one that
// is not on PATH: the status says which, the data and the script are written.
TEST(RunReport, AFailingOrMissingGnuplotIsReportedAndTheDataStay) {
  const test::TempDir tmp("zwidth_run_report_nogp_");
  const std::filesystem::path bin = tmp.path() / "bin";
  std::filesystem::create_directories(bin);
  {
    std::ofstream fake(bin / "gnuplot");
    fake << "#!/bin/sh\nexit 1\n";
  }
  std::filesystem::permissions(bin / "gnuplot", std::filesystem::perms::owner_all);
  const char* old_path = std::getenv("PATH");
  const std::string saved = old_path ? old_path : "";
  const analysis::RunAnalysis a = FigureAnalysis();
  ::setenv("PATH", (bin.string() + ":/usr/bin:/bin").c_str(), 1);
  const report::RunReport failed = WriteWithFigures(a, tmp.path() / "failed");
  ::setenv("PATH", (tmp.path() / "nothing").c_str(), 1);
  const report::RunReport missing = WriteWithFigures(a, tmp.path() / "missing");
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_EQ(failed.figures, report::FiguresStatus::kGnuplotFailed);
  EXPECT_EQ(missing.figures, report::FiguresStatus::kGnuplotMissing);
  for (const char* run : {"failed", "missing"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(tmp.path() / run / "figures" / "figures.gp")) << run;
    EXPECT_TRUE(std::filesystem::is_regular_file(tmp.path() / run / "figures" / "bode.dat")) << run;
    EXPECT_FALSE(std::filesystem::exists(tmp.path() / run / "figures" / "bode.svg")) << run;
  }
}

}  // namespace
}  // namespace zwidth
