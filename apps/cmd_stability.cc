#include <cmath>
#include <cstdio>
#include <iostream>

#include "apps/common.h"
#include "io/atomic_file.h"
#include "io/model_json.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "stability/relay.h"
#include "stability/zwidth.h"

namespace zwidth::app {
namespace {

// --period when given, else the model's sample_period_s, else 1 ms.
}  // namespace

double ResolvePeriod(double flag, const io::ModelFile& mf) {
  if (std::isnan(flag)) return mf.sample_period_s ? *mf.sample_period_s : 0.001;
  if (!(flag > 0.0 && std::isfinite(flag))) {
    throw InputError("--period = " + std::to_string(flag) + " s: must be finite and > 0");
  }
  return flag;
}

namespace {

void CheckDelay(int d, const char* flag) {
  if (d < 0) throw InputError(std::string(flag) + " = " + std::to_string(d) + ": delays must be >= 0 samples");
}

}  // namespace

void AddStabilityCommands(CLI::App& app) {
  // ---- boundary
  struct BoundaryFlags {
    std::string model, out, summary;
    std::vector<int> delays = {2, 4, 8};
    double period = kNotGiven, b_min = 0.0, b_max = -1.0, b_step = 0.0005;
  };
  auto bf = std::make_shared<BoundaryFlags>();
  CLI::App* b = app.add_subcommand("boundary", "exact Z-width K_CR(B) and the paper's margin reading, per delay");
  b->add_option("model", bf->model, "model JSON")->required();
  b->add_option("--delays", bf->delays, "loop delays in samples, e.g. 2,4,8")->delimiter(',')->capture_default_str();
  b->add_option("--period", bf->period, "sample period T [s] (default: the model's, else 0.001)");
  b->add_option("--b-min", bf->b_min, "first B [N m s/rad]")->capture_default_str();
  b->add_option("--b-max", bf->b_max, "last B [N m s/rad] (default: just past the largest B_max)");
  b->add_option("--b-step", bf->b_step, "B step [N m s/rad]")->capture_default_str();
  b->add_option("-o,--output", bf->out, "boundary CSV")->required();
  b->add_option("--summary", bf->summary, "summary JSON (B_t, K_CR^max, B_max, ... per delay)");
  b->callback([bf] {
    io::CheckOutputFolder(bf->out);
    if (!bf->summary.empty()) io::CheckOutputFolder(bf->summary);
    const io::ModelFile mf = io::ReadModelJson(bf->model);
    const double T = ResolvePeriod(bf->period, mf);
    if (bf->delays.empty()) throw InputError("--delays is empty");
    for (int d : bf->delays) CheckDelay(d, "--delays");
    if (!(bf->b_step > 0.0 && std::isfinite(bf->b_step))) throw InputError("--b-step must be > 0");
    if (!(bf->b_min >= 0.0 && std::isfinite(bf->b_min))) throw InputError("--b-min must be >= 0");
    std::vector<stability::ZWidth> zs;
    std::vector<stability::DelaySummary> sums;
    for (int d : bf->delays) {
      zs.emplace_back(mf.plant, T, d);
      sums.push_back(zs.back().Summarize());
    }
    double b_max = bf->b_max;
    if (b_max < 0.0) {
      double largest = 0.0;
      for (const auto& s : sums) if (std::isfinite(s.B_max)) largest = std::max(largest, s.B_max);
      b_max = largest > 0.0 ? 1.02 * largest : 0.4;
    }
    if (!(b_max >= bf->b_min)) throw InputError("--b-max must be >= --b-min");
    const long count = static_cast<long>(std::floor((b_max - bf->b_min) / bf->b_step + 1e-9)) + 1;
    if (count > 10000000 / static_cast<long>(bf->delays.size())) throw InputError("too many B values; raise --b-step");
    std::vector<io::BoundaryRow> rows;
    int disagree = 0;
    for (size_t i = 0; i < zs.size(); ++i) {
      for (long k = 0; k < count; ++k) {
        const double B = bf->b_min + k * bf->b_step;
        io::BoundaryRow r{bf->delays[i], zs[i].At(B)};
        if (!r.point.AgreesWithMargin()) ++disagree;
        rows.push_back(r);
      }
    }
    io::WriteBoundaryCsv(bf->out, rows);
    nlohmann::json js;
    js["period_s"] = T;
    js["model"] = mf.plant.name;
    js["delays"] = nlohmann::json::array();
    for (size_t i = 0; i < sums.size(); ++i) {
      nlohmann::json e = io::SummaryToJson(sums[i]);
      e["delay_samples"] = bf->delays[i];
      e["total_delay_samples"] = sums[i].delay_samples;
      js["delays"].push_back(e);
    }
    js["margin_disagreements"] = disagree;
    if (!bf->summary.empty()) io::WriteTextAtomically(bf->summary, js.dump(2) + "\n");
    std::printf("%-6s %12s %10s %10s %12s %10s %10s %10s\n", "delay", "K_cr(B=0)", "f(B=0)", "B_t",
                "K_cr^max", "f_before", "f_after", "B_max");
    for (size_t i = 0; i < sums.size(); ++i) {
      const auto& s = sums[i];
      std::printf("%-6d %12.6g %10.5g %10.6g %12.6g %10.5g %10.5g %10.6g\n", bf->delays[i],
                  s.K_cr_at_zero_B, s.f_at_zero_B_hz, s.B_t, s.K_cr_max, s.f_before_hz, s.f_after_hz,
                  s.B_max);
    }
    std::printf("%d of %zu rows: the margin() reading of eq. (4) differs from the exact K_CR "
                "(mostly B past B_max, where margin() stays positive but no K is stable)\n",
                disagree, rows.size());
  });

  // ---- relay
  struct RelayFlags {
    std::string model, trace;
    stability::RelayOptions o;
    double period = kNotGiven;
    bool json = false;
  };
  auto rf = std::make_shared<RelayFlags>();
  CLI::App* r = app.add_subcommand("relay", "simulate the relay experiment of section IV (Fig. 9)");
  r->add_option("model", rf->model, "model JSON")->required();
  r->add_option("--delay", rf->o.delay_samples, "loop delay [samples]")->required();
  r->add_option("--damping", rf->o.damping, "virtual damping B [N m s/rad]")->required();
  r->add_option("--period", rf->period, "sample period T [s] (default: the model's, else 0.001)");
  r->add_option("--amplitude", rf->o.amplitude, "relay amplitude [N m]")->capture_default_str();
  r->add_option("--seconds", rf->o.seconds, "simulated time [s]")->capture_default_str();
  r->add_flag("--json", rf->json, "print only JSON on standard output");
  r->add_option("-o,--output", rf->trace, "trace CSV (t, relay, damping, command, position)");
  r->callback([rf] {
    if (!rf->trace.empty()) io::CheckOutputFolder(rf->trace);
    const io::ModelFile mf = io::ReadModelJson(rf->model);
    rf->o.period_s = ResolvePeriod(rf->period, mf);
    CheckDelay(rf->o.delay_samples, "--delay");
    std::fprintf(stderr, "simulating %.3g s of relay feedback (d = %d, B = %g)...\n", rf->o.seconds,
                 rf->o.delay_samples, rf->o.damping);
    const stability::RelayResult res = stability::SimulateRelay(mf.plant, rf->o);
    if (!res.oscillating && !res.diverged) throw ComputationError("the relay loop did not oscillate");
    const stability::ZWidth z(mf.plant, rf->o.period_s, rf->o.delay_samples);
    const stability::CriticalPoint cp = z.At(rf->o.damping);
    if (!rf->trace.empty()) {
      io::WriteAtomically(rf->trace, [&](const std::string& tmp) {
        std::FILE* f = std::fopen(tmp.c_str(), "wb");
        if (!f) throw InputError("cannot create '" + tmp + "'");
        std::fputs("t,relay_force,damping_force,command,position\n", f);
        for (size_t k = 0; k < res.position.size(); ++k) {
          std::fprintf(f, "%.9g,%.9g,%.9g,%.9g,%.12g\n", k * rf->o.period_s, res.relay_force[k],
                       res.damping_force[k], res.command[k], res.position[k]);
        }
        if (std::fclose(f) != 0) throw InputError("failed writing '" + rf->trace + "'");
      });
    }
    nlohmann::json j = {{"K_cr", io::NumberOrNull(res.K_cr)}, {"f_cr_hz", io::NumberOrNull(res.f_cr_hz)},
                        {"refined", res.refined}, {"diverged", res.diverged},
                        {"K_cr_peak", io::NumberOrNull(res.K_cr_peak)},
                        {"f_cr_peak_hz", io::NumberOrNull(res.f_cr_peak_hz)}, {"relay_runs", res.relay_runs},
                        {"unsettled", res.unsettled},
                        {"uncertainty", io::NumberOrNull(res.uncertainty)}, {"below_band", res.below_band},
                        {"band_low_hz", io::NumberOrNull(res.band_low_hz)},
                        {"K_cr_exact", io::NumberOrNull(cp.K_cr)},
                        {"f_cr_exact_hz", io::NumberOrNull(cp.f_cr_hz)},
                        {"delay_samples", rf->o.delay_samples}, {"B", rf->o.damping},
                        {"period_s", rf->o.period_s}};
    if (res.refined && !(res.uncertainty <= 1e-3)) {
      std::fprintf(stderr,
                   "warning: the estimate is uncertain to about %.2g%% (L from the two halves of the steady part "
                   "differs by %.2g%%, the oscillation was still settling); simulate longer with --seconds\n",
                   100.0 * res.uncertainty, 100.0 * res.unsettled);
    }
    if (res.below_band) {
      std::fprintf(stderr,
                   "warning: the relay run at %.3g Hz, the lowest this record resolves (20 cycles in the steady part), "
                   "is already past -180 deg: the critical crossing lies below it; simulate longer with --seconds\n",
                   res.band_low_hz);
    }
    if (rf->json) {
      std::cout << j.dump() << std::endl;
    } else if (res.diverged) {
      std::printf("relay: the loop diverges with the relay alone, so no K > 0 is stable here (B past B_max): "
                  "K_cr = 0\n");
    } else {
      std::printf("relay, paper's reading (spectral peak, first harmonics): K_cr = %.6g N m/rad at %.5g Hz\n",
                  res.K_cr_peak, res.f_cr_peak_hz);
      std::printf("relay, -180 deg crossings measured by steered runs:    K_cr = %.6g N m/rad at %.5g Hz%s\n",
                  res.K_cr, res.f_cr_hz, res.refined ? "" : " (no crossing found: the paper's reading)");
    }
    if (!rf->json) {
      std::printf("exact (eq. 2):                                          K_cr = %.6g N m/rad at %.5g Hz\n",
                  cp.K_cr, cp.f_cr_hz);
    }
  });

  // ---- check
  struct CheckFlags {
    std::string scene, model;
    int delay = -1;
    double period = kNotGiven;
    bool json = false;
  };
  auto cf = std::make_shared<CheckFlags>();
  CLI::App* c = app.add_subcommand("check", "is each object of a haptic scene stable on this device?");
  c->add_option("scene", cf->scene, "scene JSON {\"objects\": [{\"name\", \"K\", \"B\"}]}")->required();
  c->add_option("--model", cf->model, "model JSON")->required();
  c->add_option("--delay", cf->delay, "loop delay [samples]")->required();
  c->add_option("--period", cf->period, "sample period T [s] (default: the model's, else 0.001)");
  c->add_flag("--json", cf->json, "print only JSON on standard output");
  c->callback([cf] {
    const io::ModelFile mf = io::ReadModelJson(cf->model);
    CheckDelay(cf->delay, "--delay");
    const double T = ResolvePeriod(cf->period, mf);
    const std::vector<io::SceneObject> objs = io::ReadScene(cf->scene);
    const stability::ZWidth z(mf.plant, T, cf->delay);
    nlohmann::json out = {{"delay_samples", cf->delay}, {"period_s", T}, {"objects", nlohmann::json::array()}};
    for (const auto& o : objs) {
      const stability::CriticalPoint cp = z.At(o.B);
      const bool stable = cp.K_cr > 0.0 && o.K < cp.K_cr;
      const double ratio = cp.K_cr > 0.0 ? o.K / cp.K_cr : std::numeric_limits<double>::infinity();
      out["objects"].push_back({{"name", o.name}, {"K", o.K}, {"B", o.B}, {"stable", stable},
                                {"K_cr", io::NumberOrNull(cp.K_cr)},
                                {"f_cr_hz", io::NumberOrNull(cp.f_cr_hz)},
                                {"K_over_K_cr", io::NumberOrNull(ratio)},
                                {"unstable_at_any_K", cp.unstable_at_zero_k}});
      if (!cf->json) {
        std::printf("%-20s K = %-10g B = %-8g %s  K_cr = %-10.5g K/K_cr = %.3g\n", o.name.c_str(), o.K,
                    o.B, stable ? "stable  " : "UNSTABLE", cp.K_cr, ratio);
      }
    }
    if (cf->json) std::cout << out.dump() << std::endl;
  });
}

}  // namespace zwidth::app
