// A synthetic run input for the tests of analysis::Analyse and
// report::WriteRunReport: a PHANToM-like model and, as the "measured" response,
// its exact ZOH response.
#pragma once

#include <complex>
#include <numbers>

#include "analysis/run.h"
#include "model/state_space.h"

namespace zwidth {

inline constexpr double kT = 1e-3;

inline model::Plant TestPlant() {  // a PHANToM-like device: inertia, damping, one mode, three samples of delay
  model::Plant p;
  p.m = 2e-3;
  p.b = 5e-3;
  const double w = 2 * std::numbers::pi * 60, v = 2 * std::numbers::pi * 40;
  p.modes.push_back({w, 0.1 * w, v, 0.1 * v});
  p.delay_samples = 3;
  return p;
}

// The "measured" response: the model's exact ZOH response turned by
// phase_offset [rad] (so the unwrapped phases differ by exactly that).
inline analysis::RunInput TestInput(double phase_offset) {
  analysis::RunInput in;
  in.model.plant = TestPlant();
  in.model.sample_period_s = kT;
  in.fit.status = fit::FitStatus::kConverged;
  in.fit.plant = in.model.plant;
  ident::FrequencyResponse& frf = in.response.frf;
  frf.sample_rate_hz = 1 / kT;
  const model::DiscreteResponse g(model::DiscretizeZoh(in.model.plant, kT));
  for (int k = 1; k <= 450; ++k) {
    frf.f_hz.push_back(k);
    frf.H.push_back(g.AtTheta(2 * std::numbers::pi * k * kT) * std::polar(1.0, phase_offset));
    frf.coherence.push_back(1.0);
    frf.H_std.push_back(0.01 * std::abs(frf.H.back()));
    frf.S_uu.push_back(1.0);  // unit input PSD: S_yy = |H|^2, S_uy = H
    frf.S_yy.push_back(std::norm(frf.H.back()));
    frf.S_uy.push_back(frf.H.back());
    in.fit.band.used.push_back(k >= 5 && k <= 300);
  }
  in.total_samples = 30000;
  in.source = "synthetic";
  in.logs = {"synthetic"};
  return in;
}

}  // namespace zwidth
