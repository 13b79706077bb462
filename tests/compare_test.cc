// analysis/compare.h: a fitted model beside a reference, against references
// computed here: each parameter's difference from the two plants' fields
// (100 (model - reference) / reference, and over the model's std); each
// delay's Z-width figures and their differences from stability::ZWidth
// built on each plant directly (not SummarizeDelays' shared sampled plant);
// the parameter table read back against the model; units refused by name.
#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/compare.h"
#include "io/model_json.h"
#include "model/error.h"
#include "model/plant.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {
namespace {

io::ModelFile Fitted() {
  io::ModelFile mf;
  mf.plant = model::PhantomTable1();
  mf.plant.m *= 1.08;
  mf.plant.b *= 0.93;
  mf.plant.modes[0].omega *= 1.03;
  mf.plant.modes[1].d *= 0.8;
  model::Plant s = mf.plant;
  s.m = 0.02 * mf.plant.m;
  s.b = 0.05 * mf.plant.b;
  for (model::Mode& md : s.modes) md = {md.omega * 0.01, md.c * 0.1, md.v * 0.01, md.d * 0.1};
  mf.std_errors = s;
  return mf;
}

// The plant's value of a parameter named as the comparison names it.
double Field(const model::Plant& p, const std::string& name) {
  if (name == "m") return p.m;
  if (name == "b") return p.b;
  const int i = std::stoi(name.substr(name.find_first_of("0123456789"))) - 1;
  const model::Mode& md = p.modes.at(i);
  switch (name[0]) {
    case 'o': return md.omega;
    case 'c': return md.c;
    case 'v': return md.v;
    case 'd': return md.d;
  }
  ADD_FAILURE() << "unknown parameter " << name;
  return NAN;
}

TEST(Compare, DifferencesAreThoseOfThePlantsAndTheirZWidths) {
  const io::ModelFile model = Fitted();
  io::ModelFile ref;
  ref.plant = model::PhantomTable1();
  const double T = 1e-3;
  const std::vector<int> delays = {1, 3};
  const DelayStability ms = SummarizeDelays(model, T, delays);
  std::vector<stability::DelaySummary> rs;
  for (int d : delays) rs.push_back(stability::ZWidth(ref.plant, T, d).Summarize());
  const ModelComparison c = CompareModels(model, ref, delays, ms, rs);
  const nlohmann::json& params = c.json["parameters"];
  ASSERT_EQ(params.size(), 2 + 4 * model.plant.modes.size());
  std::map<std::string, int> seen;
  for (const nlohmann::json& row : params) {
    const std::string name = row["name"];
    ++seen[name];
    const double mine = Field(model.plant, name), theirs = Field(ref.plant, name), sd = Field(*model.std_errors, name);
    EXPECT_EQ(row["value"].get<double>(), mine) << name;
    EXPECT_EQ(row["reference"].get<double>(), theirs) << name;
    EXPECT_NEAR(row["diff_percent"].get<double>(), 100.0 * (mine - theirs) / theirs, 1e-12) << name;
    EXPECT_NEAR(row["diff_in_std"].get<double>(), (mine - theirs) / sd, 1e-9) << name;
  }
  EXPECT_EQ(seen.size(), params.size());  // every parameter once
  ASSERT_EQ(c.json["stability"].size(), delays.size());
  for (size_t i = 0; i < delays.size(); ++i) {
    const stability::DelaySummary direct = stability::ZWidth(model.plant, T, delays[i]).Summarize();
    EXPECT_NEAR(ms.summaries[i].K_cr_max, direct.K_cr_max, 1e-12 * direct.K_cr_max);
    EXPECT_NEAR(ms.summaries[i].B_max, direct.B_max, 1e-10 * direct.B_max);
    const nlohmann::json& e = c.json["stability"][i];
    EXPECT_EQ(e["delay_samples"].get<int>(), delays[i]);
    EXPECT_NEAR(e["difference"]["K_cr_at_zero_B"].get<double>(), direct.K_cr_at_zero_B - rs[i].K_cr_at_zero_B,
                1e-10 * direct.K_cr_at_zero_B);
    EXPECT_NEAR(e["difference"]["K_cr_max"].get<double>(), direct.K_cr_max - rs[i].K_cr_max, 1e-10 * direct.K_cr_max);
    EXPECT_NEAR(e["difference"]["B_max"].get<double>(), direct.B_max - rs[i].B_max, 1e-8 * direct.B_max);
  }
  EXPECT_NE(c.text.find("diff %"), std::string::npos);
  // Different numbers of modes: no per-parameter rows, and the text says why.
  io::ModelFile one = model;
  one.plant.modes.pop_back();
  one.std_errors.reset();
  const ModelComparison c1 = CompareModels(one, ref, delays, SummarizeDelays(one, T, delays), rs);
  EXPECT_TRUE(c1.json["parameters"].empty());
  EXPECT_NE(c1.text.find("different numbers of modes (1 vs 2)"), std::string::npos) << c1.text;
}

// The table's rows "name value std unit" read back give the model and its std.
TEST(Compare, ParameterTableReadsBackAsTheModel) {
  const io::ModelFile mf = Fitted();
  std::istringstream in(ParameterTable(mf));
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string name;
    double value, sd;
    if (!(ls >> name >> value >> sd)) continue;  // a header
    if (name != "m" && name != "b" && name.find_first_of("0123456789") == std::string::npos) continue;
    EXPECT_NEAR(value, Field(mf.plant, name), 1e-5 * std::abs(Field(mf.plant, name))) << line;
    EXPECT_NEAR(sd, Field(*mf.std_errors, name), 1e-2 * Field(*mf.std_errors, name)) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 2 + 4 * static_cast<int>(mf.plant.modes.size()));
  EXPECT_NE(ParameterTable(mf).find("kg m^2"), std::string::npos);
  EXPECT_NE(ParameterTable(mf, true).find("N s/m"), std::string::npos);
}

TEST(Compare, ModelsOfDifferentUnitsAreRefusedByName) {
  io::ModelFile linear;
  linear.plant = model::PhantomTable1();
  linear.linear = true;
  io::ModelFile rotary = linear;
  rotary.linear = false;
  EXPECT_NO_THROW(CheckSameUnits(true, linear, "a.json", "b.json"));
  EXPECT_NO_THROW(CheckSameUnits(false, rotary, "a.json", "b.json"));
  try {
    CheckSameUnits(false, linear, "fitted.json", "design.json");
    ADD_FAILURE() << "rotary against linear accepted";
  } catch (const InputError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("fitted.json"), std::string::npos) << w;
    EXPECT_NE(w.find("design.json"), std::string::npos) << w;
  }
  const std::vector<int> delays = {2};
  const DelayStability ms = SummarizeDelays(rotary, 1e-3, delays);
  EXPECT_THROW(CompareModels(rotary, linear, delays, ms, ms.summaries), InputError);
}

}  // namespace
}  // namespace zwidth::analysis
