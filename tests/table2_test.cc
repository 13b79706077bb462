// analysis::CompareTable2 (issue 32): Table II's measured relay points beside
// Table I's linear Z-width and its relay simulated with Coulomb friction.
// - The linear predictions are the exact Z-width: each point's K_cr(B) equals
//   the brute force of tests/brute_force.h (closed-loop roots from companion
//   matrices, a geometric K scan and bisection), and the points where that
//   finds no stable K are the unscored ones.
// - The best Coulomb level is the argmin, over a grid written here, of the
//   stated error (the rms of ln(K_relay / K_measured)), with the relay run
//   here by stability::SimulateRelay (the paper's peak reading).
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/table2.h"
#include "io/reference_models.h"
#include "model/error.h"
#include "model/friction.h"
#include "stability/relay.h"
#include "tests/brute_force.h"

namespace zwidth::analysis {
namespace {

const model::Plant& Table1() {
  static const model::Plant p = io::Table1Model().plant;
  return p;
}

TEST(Table2, LinearPredictionsAreTheExactZWidthOfEveryPoint) {
  Table2Options o;
  o.coulomb_levels = {0.0};
  o.seconds = 2.0;  // the relay is not what this test checks
  const std::vector<io::Table2Point> points = io::Table2Points();
  const Table2Comparison c = CompareTable2(Table1(), 1e-3, points, o);
  ASSERT_EQ(c.rows.size(), points.size());
  int scored = 0;
  for (const Table2Row& r : c.rows) {
    const stability::BruteForce bf(Table1(), 1e-3, r.point.delay_samples);
    const double K = bf.KCritical(r.point.B);
    SCOPED_TRACE("d = " + std::to_string(r.point.delay_samples) + ", B = " + std::to_string(r.point.B));
    if (K > 0.0 && std::isfinite(K)) {
      EXPECT_TRUE(r.scored);
      EXPECT_NEAR(r.linear.K, K, 1e-6 * K);
      EXPECT_NEAR(r.linear.K_rel_error, (K - r.point.K_cr) / r.point.K_cr, 1e-6);
      ++scored;
    } else {
      EXPECT_FALSE(r.scored);  // past the linear B_max: no stable K, nothing to score
      EXPECT_EQ(r.linear.K, K);
    }
  }
  EXPECT_EQ(c.num_scored, scored);
  EXPECT_GE(scored, 10);  // Table II's points inside the linear Z-width
  // The linear error is the rms of the log ratios over those points.
  double sum = 0.0;
  for (const Table2Row& r : c.rows) {
    if (r.scored) sum += std::pow(std::log(r.linear.K / r.point.K_cr), 2);
  }
  EXPECT_NEAR(c.linear_error, std::sqrt(sum / scored), 1e-12);
}

TEST(Table2, BestCoulombLevelIsTheArgminOfTheLogErrorOverAGrid) {
  // The B = 0 column and two moderate-B points (Table II), a grid of 5 levels.
  std::vector<io::Table2Point> points;
  for (const io::Table2Point& p : io::Table2Points()) {
    if (p.B == 0.0 || (p.delay_samples == 4 && p.B == 0.15) || (p.delay_samples == 8 && p.B == 0.08)) points.push_back(p);
  }
  ASSERT_EQ(points.size(), 5u);
  Table2Options o;
  o.coulomb_levels = {0.0, 0.004, 0.008, 0.012, 0.02};
  const Table2Comparison c = CompareTable2(Table1(), 1e-3, points, o);
  // The brute force: every (point, level) relay run here, the error, its argmin.
  double best_error = std::numeric_limits<double>::infinity();
  size_t best = 0;
  for (size_t l = 0; l < o.coulomb_levels.size(); ++l) {
    double sum = 0.0;
    for (size_t j = 0; j < points.size(); ++j) {
      stability::RelayOptions ro;
      ro.delay_samples = points[j].delay_samples;
      ro.damping = points[j].B;
      ro.seconds = 10.0;
      ro.amplitude = 0.1;
      ro.encoder_step = 2.0 * std::numbers::pi / 40960.0;
      ro.friction = model::Friction::Symmetric(o.coulomb_levels[l]);
      ro.refine = false;
      const stability::RelayResult r = stability::SimulateRelay(Table1(), ro);
      ASSERT_GT(r.K_cr_peak, 0.0);
      EXPECT_EQ(c.rows[j].relay[l].K, r.K_cr_peak);
      EXPECT_EQ(c.rows[j].relay[l].f_hz, r.f_cr_peak_hz);
      sum += std::pow(std::log(r.K_cr_peak / points[j].K_cr), 2);
    }
    const double e = std::sqrt(sum / static_cast<double>(points.size()));
    EXPECT_NEAR(c.relay_error[l], e, 1e-12);
    if (e < best_error) { best_error = e; best = l; }
  }
  EXPECT_EQ(c.best_level, best);
  EXPECT_EQ(c.best_coulomb(), o.coulomb_levels[best]);
  // Friction explains these points better than the linear model (docs/friction.md's finding).
  EXPECT_LT(c.relay_error[c.best_level], c.linear_error);
  std::printf("best F_c %g N m: error %.3g (linear %.3g)\n", c.best_coulomb(), c.relay_error[c.best_level],
              c.linear_error);
}

TEST(Table2, RefusesAnotherPeriodAndBadOptionsNamingThem) {
  const std::vector<io::Table2Point> one = {io::Table2Points().front()};
  try {
    CompareTable2(Table1(), 2e-3, one);
    FAIL() << "period 2 ms accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("T = 1 ms"), std::string::npos) << e.what();
  }
  std::string why;
  EXPECT_TRUE(Table2Options{}.IsValid(&why)) << why;
  Table2Options o;
  o.coulomb_levels = {};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("Table2Options::coulomb_levels"), std::string::npos) << why;
  o = {};
  o.coulomb_levels = {0.0, -0.01};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("Table2Options::coulomb_levels"), std::string::npos) << why;
  o = {};
  o.relay_amplitude = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("Table2Options::relay_amplitude"), std::string::npos) << why;
  o = {};
  o.seconds = std::nan("");
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("Table2Options::seconds"), std::string::npos) << why;
  EXPECT_THROW(CompareTable2(Table1(), 1e-3, one, o), InputError);
}

}  // namespace
}  // namespace zwidth::analysis
