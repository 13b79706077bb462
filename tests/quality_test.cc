// The fit's judgement of itself (fit/quality.cc): the excited band, the
// quality verdict, short logs (order selection: order_test.cc). Logs are
// simulated by SimulateLog (tests/fit_devices.h), seeded, 1 kHz.
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "fit/fit_internal.h"
#include "ident/welch.h"
#include "model/error.h"
#include "model/plant.h"
#include "model/simulate.h"
#include "tests/fit_devices.h"

namespace zwidth::fit {
namespace {

TEST(FitQuality, UnderFittedLogIsPoor) {
  FitOptions o;
  o.num_modes = 2;
  const FitResult r = FitModel(Frf(Device(kPoles[3]), 21), o);
  ASSERT_EQ(r.status, FitStatus::kConverged);
  EXPECT_EQ(r.quality, FitQuality::kPoor);
  bool chi2 = false;
  for (const auto& q : r.reasons) chi2 |= q.code == "chi2_per_dof";
  EXPECT_TRUE(chi2);
}

TEST(FitQuality, OneModeTooManyIsFlagged) {
  FitOptions o;
  o.num_modes = 3;
  const FitResult r = FitModel(Frf(Device(kPoles[2]), 22), o);
  ASSERT_EQ(r.status, FitStatus::kConverged);
  EXPECT_EQ(r.quality, FitQuality::kPoor);
  // The extra section is named: spurious, or (a pole-zero pair 0.06 % apart
  // with damping 1e-3, on the bins of the band rule of issue 29) narrower
  // than the window's bins.
  bool narrow = false;
  for (const auto& q : r.reasons) narrow |= q.code == "mode_narrower_than_bins";
  EXPECT_TRUE(!SpuriousSections(r, o).empty() || narrow);
}

TEST(FitQuality, OneSegmentLogIsRefusedUnlessAllowed) {
  const ident::FrequencyResponse frf = Frf(model::PhantomTable1(), 23, 5.0);  // 5 s < two 4096-sample windows
  ASSERT_EQ(frf.num_averages, 1);
  FitOptions o;
  try {
    FitModel(frf, o);
    ADD_FAILURE() << "a one-segment log was fitted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("WelchOptions::window_length"), std::string::npos) << m;
    EXPECT_NE(m.find("FitOptions::allow_few_averages"), std::string::npos) << m;
  }
  o.allow_few_averages = true;
  const FitResult r = FitModel(frf, o);
  EXPECT_EQ(r.quality, FitQuality::kPoor);
  bool few = false;
  for (const auto& q : r.reasons) few |= q.code == "few_averages";
  EXPECT_TRUE(few);
}

TEST(FitQuality, InputStoppingAtTenHertzIsFittedOnlyBelowIt) {
  // The torque is band-limited to 10 Hz (the simulator's windowed-sinc low
  // pass: -6 dB at 10 Hz, over 20 dB down by 12 Hz); above, the "response" is
  // encoder noise over nothing.
  const ident::FrequencyResponse frf = Frf(Device({}), 24, 60, 10.0);
  FitOptions o;
  o.num_modes = 0;
  const FitResult r = FitModel(frf, o);
  ASSERT_EQ(r.status, FitStatus::kConverged);
  EXPECT_LE(r.band.f_hi_hz, 12.0);
  EXPECT_GT(r.band.num_low_input, 1000);
  for (size_t k = 0; k < frf.f_hz.size(); ++k) {
    if (frf.f_hz[k] > 12.0) EXPECT_EQ(r.band.used[k], 0) << frf.f_hz[k];
  }
  EXPECT_NEAR(r.plant.m / model::PhantomTable1().m, 1.0, 0.05);
}

TEST(FitQuality, BandLimitsApplyToAGivenResponse) {
  const ident::FrequencyResponse frf = Frf(Device(kPoles[1]), 25);
  FitOptions o;
  o.num_modes = 0;
  o.band.fmin_hz = 2;
  o.band.fmax_hz = 20;
  const FitResult r = FitModel(frf, o);
  EXPECT_GE(r.band.f_lo_hz, 2.0);
  EXPECT_LE(r.band.f_hi_hz, 20.0);
  EXPECT_EQ(r.num_residuals / 2, r.band.num_used);
}

// A very lightly damped mode (zeta 0.001 at 120 Hz, half-power bandwidth
// 0.24 Hz, about one bin of the default 4096-sample window at 1 kHz): Welch
// leakage widens the measured peak, so the fitted damping is biased up. The
// fit must say so (poor, code mode_narrower_than_bins); with a window 16
// times longer the section spans several bins, the reason goes, and the
// fitted pole damping c is at most half as far from the truth.
TEST(FitQuality, AModeNarrowerThanTwoBinsIsFlagged) {
  const double w = 2 * std::numbers::pi * 120, v = 2 * std::numbers::pi * 100;
  const model::Plant p{1e-3, 5e-3, {{w, 2 * 0.001 * w, v, 2 * 0.001 * v}}};
  model::SimulateOptions so;
  so.seed = 27;
  so.seconds = 240;
  so.encoder_step_rad = 1e-7;  // fine enough that quantisation does not hide the mode
  const model::SimulatedLog log = model::SimulateLog(p, so);
  FitOptions o;
  o.num_modes = 1;
  auto narrow = [](const FitResult& r) {
    bool n = false;
    for (const auto& q : r.reasons) n |= q.code == "mode_narrower_than_bins";
    return n;
  };
  ident::WelchOptions wo;
  const FitResult short_w = FitModel(ident::EstimateFrequencyResponse(log.torque, log.position, 1000, wo), o);
  ASSERT_EQ(short_w.status, FitStatus::kConverged);
  EXPECT_TRUE(narrow(short_w));
  EXPECT_EQ(short_w.quality, FitQuality::kPoor);
  wo.window_length = 65536;
  const FitResult long_w = FitModel(ident::EstimateFrequencyResponse(log.torque, log.position, 1000, wo), o);
  ASSERT_EQ(long_w.status, FitStatus::kConverged);
  EXPECT_FALSE(narrow(long_w));
  const double bias_short = short_w.plant.modes[0].c / p.modes[0].c - 1, bias_long = long_w.plant.modes[0].c / p.modes[0].c - 1;
  std::printf("pole damping c: %+.2f %% with 4096 samples, %+.2f %% with 65536\n", 100 * bias_short, 100 * bias_long);
  EXPECT_LT(std::abs(bias_long), 0.5 * std::abs(bias_short));
}

TEST(FitQuality, SixSampleDelayIsFoundAutomatically) {
  model::SimulateOptions so;
  so.seed = 26;
  so.delay_samples = 6;
  const model::SimulatedLog log = model::SimulateLog(model::PhantomTable1(), so);
  const auto frf = ident::EstimateFrequencyResponse(log.torque, log.position, 1000, ident::WelchOptions{});
  FitOptions o;
  o.auto_delay = true;
  const FitResult r = FitModel(frf, o);
  EXPECT_EQ(r.plant.delay_samples, 6) << r.delay_choice;
  EXPECT_EQ(r.quality, FitQuality::kGood) << (r.reasons.empty() ? "" : r.reasons[0].message);
  EXPECT_FALSE(r.delay_choice.empty());
}

// The advice of a poor fit is assembled from optional parts (more modes, a
// delay, a band): whatever the options leave out, it must read as one
// sentence ("...: or a band" was written when both optional parts were
// empty). Residuals of one sign over 300 bins set off both chi2_per_dof and
// residual_runs for every combination of auto_modes, auto_delay and an order
// search at its limit.
TEST(FitQuality, AdviceReadsAsOneSentenceWhateverTheOptions) {
  EXPECT_EQ(internal::Alternatives({}), "");
  EXPECT_EQ(internal::Alternatives({"", "a", ""}), "a");
  EXPECT_EQ(internal::Alternatives({"a", "", "b"}), "a or b");
  EXPECT_EQ(internal::Alternatives({"a", "b", "c"}), "a, b, or c");
  for (int mask = 0; mask < 8; ++mask) {
    internal::Fixed fx;
    for (int k = 0; k < 300; ++k) {
      fx.f_hz.push_back(1.0 + k);
      fx.r.push_back({3.0, 3.0});
    }
    fx.res.chi2_per_dof = 50;
    fx.res.num_residuals = 600;
    fx.res.num_parameters = 2;
    fx.res.plant = model::PhantomTable1();
    ident::FrequencyResponse sub;
    sub.num_averages = 20;
    FitOptions o;
    o.auto_modes = mask & 1;
    o.auto_delay = mask & 2;
    o.max_modes = (mask & 4) ? 2 : 4;
    internal::JudgeQuality(fx, sub, o, &fx.res);
    int judged = 0;
    for (const auto& q : fx.res.reasons) {
      if (q.code != "chi2_per_dof" && q.code != "residual_runs") continue;
      ++judged;
      for (const char* bad : {": or ", "try or ", ", ,", ", or or", "  ", ": ,", "try ,"}) {
        EXPECT_EQ(q.advice.find(bad), std::string::npos) << "mask " << mask << ": '" << bad << "' in " << q.advice;
      }
      EXPECT_NE(q.advice.back(), ' ') << q.advice;
      EXPECT_NE(q.advice.back(), ',') << q.advice;
    }
    EXPECT_EQ(judged, 2) << "mask " << mask;
  }
}

TEST(FitQuality, SectionsAreNamedFromOneInCanonicalOrder) {
  FitResult r;
  r.plant = Device({100, 200});
  r.plant.modes[1].v = r.plant.modes[1].omega;  // section 2's pole cancelled by its zero
  r.plant.modes[1].d = r.plant.modes[1].c;
  r.std_errors = r.plant;
  for (model::Mode& m : r.std_errors.modes) m = {1, 1, 1, 1};
  const auto s = SpuriousSections(r, FitOptions{});
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].rfind("section 2:", 0), 0u) << s[0];
}

}  // namespace
}  // namespace zwidth::fit

namespace zwidth::fit {
namespace {

// The leakage bound of a Hann window (fit/quality.cc, LeakageChecks): a peak
// of half-power bandwidth bw [Hz] is widened by (4/3) (df / bw)^2 relative.
// Written here for a section 0.3 bins wide (df / bw = 1 / 0.3 is not under 2
// bins: r = df / bw = 0.3 < 0.5, so no reason): the bound, 0.12 of c, is
// 0.61 rad/s; with a damping std of 0.1 it is over 3 std and the warning
// names the local rational method, with a std of 1 it is under and nothing is said.
TEST(FitQuality, TheLeakageBoundAboveThreeStdSuggestsTheLocalRationalMethod) {
  ident::FrequencyResponse sub;
  sub.sample_rate_hz = 1000.0;
  sub.window_length = 4096;
  sub.bin_correlation = 1.94;
  const double df = 1000.0 / 4096, bw = df / 0.3, c = 2 * std::numbers::pi * bw;
  const double bound = 4.0 / 3.0 * 0.3 * 0.3 * c;  // 0.61 rad/s
  for (const double sd : {0.1, 1.0}) {
    FitResult r;
    r.plant = model::Plant{1e-3, 5e-3, {{2 * std::numbers::pi * 100, c, 2 * std::numbers::pi * 80, 1e3}}};
    r.std_errors = model::Plant{0, 0, {{1, sd, 1, 1e3}}};
    internal::LeakageChecks(sub, &r);
    EXPECT_TRUE(r.reasons.empty());
    bool lrm = false;
    for (const std::string& w : r.warnings) lrm |= w.find("LocalModelOptions::method lrm") != std::string::npos;
    EXPECT_EQ(lrm, bound > 3 * sd) << "sd " << sd << ", bound " << bound;
    EXPECT_EQ(lrm, sd == 0.1);
  }
}

// The robust method's check (fit/quality.cc, DistortionCheck) on a response
// written here: bins below half the lowest section frequency decide; a
// median distortion/noise ratio of 4 there makes the reason, 0.25 does not,
// and the distortion above the section (not where m and b are set) does not count.
TEST(FitQuality, DistortionAboveTheNoiseWhereTheRigidBodyIsSetIsAReason) {
  for (const double low_ratio : {4.0, 0.25}) {
    ident::FrequencyResponse sub;
    FitResult r;
    r.plant = model::Plant{1e-3, 5e-3, {{2 * std::numbers::pi * 100, 50, 2 * std::numbers::pi * 80, 50}}};
    for (int k = 1; k <= 200; ++k) {
      sub.f_hz.push_back(k);
      sub.noise_var.push_back(1e-10);
      sub.distortion_var.push_back(k < 40 ? low_ratio * 1e-10 : 100e-10);
    }
    internal::DistortionCheck(sub, &r);
    bool reason = false;
    for (const auto& q : r.reasons) reason |= q.code == "nonlinear_distortion";
    EXPECT_EQ(reason, low_ratio > 1) << low_ratio;
    EXPECT_DOUBLE_EQ(r.distortion_to_noise, low_ratio);
  }
}

}  // namespace
}  // namespace zwidth::fit

namespace zwidth::fit {
namespace {

// Chi2SmallSampleLaw against a Monte Carlo of the estimators written here:
// per bin, n segments U_i (complex normal), Y_i = H U_i + N_i, H1 = sum
// conj(U) Y / sum |U|^2, its std from the coherence by ident::CoherenceStd
// (per component), and the chi2 of the true H, |H1 - H|^2 / (2 std^2); and m
// runs' estimates H + e_i, their mean and its textbook standard error from
// their scatter. The law's mean must be the measured one.
TEST(FitQuality, ChiSquareOfTheTrueResponseWithAnEstimatedStdHasTheMeanOfTheFLaw) {
  std::mt19937_64 rng(20261204);
  std::normal_distribution<double> g(0.0, std::sqrt(0.5));
  const std::complex<double> H(0.3, -1.2);
  auto mean_chi2 = [&](int n) {
    const int bins = 400000 / n;
    double sum = 0.0;
    for (int b = 0; b < bins; ++b) {
      double suu = 0.0, syy = 0.0;
      std::complex<double> suy = 0.0;
      for (int i = 0; i < n; ++i) {
        const std::complex<double> u(g(rng), g(rng)), y = H * u + 0.7 * std::complex<double>(g(rng), g(rng));
        suu += std::norm(u);
        syy += std::norm(y);
        suy += std::conj(u) * y;
      }
      const std::complex<double> h = suy / suu;
      const double sd = ident::CoherenceStd(std::abs(h), std::norm(suy) / (suu * syy), n);
      sum += std::norm(h - H) / (2.0 * sd * sd);
    }
    return sum / bins;
  };
  auto mean_chi2_of_runs = [&](int m) {
    const int bins = 400000 / m;
    double sum = 0.0;
    for (int b = 0; b < bins; ++b) {
      std::vector<std::complex<double>> h(m);
      std::complex<double> mean = 0.0;
      for (auto& x : h) mean += (x = H + 0.3 * std::complex<double>(g(rng), g(rng)));
      mean /= m;
      double ss = 0.0;
      for (const auto& x : h) ss += std::norm(x - mean);
      const double se2 = ss / (m - 1.0) / m;  // the complex variance of the mean, from the scatter
      sum += std::norm(mean - H) / se2;       // over 2 dof, each of half that variance
    }
    return sum / bins;
  };
  for (int n : {3, 4, 6, 8, 13}) {
    ident::FrequencyResponse frf;
    frf.estimator = "welch-h1";
    frf.effective_averages = n;
    const double measured = mean_chi2(n), law = Chi2SmallSampleLaw(frf).expected;
    std::printf("n = %2d: mean chi2 of the true H %.4f, the law %.4f\n", n, measured, law);
    // n = 3: F(2, 4) has no finite variance; its sample mean converges slowly.
    EXPECT_NEAR(measured / law, 1.0, n == 3 ? 0.08 : 0.02) << n;
    frf.estimator = "";  // read from a file: the Welch law only for overlapped segments
    frf.num_averages = n;
    EXPECT_EQ(Chi2SmallSampleLaw(frf).n, 0.0);  // effective = num: a local method's dof, or no overlap
    frf.effective_averages = n - 0.1;
    EXPECT_NEAR(Chi2SmallSampleLaw(frf).expected, (n - 0.1) / (n - 2.1), 1e-12);
    frf.effective_averages = n;
    frf.estimator = "welch-h1-runs";
    const double runs = mean_chi2_of_runs(n), runs_law = Chi2SmallSampleLaw(frf).expected;
    std::printf("m = %2d runs: mean chi2 of the true H %.4f, the law %.4f\n", n, runs, runs_law);
    EXPECT_NEAR(runs / runs_law, 1.0, n == 3 ? 0.08 : 0.02) << n;
    frf.estimator = "lpm";  // its own dof: no law, no scaling
    EXPECT_EQ(Chi2SmallSampleFactor(frf), 1.0);
  }
}

// A right model on a 10 s log (the default window leaves 3 segments): chi2/dof
// near 3, as the law says; before the factor (2026-12-04) every such fit was
// poor ("chi2/dof 2.93 is above 1.66") with advice to look for aliasing.
// A model one section short, and one a sample of delay off (a near miss the
// sections bend to absorb), are still poor there.
TEST(FitQuality, TenSecondLogOfARightModelIsGoodAndAMissingSectionStillPoor) {
  for (uint64_t seed : {31, 32, 33}) {
    const model::Plant p = Device(kPoles[1]);
    model::SimulateOptions so;
    so.seed = seed;
    so.seconds = 10;
    so.bandwidth_hz = 450;
    const model::SimulatedLog log = model::SimulateLog(p, so);
    const ident::FrequencyResponse frf = ident::EstimateFrequencyResponse(
        log.torque, log.position, 1000.0, ident::WelchOptions{.window_length = ident::DefaultWindowLength(1000.0, log.torque.size())});
    ASSERT_EQ(frf.num_averages, 3);
    FitOptions o;
    o.num_modes = 1;
    const FitResult r = FitModel(frf, o);
    ASSERT_EQ(r.status, FitStatus::kConverged);
    std::printf("seed %d: chi2/dof %.3f, %s\n", static_cast<int>(seed), r.chi2_per_dof, ToString(r.quality).c_str());
    EXPECT_GT(r.chi2_per_dof, 2.0);  // the small-sample inflation is real
    EXPECT_EQ(r.quality, FitQuality::kGood) << r.BriefReport();
    bool warned = false;
    for (const std::string& w : r.warnings) warned |= w.find("averages (segments, or runs)") != std::string::npos;
    EXPECT_TRUE(warned);
    o.num_modes = 0;
    const FitResult under = FitModel(frf, o);
    EXPECT_EQ(under.quality, FitQuality::kPoor);
    o.num_modes = 1;
    o.auto_delay = false;
    o.delay_samples = 1;  // the device has none
    const FitResult late = FitModel(frf, o);
    std::printf("seed %d, delay 1 off: chi2/dof %.3f, %s\n", static_cast<int>(seed), late.chi2_per_dof,
                ToString(late.quality).c_str());
    EXPECT_EQ(late.quality, FitQuality::kPoor);
  }
}

}  // namespace
}  // namespace zwidth::fit
