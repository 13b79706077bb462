// analysis/friction_amplitude.h: A* along a boundary, against references
// built here: each computed row's wall K = k_factor x K_cr(B) with K_cr(B)
// from stability::ZWidth directly; which rows are computed (per delay the
// first, the last and evenly spaced ones, as many as rows_per_delay) against
// the index rule written out; rows without a finite K_cr > 0 not run; the
// encoder step's precedence and the options' refusals by name.
#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/friction_amplitude.h"
#include "io/model_json.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "model/friction.h"
#include "model/plant.h"
#include "stability/loop_options.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {
namespace {

TEST(FrictionAmplitude, ComputedRowsAreKFactorTimesKcrOnTheChosenRows) {
  const model::Plant p = model::PhantomTable1();
  const double T = 1e-3;
  std::vector<io::BoundaryRow> rows;
  for (int d : {2, 5}) {
    const stability::ZWidth z(p, T, d);
    const double Bmax = z.Summarize().B_max;
    for (int i = 0; i < 7; ++i) {
      io::BoundaryRow r;
      r.delay_samples = d;
      r.point = z.At(1.1 * Bmax * i / 6.0);  // the last past B_max: K_cr = 0 there
      rows.push_back(r);
    }
  }
  FrictionAmplitudeOptions o;
  o.rows_per_delay = 3;
  o.k_factor = 1.5;
  const model::Friction f = model::Friction::Symmetric(0.01);
  const std::vector<FrictionAmplitudeRow> a = FrictionAmplitudes(p, T, stability::LoopOptions{}, rows, f, o);
  ASSERT_EQ(a.size(), rows.size());
  // 3 of 7 rows per delay: indices k (7 - 1) / (3 - 1) = 0, 3, 6 of each run.
  const std::set<size_t> chosen = {0, 3, 6, 7, 10, 13};
  int run = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(a[i].delay_samples, rows[i].delay_samples);
    EXPECT_EQ(a[i].B, rows[i].point.B);
    const double kcr = stability::ZWidth(p, T, rows[i].delay_samples).At(rows[i].point.B).K_cr;
    if (chosen.count(i) && kcr > 0 && std::isfinite(kcr)) {
      EXPECT_NEAR(a[i].K, 1.5 * kcr, 1e-12 * kcr) << i;
      EXPECT_NE(a[i].prediction.verdict, stability::FrictionVerdict::kNotRun) << i;
      ++run;
    } else {
      EXPECT_TRUE(std::isnan(a[i].K)) << i;
      EXPECT_EQ(a[i].prediction.verdict, stability::FrictionVerdict::kNotRun) << i;
    }
  }
  EXPECT_EQ(run, 4);  // rows 6 and 13 lie past B_max
  // The columns copied into the rows.
  SetFrictionColumns(a, &rows);
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_TRUE(rows[i].friction_K == a[i].K || (std::isnan(rows[i].friction_K) && std::isnan(a[i].K)));
    EXPECT_EQ(rows[i].A_star_valid, a[i].prediction.verdict == stability::FrictionVerdict::kNotRun ? -1
                                    : a[i].prediction.valid                                      ? 1
                                                                                                 : 0);
  }
}

TEST(FrictionAmplitude, EncoderStepPrecedenceAndRefusals) {
  io::ModelFile mf;
  EXPECT_EQ(EncoderStepOf(mf, std::nullopt), 0.0);  // nothing known: exact
  mf.encoder_step = 1e-4;
  EXPECT_EQ(EncoderStepOf(mf, std::nullopt), 1e-4);  // the model's
  EXPECT_EQ(EncoderStepOf(mf, 2e-5), 2e-5);          // the caller's wins
  EXPECT_EQ(EncoderStepOf(mf, 0.0), 0.0);            // 0 given: an exact encoder
  for (double bad : {-1e-4, std::nan("")}) {
    try {
      EncoderStepOf(mf, bad, "--encoder-step");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--encoder-step", 0), 0u) << e.what();
    }
  }
  std::string why;
  EXPECT_TRUE(FrictionAmplitudeOptions{}.IsValid(&why)) << why;
  FrictionAmplitudeOptions o;
  for (double k : {1.0, 0.5, 100.5}) {
    o.k_factor = k;
    EXPECT_FALSE(o.IsValid(&why)) << k;
    EXPECT_NE(why.find("FrictionAmplitudeOptions::k_factor"), std::string::npos) << why;
  }
  o = {};
  o.k_factor = 100.0;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.rows_per_delay = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("rows_per_delay"), std::string::npos) << why;
  EXPECT_THROW(FrictionAmplitudes(model::PhantomTable1(), 1e-3, {}, {}, model::Friction::Symmetric(0.01), o), InputError);
}

}  // namespace
}  // namespace zwidth::analysis
