// A Monte Carlo sweep of the fit of eq. (1) to simulated logs, for the tests
// of the local estimators (local_fit_test, local_fit_stress_test).
//
// Logs: model::SimulateLog (exact ZOH plant, white torque of 0.03 N m rms at
// 1 kHz, the PHANToM encoder's 2 pi / 40960 rad quantisation, no other noise),
// 30 s, seeds 1..N. LightModes: Table I with the damping ratios of both poles
// and zeros set to 0.01.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "ident/local_models.h"
#include "ident/welch.h"
#include "model/simulate.h"

namespace zwidth {

inline model::Plant LightModes() {
  model::Plant p = model::PhantomTable1();
  for (model::Mode& m : p.modes) {
    m.c = 2 * 0.01 * m.omega;
    m.d = 2 * 0.01 * m.v;
  }
  return p;
}

struct Sweep {
  double rms_m = 0, rms_b = 0;        // relative rms errors
  double std_m = 0, std_b = 0;        // mean reported relative std
  double scatter_m = 0, scatter_b = 0;  // relative std of the estimates about their mean
  double bias_c1 = 0;                  // mean relative error of c_1
  double scatter_c1 = 0, std_c1 = 0;
};

// Fits two sections (delay 0) to `seeds` logs of p estimated by `estimator`
// ("h1", "lpm", "lrm").
inline Sweep MonteCarlo(const model::Plant& p, const std::string& estimator, int seeds) {
  std::vector<double> em, eb, ec, sm, sb, sc;
  for (int s = 1; s <= seeds; ++s) {
    model::SimulateOptions so;
    so.seed = static_cast<uint64_t>(s);
    so.bandwidth_hz = 500.0;
    const model::SimulatedLog log = model::SimulateLog(p, so);
    ident::FrequencyResponse frf;
    if (estimator == "h1") {
      frf = ident::EstimateFrequencyResponse(log.torque, log.position, 1000.0, ident::WelchOptions{});
    } else {
      ident::LocalModelOptions o;
      EXPECT_TRUE(ident::FromString(estimator, &o.method));
      frf = ident::EstimateLocal({{log.torque, log.position, {}}}, 1000.0, o).frf;
    }
    fit::FitOptions fo;
    fo.num_modes = 2;
    const fit::FitResult r = fit::FitModel(frf, fo);
    EXPECT_EQ(r.status, fit::FitStatus::kConverged);
    em.push_back(r.plant.m / p.m - 1);
    eb.push_back(r.plant.b / p.b - 1);
    ec.push_back(r.plant.modes[0].c / p.modes[0].c - 1);
    sm.push_back(r.std_errors.m / p.m);
    sb.push_back(r.std_errors.b / p.b);
    sc.push_back(r.std_errors.modes[0].c / p.modes[0].c);
  }
  auto rms = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x * x;
    return std::sqrt(s / v.size());
  };
  auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s / v.size();
  };
  auto scatter = [&](const std::vector<double>& v) {
    const double mu = mean(v);
    double s = 0;
    for (double x : v) s += (x - mu) * (x - mu);
    return std::sqrt(s / (v.size() - 1));
  };
  Sweep w{rms(em), rms(eb), mean(sm), mean(sb), scatter(em), scatter(eb), mean(ec), scatter(ec), mean(sc)};
  std::printf("%s %d seeds: rms m %.4f %%, b %.4f %%; std/scatter m %.2f, b %.2f, c1 %.2f; c1 bias %.3f %% "
              "(scatter %.3f %%)\n",
              estimator.c_str(), seeds, 100 * w.rms_m, 100 * w.rms_b, w.std_m / w.scatter_m, w.std_b / w.scatter_b,
              w.std_c1 / w.scatter_c1, 100 * w.bias_c1, 100 * w.scatter_c1);
  return w;
}

}  // namespace zwidth
