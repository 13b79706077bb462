// The robust method wired end to end (issue 23 item 2): periodic logs of the
// Table I plant, each one random-phase multisine realisation (lines 1..300 Hz,
// 1 Hz apart, 0.03 N m rms, 2 transient + 4 steady periods of 1000 samples at
// 1 kHz), simulated exactly with and without Coulomb friction
// (model::StickSlipPlant), white sensor noise 1e-6 rad. They are written as
// text logs, estimated by analysis::EstimateFromLogs (estimator robust), the
// response written and read back as the CSV the fit reads, and fitted.
//
// The references: the nonlinear-distortion variance against the noise
// variance the same estimate gives (the distortion is the scatter over the
// realisations the noise does not explain), and for the linear device the
// exact ZOH response of the plant simulated.
#include <cmath>
#include <cstdio>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/logs_estimate.h"
#include "fit/fit.h"
#include "io/frf_file.h"
#include "io/log.h"
#include "model/error.h"
#include "model/nonlinear_simulate.h"
#include "model/plant.h"
#include "model/state_space.h"
#include "tests/test_util.h"

namespace zwidth {
namespace {

constexpr int kPeriod = 1000, kTransient = 2, kPeriods = 4, kLines = 300, kRealisations = 6;

// One realisation of kTransient + kPeriods periods (the transient kept: the
// estimate drops it), phases from `seed`, written to `path`.
void WriteRealisation(const std::string& path, double coulomb, uint64_t seed) {
  const model::Plant plant = model::PhantomTable1();
  model::StickSlipPlant sim(model::ContinuousStateSpace(plant), model::Friction::Symmetric(coulomb), 1e-3);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  std::normal_distribution<double> g(0.0, 1.0);
  const double a = 0.03 / std::sqrt(kLines / 2.0);
  std::vector<double> period(kPeriod, 0.0);
  for (int k = 1; k <= kLines; ++k) {
    const double ph = phase(rng);
    for (int t = 0; t < kPeriod; ++t) period[t] += a * std::cos(2.0 * std::numbers::pi * k * t / kPeriod + ph);
  }
  std::vector<double> u, y;
  for (int p = 0; p < kTransient + kPeriods; ++p) {
    for (int t = 0; t < kPeriod; ++t) {
      y.push_back(sim.position() + 1e-6 * g(rng));
      sim.Step(period[t]);
      u.push_back(period[t]);
    }
  }
  io::WriteLog(path, 1000.0, u, y);
}

struct Device {
  ident::FrequencyResponse frf;  // as read back from the CSV
  fit::FitResult fit;
};

Device EstimateAndFit(double coulomb, const test::TempDir& dir) {
  std::vector<std::string> paths;
  for (int m = 0; m < kRealisations; ++m) {
    paths.push_back(dir / ("r" + std::to_string(m) + ".csv"));
    WriteRealisation(paths.back(), coulomb, 100 + m);
  }
  analysis::LogsEstimateOptions o;
  ident::RobustOptions r;
  r.period_samples = kPeriod;
  r.transient_periods = kTransient;
  r.fmin_hz = 0.5;
  o.robust = r;
  const analysis::LogsEstimate e = analysis::EstimateFromLogs(paths, o);
  EXPECT_EQ(e.response.method, ident::CombinedMethod::kRobust);
  EXPECT_EQ(e.response.frf.estimator, "robust");
  EXPECT_EQ(e.response.frf.f_hz.size(), static_cast<size_t>(kLines));
  const std::string csv = dir / "frf.csv";
  io::WriteFrequencyResponse(csv, e.response.frf);
  Device d;
  d.frf = io::ReadFrequencyResponse(csv);
  EXPECT_EQ(d.frf.noise_var, e.response.frf.noise_var);  // written with 17 digits: read back exactly
  EXPECT_EQ(d.frf.distortion_var, e.response.frf.distortion_var);
  fit::FitOptions fo;
  fo.num_modes = 2;
  d.fit = fit::FitModel(d.frf, fo);
  return d;
}

bool HasReason(const fit::FitResult& r, const std::string& code) {
  for (const auto& q : r.reasons) {
    if (q.code == code) return true;
  }
  return false;
}

double MedianRatio(const ident::FrequencyResponse& r, double below_hz) {
  std::vector<double> v;
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.f_hz[k] < below_hz) v.push_back(r.distortion_var[k] / r.noise_var[k]);
  }
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Coulomb friction (0.005 N m against 0.03 N m rms): below the first section
// the distortion variance is many times the noise variance, and the fit is
// poor with the reason nonlinear_distortion, its advice naming friction.
TEST(RobustFit, CoulombFrictionMakesTheVerdictSayNonlinearDistortion) {
  test::TempDir dir;
  const Device d = EstimateAndFit(0.005, dir);
  ASSERT_EQ(d.frf.distortion_var.size(), d.frf.f_hz.size());
  EXPECT_GT(MedianRatio(d.frf, 30.0), 10.0);
  ASSERT_EQ(d.fit.status, fit::FitStatus::kConverged) << d.fit.message;
  EXPECT_EQ(d.fit.quality, fit::FitQuality::kPoor);
  ASSERT_TRUE(HasReason(d.fit, "nonlinear_distortion")) << d.fit.BriefReport();
  EXPECT_GT(d.fit.distortion_to_noise, 10.0);
  std::printf("friction: distortion/noise %.3g (fit's), %.3g (below 30 Hz); %s\n", d.fit.distortion_to_noise,
              MedianRatio(d.frf, 30.0), d.fit.BriefReport().c_str());
  for (const auto& q : d.fit.reasons) {
    if (q.code == "nonlinear_distortion") EXPECT_NE(q.advice.find("friction"), std::string::npos) << q.advice;
  }
}

// The same device without friction: no distortion above the noise, no such
// reason, and the best linear approximation is the plant's exact ZOH response
// within 6 of its std.
TEST(RobustFit, TheSameDeviceWithoutFrictionShowsNoDistortion) {
  test::TempDir dir;
  const Device d = EstimateAndFit(0.0, dir);
  ASSERT_EQ(d.frf.distortion_var.size(), d.frf.f_hz.size());
  EXPECT_LT(MedianRatio(d.frf, 30.0), 1.0);
  ASSERT_EQ(d.fit.status, fit::FitStatus::kConverged) << d.fit.message;
  EXPECT_FALSE(HasReason(d.fit, "nonlinear_distortion")) << d.fit.BriefReport();
  EXPECT_LT(d.fit.distortion_to_noise, 1.0);
  std::printf("linear: distortion/noise %.3g (fit's), %.3g (below 30 Hz); %s\n", d.fit.distortion_to_noise,
              MedianRatio(d.frf, 30.0), d.fit.BriefReport().c_str());
  const model::DiscreteResponse exact(model::DiscretizeZoh(model::PhantomTable1(), 1e-3));
  for (size_t k = 0; k < d.frf.f_hz.size(); ++k) {
    const std::complex<double> gz = exact.AtTheta(2.0 * std::numbers::pi * d.frf.f_hz[k] / 1000.0);
    EXPECT_LT(std::abs(d.frf.H[k] - gz), 6.0 * std::sqrt(2.0) * d.frf.H_std[k]) << d.frf.f_hz[k];
  }
}

// The options that do not go with it are refused naming the field.
TEST(RobustFit, MissingPeriodAndTooFewPeriodsAreRefusedWithWhatToDo) {
  test::TempDir dir;
  const std::string path = dir / "r.csv";
  WriteRealisation(path, 0.0, 1);
  analysis::LogsEstimateOptions o;
  o.robust = ident::RobustOptions{};
  try {
    analysis::EstimateFromLogs({path}, o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("RobustOptions::period_samples"), std::string::npos) << e.what();
  }
  o.robust->period_samples = kPeriod;
  o.robust->transient_periods = kTransient + kPeriods - 1;
  try {
    analysis::EstimateFromLogs({path}, o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("RobustOptions::transient_periods"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace zwidth
