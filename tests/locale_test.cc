// Issue 30: the text zwidth writes (.m, .py, CSV logs, frequency responses,
// model JSON) does not depend on the locale of the process it runs in. A
// Python session after locale.setlocale(LC_ALL, "de_DE.UTF-8") has a German C
// locale (printf writes 0,001168) and a program may set the global C++ locale
// (streams group thousands: 1.000). The files are written under both and read
// back with the C locale's strtod, compared to the values written.
#include <clocale>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <locale>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/compare.h"
#include "analysis/run.h"
#include "fit/fit.h"
#include "io/export.h"
#include "io/frf_file.h"
#include "io/log.h"
#include "io/model_json.h"
#include "io/reference_models.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {

class GermanLocale : public ::testing::Test {
 protected:
  void SetUp() override {
    try {
      std::locale::global(std::locale("de_DE.UTF-8"));
    } catch (const std::runtime_error&) {
      GTEST_SKIP() << "no de_DE.UTF-8 locale (scripts/setup generates it with localedef)";
    }
    ASSERT_NE(std::setlocale(LC_ALL, "de_DE.UTF-8"), nullptr);
    char buf[16];
    std::snprintf(buf, sizeof buf, "%g", 0.5);
    ASSERT_STREQ(buf, "0,5") << "the locale is not German after all: the test would prove nothing";
  }
  void TearDown() override {
    std::locale::global(std::locale::classic());
    std::setlocale(LC_ALL, "C");
  }
  test::TempDir dir_{"zwidth_locale_"};
};

// The value after `key` up to the next ';' or newline, as C strtod reads it.
double ValueAfter(const std::string& text, const std::string& key) {
  const size_t at = text.find(key);
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return 0.0;
  const std::string rest = text.substr(at + key.size(), text.find_first_of(";\n", at) - at - key.size());
  std::setlocale(LC_NUMERIC, "C");
  const double v = std::strtod(rest.c_str(), nullptr);
  std::setlocale(LC_NUMERIC, "de_DE.UTF-8");
  return v;
}

TEST_F(GermanLocale, MatlabAndPythonExportsWriteDecimalPoints) {
  const ModelFile mf = Table1Model();
  ExportModel(mf, ExportFormat::kMatlab, 0.001, dir_ / "m.m");
  ExportModel(mf, ExportFormat::kPython, 0.001, dir_ / "m.py");
  const std::string m = test::ReadFile(dir_ / "m.m"), py = test::ReadFile(dir_ / "m.py");
  EXPECT_DOUBLE_EQ(ValueAfter(m, "\nm = "), mf.plant.m);
  EXPECT_DOUBLE_EQ(ValueAfter(m, "\nb = "), mf.plant.b);
  EXPECT_FALSE(std::regex_search(m, std::regex("[0-9],[0-9]"))) << m.substr(0, 600);
  EXPECT_FALSE(std::regex_search(py, std::regex("[0-9],[0-9]{3}"))) << py.substr(0, 600);
}

TEST_F(GermanLocale, TextLogsAndResponsesReadBackExactly) {
  std::vector<double> u(2000), y(2000);
  for (size_t k = 0; k < u.size(); ++k) {
    u[k] = std::sin(0.37 * k) + 0.25 * std::sin(1.7 * k);
    y[k] = 1e-3 * std::cos(0.11 * k) + 1e-5 * k;
  }
  WriteLog(dir_ / "log.csv", 1000.0, u, y);
  std::locale::global(std::locale::classic());  // read back in the C locale
  std::setlocale(LC_ALL, "C");
  const Log back = ReadLog(dir_ / "log.csv");
  ASSERT_EQ(back.input.size(), u.size());
  for (size_t k = 0; k < u.size(); k += 97) {
    EXPECT_EQ(back.input[k], u[k]);
    EXPECT_EQ(back.output[k], y[k]);
  }
}

TEST_F(GermanLocale, ModelJsonRoundTrips) {
  const ModelFile mf = Table1Model();
  WriteModelJson(dir_ / "model.json", mf);
  const ModelFile back = ReadModelJson(dir_ / "model.json");
  EXPECT_EQ(back.plant.m, mf.plant.m);
  EXPECT_EQ(back.plant.modes.at(0).omega, mf.plant.modes.at(0).omega);
}

// The texts the library prints (compare's table, the parameter table, a fit's
// brief report) under German C and C++ locales equal the C locale's, byte for
// byte (before: compare wrote 0,001168 and the brief report 1.234,57).
struct Texts {
  std::string compare, parameters, brief;
  bool operator==(const Texts&) const = default;
};

Texts MakeTexts() {
  ModelFile model = Table1Model(), ref = Table1Model();
  model.plant.m *= 1.0123;  // decimals on both sides
  model.plant.b *= 1000.5;  // > 1000: a grouping locale writes 5.843,...
  const std::vector<int> delays = {2, 4};
  Texts t;
  t.compare = analysis::CompareModels(model, ref, delays, analysis::SummarizeDelays(model, 1e-3, delays),
                                      analysis::ReferenceStabilityOf(ref, 1e-3, delays).summaries)
                  .text;
  t.parameters = analysis::ParameterTable(model);
  fit::FitResult r;
  r.status = fit::FitStatus::kConverged;
  r.chi2_per_dof = 1234.5678;
  r.nrmse_fit_percent = 97.25;
  r.worst_misfit_hz = 0.125;
  t.brief = r.BriefReport();
  return t;
}

TEST_F(GermanLocale, CompareParameterTableAndBriefReportAreTheCLocales) {
  const Texts de = MakeTexts();
  std::locale::global(std::locale::classic());
  std::setlocale(LC_ALL, "C");
  const Texts c = MakeTexts();
  EXPECT_EQ(de.compare, c.compare);
  EXPECT_EQ(de.parameters, c.parameters);
  EXPECT_EQ(de.brief, c.brief);
  EXPECT_NE(c.brief.find("1234.57"), std::string::npos) << c.brief;
}

}  // namespace
}  // namespace zwidth::io
