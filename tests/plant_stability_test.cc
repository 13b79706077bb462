// analysis::AnalysePlantStability, the one Z-width pipeline of `run` and
// `boundary` (issue 24): the rows with several hands, the Monte Carlo and the
// friction amplitudes, each against the stability module called directly
// (one ZWidth per hand from the plant, IsStable at test points,
// SummaryMonteCarlo, PredictFriction), not through the pipeline's own code.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/plant_stability.h"
#include "io/reference_models.h"
#include "model/error.h"
#include "stability/friction_prediction.h"

namespace zwidth::analysis {
namespace {

constexpr double kT = 1e-3;

stability::LoopOptions WithHand(double M, double B, double K) {
  stability::LoopOptions l;
  l.hand = {M, B, K};
  return l;
}

// A diagonal log covariance: relative std 1 % on every parameter.
std::vector<double> DiagonalCovariance(const model::Plant& p) {
  const int n = stability::NumLogParameters(p);
  std::vector<double> cov(n * n, 0.0);
  for (int i = 0; i < n; ++i) cov[i * n + i] = 1e-4;
  return cov;
}

TEST(PlantStability, DefaultOptionsAreValidAndBadOnesNameTheField) {
  std::string why;
  EXPECT_TRUE(PlantStabilityOptions{}.IsValid(&why)) << why;
  using Spoil = std::function<void(PlantStabilityOptions*)>;
  const std::vector<std::pair<Spoil, std::string>> cases = {
      {[](PlantStabilityOptions* o) { o->monte_carlo = -1; }, "PlantStabilityOptions::monte_carlo must be >= 0"},
      {[](PlantStabilityOptions* o) { o->loops[0].hand.K = -1.0; }, "PlantStabilityOptions::loops[0].hand.K"},
      {[](PlantStabilityOptions* o) { o->delays.clear(); }, "PlantStabilityOptions::delays"},
      {[](PlantStabilityOptions* o) { o->grid.b_points = 1; }, "BGridOptions::b_points"},
      {[](PlantStabilityOptions* o) { o->amplitude.k_factor = 0.5; }, "k_factor"},
  };
  for (const auto& [spoil, field] : cases) {
    PlantStabilityOptions o;
    spoil(&o);
    EXPECT_FALSE(o.IsValid(&why)) << field;
    EXPECT_NE(why.find(field), std::string::npos) << why;
  }
}

TEST(PlantStability, SeveralHandsGiveTheRegionStableForEveryHand) {
  const io::ModelFile m = io::Table1Model();
  PlantStabilityOptions o;
  o.delays = {2, 4};
  o.loops = {WithHand(0.001, 0.01, 5), WithHand(0.002, 0.005, 20)};
  o.grid.b_points = 25;
  const PlantStability st = AnalysePlantStability(m, kT, o);
  ASSERT_EQ(st.rows.size(), o.delays.size() * st.b_grid.size());
  ASSERT_EQ(st.loop_summaries.size(), o.delays.size());
  for (size_t i = 0; i < o.delays.size(); ++i) {
    std::vector<stability::ZWidth> each;  // one loop per hand, each from the plant
    for (const stability::LoopOptions& l : o.loops) each.emplace_back(m.plant, kT, o.delays[i], l);
    for (size_t h = 0; h < each.size(); ++h) {
      EXPECT_EQ(st.loop_summaries[i][h].K_cr_max, each[h].Summarize().K_cr_max) << "delay " << o.delays[i];
    }
    // The reported summary is the first hand's loop's, built here on its own.
    EXPECT_EQ(st.summaries[i].B_max, each[0].Summarize().B_max) << "delay " << o.delays[i];
    EXPECT_EQ(st.summaries[i].K_cr_at_zero_B, each[0].Summarize().K_cr_at_zero_B) << "delay " << o.delays[i];
    for (size_t k = 0; k < st.b_grid.size(); ++k) {
      const io::BoundaryRow& row = st.rows[i * st.b_grid.size() + k];
      const double B = st.b_grid[k];
      EXPECT_EQ(row.point.K_cr, std::min(each[0].At(B).K_cr, each[1].At(B).K_cr)) << "B " << B;
      // Inside an interval every hand's loop is stable; just past its upper end some hand's is not.
      for (const stability::KInterval& iv : row.intervals) {
        const double K = std::isfinite(iv.K_hi) ? 0.5 * (iv.K_lo + iv.K_hi) : 2.0 * iv.K_lo + 1.0;
        for (const stability::ZWidth& z : each) EXPECT_TRUE(z.IsStable(K, B)) << "K " << K << " B " << B;
        if (std::isfinite(iv.K_hi)) {
          const double past = iv.K_hi * (1.0 + 1e-4);
          EXPECT_FALSE(each[0].IsStable(past, B) && each[1].IsStable(past, B)) << "K " << past << " B " << B;
        }
      }
    }
  }
}

TEST(PlantStability, StdNeedsOneLoopAndMonteCarloACovariance) {
  io::ModelFile m = io::Table1Model();
  PlantStabilityOptions o;
  o.delays = {2};
  o.grid.b_points = 5;
  o.monte_carlo = 3;
  try {
    AnalysePlantStability(m, kT, o);
    FAIL() << "a Monte Carlo without a covariance ran";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("PlantStabilityOptions::monte_carlo needs a model with"), std::string::npos)
        << e.what();
  }
  m.log_covariance = DiagonalCovariance(m.plant);
  o.loops = {WithHand(0.001, 0.01, 5), WithHand(0.002, 0.005, 20)};
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("PlantStabilityOptions::monte_carlo takes at most one"), std::string::npos) << why;
  o.monte_carlo = 0;
  const PlantStability several = AnalysePlantStability(m, kT, o);
  EXPECT_FALSE(several.has_std);
  EXPECT_TRUE(std::isnan(several.rows[0].K_cr_std));
}

TEST(PlantStability, MonteCarloIsTheStabilityModulesDraws) {
  io::ModelFile m = io::Table1Model();
  m.log_covariance = DiagonalCovariance(m.plant);
  PlantStabilityOptions o;
  o.delays = {2, 4};
  o.grid.b_points = 5;
  o.monte_carlo = 4;
  o.seed = 7;
  std::vector<int> announced;
  o.on_monte_carlo = [&](int d, int n) {
    announced.push_back(d);
    EXPECT_EQ(n, 4);
  };
  const PlantStability st = AnalysePlantStability(m, kT, o);
  EXPECT_EQ(announced, o.delays);
  ASSERT_EQ(st.monte_carlo.size(), 2u);
  EXPECT_TRUE(st.has_std);
  for (size_t i = 0; i < o.delays.size(); ++i) {
    const stability::MonteCarloResult direct =
        stability::SummaryMonteCarlo(m.plant, m.log_covariance, kT, o.delays[i], 4, 7, {});
    EXPECT_EQ(st.monte_carlo[i].std.K_cr_max, direct.std.K_cr_max);
    EXPECT_EQ(st.monte_carlo[i].samples, direct.samples);
  }
  const nlohmann::json j = PlantStabilityJson(st);
  EXPECT_EQ(j["delays"][1]["monte_carlo"]["seed"], 7);
  EXPECT_EQ(j["delays"][0]["delay_samples"], 2);
}

TEST(PlantStability, FrictionRowsArePredictFrictionAtTheirWall) {
  const io::ModelFile m = io::Table1Model();
  PlantStabilityOptions o;
  o.delays = {2};
  o.grid.b_points = 8;
  o.friction = model::Friction::Symmetric(0.01);
  o.amplitude.rows_per_delay = 2;
  const PlantStability st = AnalysePlantStability(m, kT, o);
  ASSERT_EQ(st.friction_amplitudes.size(), st.rows.size());
  const io::BoundaryRow& first = st.rows[0];  // B = b_min = 0 is always computed
  ASSERT_EQ(first.point.B, 0.0);
  const double K = o.amplitude.k_factor * first.point.K_cr;
  const stability::FrictionPrediction p = stability::PredictFriction(
      m.plant, kT, 2, {}, K, 0.0, *o.friction, o.amplitude.encoder_step, o.amplitude.prediction);
  EXPECT_EQ(first.friction_K, K);
  EXPECT_EQ(first.A_star, p.amplitude);
  EXPECT_TRUE(std::isfinite(first.A_star));
  EXPECT_EQ(st.rows[1].A_star_valid, -1);  // between the computed rows
  // Without a Coulomb level nothing is computed.
  o.friction = model::Friction{};
  EXPECT_TRUE(AnalysePlantStability(m, kT, o).friction_amplitudes.empty());
}

}  // namespace
}  // namespace zwidth::analysis
