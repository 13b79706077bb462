// report::WriteRunReport: the files of a run written into its folder, on the
// analysis of a synthetic model (tests/run_input.h).
#include <filesystem>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "analysis/run.h"
#include "io/atomic_file.h"
#include "report/run_report.h"
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
  const analysis::RunAnalysis a = analysis::Analyse(std::move(in), o);
  {
    io::OutputFolder folder(dir.string(), false);
    const report::RunReport r = report::WriteRunReport(a, folder);
    EXPECT_EQ(r.figures, report::FiguresStatus::kNotRequested);
    folder.Commit();
  }
  for (const char* f : {"model.json", "frf.csv", "boundary.csv", "summary.json", "report.html"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / f)) << f;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "figures"));
  const std::string text = test::ReadFile(dir / "report.html");
  EXPECT_NE(text.find("No figures"), std::string::npos);
}

}  // namespace
}  // namespace zwidth
