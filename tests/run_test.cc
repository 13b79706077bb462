// analysis/run.h: analysis::Analyse (the `run` pipeline after the estimate and the fit) on a
// synthetic model (tests/run_input.h), checked against the exact ZOH response
// of model/ and against identities (report::WriteRunReport: run_report_test.cc).
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "analysis/run.h"
#include "model/error.h"
#include "model/state_space.h"
#include "stability/uncertainty.h"
#include "tests/run_input.h"

namespace zwidth {
namespace {

TEST(RunAnalysis, DefaultOptionsAreValidAndFieldsAreNamed) {
  analysis::RunOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.delays = {2, -1};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("RunOptions::delays"), std::string::npos) << why;
  o = {};
  o.report_filter_hz = std::nan("");
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("RunOptions::report_filter_hz"), std::string::npos) << why;
  o.figures = false;  // the filter is the figures' alone
  EXPECT_TRUE(o.IsValid(&why)) << why;
  EXPECT_THROW(analysis::Analyse(TestInput(0.0), analysis::RunOptions{.delays = {-2}}), InputError);
}

TEST(RunAnalysis, BodeIsTheExactZohResponseWithUnwrappedPhases) {
  const double offset = 0.3;  // rad
  const analysis::RunAnalysis a = analysis::Analyse(TestInput(offset), {});
  ASSERT_TRUE(a.figures.has_value());
  const analysis::BodeData& b = a.figures->bode;
  const model::DiscreteResponse g(model::DiscretizeZoh(TestPlant(), kT));
  const auto& f = a.input.response.frf.f_hz;
  ASSERT_EQ(b.G_abs.size(), f.size());
  for (size_t k = 0; k < f.size(); ++k) {
    const std::complex<double> gk = g.AtTheta(2 * std::numbers::pi * f[k] * kT);
    EXPECT_NEAR(b.G_abs[k], std::abs(gk), 1e-9 * std::abs(gk)) << f[k];
    EXPECT_NEAR(b.H_abs[k], std::abs(gk), 1e-9 * std::abs(gk)) << f[k];
    // Same angle modulo a turn, unwrapped: consecutive steps under half a turn,
    // measured exactly `offset` above the model.
    const double turns = (b.G_phase_deg[k] - std::arg(gk) * 180 / std::numbers::pi) / 360;
    EXPECT_NEAR(turns, std::round(turns), 1e-9) << f[k];
    if (k > 0) EXPECT_LT(std::abs(b.G_phase_deg[k] - b.G_phase_deg[k - 1]), 180.0) << f[k];
    EXPECT_NEAR(b.H_phase_deg[k] - b.G_phase_deg[k], offset * 180 / std::numbers::pi, 1e-7) << f[k];
  }
  // The phase falls by more than a turn over the band (delay + ZOH + mode), so
  // the unwrapping was exercised.
  EXPECT_LT(b.G_phase_deg.back() - b.G_phase_deg.front(), -360.0);
  // used_by_fit comes from the fit's band.
  EXPECT_EQ(a.input.response.frf.used_by_fit, a.input.fit.band.used);
}

TEST(RunAnalysis, AModelComparedWithItselfHasTheModelsCurvesAndNoRigidModes) {
  analysis::RunInput in = TestInput(0.0);
  in.reference = in.model;
  in.reference_name = "self";
  analysis::RunOptions o;
  o.delays = {1, 3};
  const analysis::RunAnalysis a = analysis::Analyse(std::move(in), o);
  ASSERT_TRUE(a.comparison.has_value());
  ASSERT_TRUE(a.figures.has_value());
  const analysis::PlantStability& st = a.stability;
  const size_t nB = st.b_grid.size();
  ASSERT_EQ(a.figures->kcr_reference.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    for (size_t k = 0; k < nB; ++k) {
      EXPECT_EQ(a.figures->kcr_reference[i][k].K_cr, st.rows[i * nB + k].point.K_cr);
    }
    // The rigid body alone (modes removed): its K_CR(B=0) differs from the model's.
    EXPECT_NE(a.figures->kcr_rigid[i][0].K_cr, st.rows[i * nB].point.K_cr);
  }
  // The loop figure: 300 B values from 0 per delay, its filtered region inside [0, top].
  ASSERT_EQ(a.figures->loop.size(), 2u);
  EXPECT_EQ(a.figures->loop[0].B.size(), 300u);
  EXPECT_EQ(a.figures->loop[0].B.front(), 0.0);
  std::vector<std::string> names;
  for (const auto& s : a.stages) names.push_back(s.name);
  EXPECT_EQ(names, (std::vector<std::string>{"boundary", "compare (reference Z-width)", "figure data (reference, rigid)"}));
}

// The reference's Z-width computed beforehand (as `run` does while the fit
// runs) gives the comparison and the curves computed in Analyse, exactly; one
// for another period or other delays is not used.
TEST(RunAnalysis, AReferenceComputedBeforehandGivesTheSameComparison) {
  analysis::RunOptions o;
  o.delays = {1, 3};
  auto input = [&] {
    analysis::RunInput in = TestInput(0.0);
    model::Plant other = in.model.plant;
    other.m *= 1.3;
    in.reference = io::ModelFile{};
    in.reference->plant = other;
    in.reference_name = "other";
    return in;
  };
  const analysis::RunAnalysis plain = analysis::Analyse(input(), o);
  analysis::RunInput in = input();
  in.reference_stability = analysis::ReferenceStabilityOf(*in.reference, kT, o.delays);
  const analysis::RunAnalysis given = analysis::Analyse(std::move(in), o);
  analysis::RunInput stale = input();
  stale.reference_stability = analysis::ReferenceStabilityOf(*stale.reference, kT, {1, 4});  // other delays
  const analysis::RunAnalysis redone = analysis::Analyse(std::move(stale), o);
  ASSERT_TRUE(plain.comparison && given.comparison && redone.comparison);
  EXPECT_EQ(given.comparison->text, plain.comparison->text);
  EXPECT_EQ(given.comparison->json, plain.comparison->json);
  EXPECT_EQ(redone.comparison->text, plain.comparison->text);
  EXPECT_EQ(given.stages[1].name, "compare");
  EXPECT_EQ(redone.stages[1].name, "compare (reference Z-width)");
  for (size_t i = 0; i < 2; ++i) {
    for (size_t k = 0; k < plain.stability.b_grid.size(); ++k) {
      EXPECT_EQ(given.figures->kcr_reference[i][k].K_cr, plain.figures->kcr_reference[i][k].K_cr);
    }
  }
}

// The Bode figure's model band against a Monte Carlo written here: parameter
// draws from the covariance (Cholesky of C, seeded), each plant's exact ZOH
// response from model/ (not the SampledPlant the band uses), and the scatter
// of ln|G| and of the phase at a few bins.
TEST(RunAnalysis, ModelBandIsTheCovarianceSpreadOfTheResponse) {
  analysis::RunInput in = TestInput(0.0);
  const size_t p = static_cast<size_t>(stability::NumLogParameters(in.model.plant));
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(p, p);
  for (size_t i = 0; i < p; ++i) C(i, i) = std::pow(1e-4 * (1.0 + i), 2);  // small: the delta method is linear
  C(0, 1) = C(1, 0) = 0.5 * std::sqrt(C(0, 0) * C(1, 1));  // m and b correlated
  in.model.log_covariance.assign(C.data(), C.data() + p * p);
  const analysis::RunAnalysis a = analysis::Analyse(std::move(in), {});
  ASSERT_TRUE(a.figures.has_value());
  const analysis::BodeData& bd = a.figures->bode;
  ASSERT_EQ(bd.G_log_abs_std.size(), a.input.response.frf.f_hz.size());
  const Eigen::MatrixXd L = C.llt().matrixL();
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01;
  const std::vector<size_t> bins = {4, 39, 59, 99, 299};  // 5, 40 (zero), 60 (pole), 100, 300 Hz
  const model::Plant plant = TestPlant();
  const model::DiscreteResponse g0(model::DiscretizeZoh(plant, kT));
  std::vector<double> s_abs(bins.size()), s_ph(bins.size());
  const int draws = 4000;
  for (int k = 0; k < draws; ++k) {
    Eigen::VectorXd z(p);
    for (size_t i = 0; i < p; ++i) z(i) = n01(rng);
    const Eigen::VectorXd x = L * z;
    const model::DiscreteResponse g(
        model::DiscretizeZoh(stability::PerturbLog(plant, std::vector<double>(x.data(), x.data() + p)), kT));
    for (size_t j = 0; j < bins.size(); ++j) {
      const double th = 2 * std::numbers::pi * a.input.response.frf.f_hz[bins[j]] * kT;
      const std::complex<double> d = std::log(g.AtTheta(th) / g0.AtTheta(th));
      s_abs[j] += d.real() * d.real() / draws;
      s_ph[j] += d.imag() * d.imag() / draws;
    }
  }
  for (size_t j = 0; j < bins.size(); ++j) {
    SCOPED_TRACE(bins[j]);
    // 4000 draws: the std of a std estimate is ~1.1 %; 5 % allows the curvature.
    EXPECT_NEAR(bd.G_log_abs_std[bins[j]] / std::sqrt(s_abs[j]), 1.0, 0.05);
    EXPECT_NEAR(bd.G_phase_std_deg[bins[j]] * std::numbers::pi / 180 / std::sqrt(s_ph[j]), 1.0, 0.05);
  }
  // Without a covariance: no band.
  EXPECT_TRUE(analysis::Analyse(TestInput(0.0), {}).figures->bode.G_log_abs_std.empty());
}

}  // namespace
}  // namespace zwidth
