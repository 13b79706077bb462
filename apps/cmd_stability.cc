#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <cstdio>
#include <iostream>
#include <memory>

#include "analysis/friction_amplitude.h"
#include "analysis/plant_stability.h"
#include "analysis/scene_check.h"
#include "apps/common.h"
#include "apps/friction_flags.h"
#include "flags/loop_flags.h"
#include "io/atomic_file.h"
#include "io/loop_text.h"
#include "io/model_json.h"
#include "io/printable.h"
#include "io/provenance.h"
#include "io/stability_files.h"
#include "model/error.h"
#include "model/units.h"
#include "stability/cutoff_sweep.h"
#include "stability/friction_prediction.h"
#include "stability/loop_options.h"
#include "stability/passivity.h"
#include "stability/relay.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::app {
namespace {

void CheckDelay(int d, const char* flag) {
  if (const std::string why = io::LoopDelaysProblem({d}, flag); !why.empty()) throw InputError(why);
}

// The summary table, per-hand lines, passivity and the margin() count on stdout.
void PrintBoundarySummary(const analysis::PlantStability& t, const io::ModelFile& mf) {
  const std::vector<int>& delays = t.delays;
  const std::vector<stability::LoopOptions>& loops = t.loops;
  std::printf("delay: the loop's; the Z-width is computed for it plus the model's input delay:");
  for (size_t i = 0; i < delays.size(); ++i) {
    std::printf("%s %s", i ? ";" : "", io::DelayText(delays[i], mf.plant.delay_samples).c_str());
  }
  std::printf("\n%-6s %12s %10s %10s %12s %10s %10s %12s %12s\n", "delay", "K_cr(B=0)", "f(B=0)", "B_t",
              "K_cr^max", "f_before", "f_after", "B_max_0", "B_max");
  for (size_t i = 0; i < t.summaries.size(); ++i) {
    const auto& s = t.summaries[i];
    std::printf("%-6d %12.6g %10.5g %10.6g %12.6g %10.5g %10.5g %12.6g %12.6g\n", delays[i],
                s.K_cr_at_zero_B, s.f_at_zero_B_hz, s.B_t, s.K_cr_max, s.f_before_hz, s.f_after_hz,
                s.B_max_from_zero, s.B_max);
    if (t.has_std) {
      std::printf("  std   %12.3g %10s %10.3g %12.3g %10s %10s %12s %12.3g\n", t.stds[i].K_cr_at_zero_B, "",
                  t.stds[i].B_t, t.stds[i].K_cr_max, "", "", "", t.stds[i].B_max);
    }
    for (const auto& band : s.reopened_bands) {
      std::printf("  reopened band: B in (%.6g, %.6g), largest stable K %.6g\n", band.B_lo, band.B_hi, band.K_max);
    }
    for (const auto& j : s.frequency_jumps) {
      std::printf("  f_CR jumps at B = %.6g: K_CR %.6g -> %.6g, f_CR %.5g -> %.5g Hz%s\n", j.B, j.K_before, j.K_after,
                  j.f_before_hz, j.f_after_hz, j.B == s.B_t ? " (B_t)" : "");
    }
    if (!s.polynomial_test) std::printf("  %s\n", stability::StabilityTestNote(s).c_str());
    if (!s.conditioning_warning.empty()) std::printf("  warning: %s\n", s.conditioning_warning.c_str());
  }
  std::printf("B_max_0: where the interval from K = 0+ closes; B_max: the largest B with some stable K > 0\n");
  if (loops.size() > 1) {
    for (size_t i = 0; i < t.summaries.size(); ++i) {
      for (size_t h = 0; h < loops.size(); ++h) {
        const auto& s = t.loop_summaries[i][h];
        std::printf("  d = %d, hand M %g B %g K %g: K_cr(0) %.6g, K_cr^max %.6g, B_max %.6g\n", delays[i],
                    loops[h].hand.M, loops[h].hand.B, loops[h].hand.K, s.K_cr_at_zero_B, s.K_cr_max, s.B_max);
      }
    }
    std::printf("the boundary CSV holds the region stable for every hand (intersection of the intervals)\n");
  }
  for (size_t i = 0; i < t.summaries.size(); ++i) {
    const stability::PassiveInterval p0 = t.passivity[i].At(0.0);
    std::printf("d = %d passivity (Colgate-Schenkel, b = %g): K_P(0) = %.6g; passive up to B = %.6g\n",
                delays[i], mf.plant.b, p0.K_hi, io::PassiveBMax(t.passivity[i], mf.plant.b));
  }
  std::printf("%d of %zu B values: the margin() reading of eq. (4) differs from the exact K_CR "
              "(mostly B past B_max_0, where margin() stays positive but K -> 0+ is unstable)\n",
              t.margin_disagreements, t.rows.size());
}

// zwidth boundary: the stable K intervals per B, K_CR(B) and the summary per delay.
void AddBoundaryCommand(CLI::App& app) {
  struct BoundaryFlags {
    std::string model, out, summary;
    std::vector<int> delays = {2, 4, 8};
    double period = kNotGiven;
    stability::BGridOptions grid;
    int monte_carlo = 0;
    std::uint64_t seed = 1;
    LoopFlags loop;
    FrictionFlags friction;
    analysis::FrictionAmplitudeOptions amplitude;
    double encoder_step = kNotGiven;  // else the model's
  };
  auto bf = std::make_shared<BoundaryFlags>();
  CLI::App* b = app.add_subcommand("boundary", "exact Z-width: stable K intervals per B, K_CR(B), summary, per delay");
  b->add_option("model", bf->model, "model JSON")->required();
  b->add_option("--delays", bf->delays, "loop delays in samples, e.g. 2,4,8")->delimiter(',')->capture_default_str();
  b->add_option("--period", bf->period, "sample period T [s] (default: the model's, else 0.001)");
  b->add_option("--b-min", bf->grid.b_min, "first B [N m s/rad]")->capture_default_str();
  b->add_option("--b-max", bf->grid.b_max, "last B [N m s/rad] (default: 1.05 x the largest stable B)");
  b->add_option("--b-step", bf->grid.b_step, "B step [N m s/rad] (wins over --b-points)");
  b->add_option("--b-points", bf->grid.b_points, "number of B values when --b-step is not given")->capture_default_str();
  b->add_option("-o,--output", bf->out, "boundary CSV")->required();
  b->add_option("--summary", bf->summary, "summary JSON (B_t, K_CR^max, B_max, bands, std ... per delay)");
  b->add_option("--monte-carlo", bf->monte_carlo, "also sample the parameter covariance N times and report the "
                "sample std beside the delta method's (0 = off)")->capture_default_str();
  AddSeedOption(b, &bf->seed, "seed of --monte-carlo");
  AddLoopFlags(b, &bf->loop);
  AddFrictionFlags(b, &bf->friction);
  b->add_option("--encoder-step", bf->encoder_step, kEncoderStepHelp);
  b->add_option("--amplitude-k-factor", bf->amplitude.k_factor,
                "with friction: the amplitude A* below which friction holds a wall at this multiple of K_cr(B)")
      ->capture_default_str();
  b->callback([bf] {
    // The inputs: the model and a velocity filter file (text "b:..;a:.." is no file and matches nothing).
    const std::vector<std::string> inputs = {bf->model, bf->loop.filter_coeffs};
    io::CheckOutputFolder(bf->out, inputs);
    io::CheckOutputKind(bf->out, "a boundary CSV", io::kCsvExtensions);
    if (!bf->summary.empty()) io::CheckOutputFolder(bf->summary, inputs);
    if (!bf->summary.empty()) io::CheckOutputKind(bf->summary, "a summary JSON", {".json"});
    if (bf->out == "-" && bf->summary == "-") {
      throw InputError("-o - and --summary - would both write to standard output, mixed beyond parsing: write one "
                       "of them to a file");
    }
    io::ModelFile mf = io::ReadModelJsonFor(bf->model, "boundary");  // not const: --period may convert its delay
    const double T = ResolvePeriod(bf->period, &mf);
    analysis::PlantStabilityOptions o;
    o.delays = bf->delays;
    o.loops = ResolveLoops(bf->loop, T);
    o.grid = bf->grid;
    o.monte_carlo = bf->monte_carlo;
    o.seed = bf->seed;
    o.friction = ResolveFriction(bf->friction, mf);
    o.amplitude = bf->amplitude;
    o.amplitude.encoder_step = analysis::EncoderStepOf(mf, Given(bf->encoder_step), "--encoder-step");
    o.on_monte_carlo = [](int d, int n) { std::fprintf(stderr, "Monte Carlo, d = %d: %d samples...\n", d, n); };
    std::string why;
    if (!o.IsValid(&why)) throw InputError(WithFlags(why));
    if (!mf.log_covariance.empty() && o.loops.size() > 1) {
      std::fprintf(stderr, "note: the std columns are not computed with several hands\n");
    }
    const analysis::PlantStability t = [&] {
      try {
        return analysis::AnalysePlantStability(mf, T, o);
      } catch (const InputError& e) {
        throw InputError(WithFlags(e.what()));
      }
    }();
    // The summary before any file: a failure leaves nothing written.
    nlohmann::json js = analysis::PlantStabilityJson(t);
    js["provenance"] = io::ProvenanceJson();
    io::WriteBoundaryCsv(bf->out, t.rows);
    if (!bf->summary.empty()) io::WriteTextAtomically(bf->summary, js.dump(2) + "\n");
    for (size_t i = 0; i < t.monte_carlo.size(); ++i) {
      const stability::MonteCarloResult& mc = t.monte_carlo[i];
      const stability::SummaryStd& sd = t.stds[i];
      std::printf("d = %d  std by delta method / Monte Carlo (%d samples): K_cr(0) %.4g / %.4g, B_t %.4g / %.4g, "
                  "K_cr^max %.4g / %.4g, B_max %.4g / %.4g\n",
                  t.delays[i], mc.samples, sd.K_cr_at_zero_B, mc.std.K_cr_at_zero_B, sd.B_t, mc.std.B_t, sd.K_cr_max,
                  mc.std.K_cr_max, sd.B_max, mc.std.B_max);
    }
    PrintBoundarySummary(t, mf);
    const std::vector<analysis::FrictionAmplitudeRow>& amps = t.friction_amplitudes;
    for (size_t i = 0; i < t.delays.size() && !amps.empty(); ++i) {
      std::printf("%s\n", analysis::FrictionSummaryLine(amps, t.delays[i], t.friction_options, model::Units(mf.linear)).c_str());
    }
    if (!amps.empty()) {
      std::printf("friction (Coulomb %g %s): the CSV's A_star column [%s] at %d B values per delay (docs/friction.md)\n",
                  t.friction.MeanCoulomb(), model::Units(mf.linear).input, model::Units(mf.linear).position,
                  t.friction_options.rows_per_delay);
    }
  });
}

// zwidth filter-sweep: the velocity low-pass cut-off that maximises a Z-width measure.
void AddFilterSweepCommand(CLI::App& app) {
  struct SweepFlags {
    std::string model, out;
    int delay = -1;
    double period = kNotGiven;
    double f_min = 5.0, f_max = kNotGiven;
    int points = 40;
    std::string measure = "kcr-max";
    double area_b_max = kNotGiven;
    std::vector<std::string> hands;
  };
  auto sf = std::make_shared<SweepFlags>();
  CLI::App* sw = app.add_subcommand("filter-sweep", "sweep the cut-off of a first-order velocity low-pass and report "
                                    "the one that maximises the Z-width by a stated measure");
  sw->add_option("model", sf->model, "model JSON")->required();
  sw->add_option("--delay", sf->delay, "loop delay [samples]")->required();
  sw->add_option("--period", sf->period, "sample period T [s] (default: the model's, else 0.001)");
  sw->add_option("--f-min", sf->f_min, "lowest cut-off [Hz]")->capture_default_str();
  sw->add_option("--f-max", sf->f_max, "highest cut-off [Hz] (default: Nyquist/2)");
  sw->add_option("--points", sf->points, "cut-offs, log-spaced, in [2, 10000]")->capture_default_str();
  sw->add_option("--measure", sf->measure, "kcr-max (K_CR^max) or area (area of the stable (B, K) set for "
                 "0 <= B <= --area-b-max, K_hi = inf counted to the largest finite K of the sweep)")->capture_default_str();
  sw->add_option("--area-b-max", sf->area_b_max, "upper B of the area measure [N m s/rad] (default: B_max without filter)");
  sw->add_option("--hand", sf->hands, "the user's hand M,B,K (SI) kept in the loop while sweeping");
  sw->add_option("-o,--output", sf->out, "CSV cutoff_hz,measure");
  sw->callback([sf] {
    if (!sf->out.empty()) io::CheckOutputFolder(sf->out, {sf->model});
    if (!sf->out.empty()) io::CheckOutputKind(sf->out, "a CSV of cutoff_hz,measure", io::kCsvExtensions);
    io::ModelFile mf = io::ReadModelJsonFor(sf->model, "filter-sweep");  // not const: --period may convert its delay
    CheckDelay(sf->delay, "--delay");
    const double T = ResolvePeriod(sf->period, &mf);
    const double f_max = std::isnan(sf->f_max) ? 0.25 / T : sf->f_max;
    if (!(sf->f_min > 0.0 && f_max > sf->f_min && f_max < 0.5 / T)) {
      throw InputError("--f-min/--f-max: need 0 < f-min < f-max < Nyquist (" + std::to_string(0.5 / T) + " Hz)");
    }
    if (sf->points < 2 || sf->points > 10000) throw InputError("--points must be in [2, 10000]");
    if (sf->hands.size() > 1) throw InputError("filter-sweep takes one --hand");
    stability::LoopOptions loop;
    if (!sf->hands.empty()) loop.hand = io::ParseHand(sf->hands[0]);
    stability::CutoffSweepOptions o;
    o.measure = stability::SweepMeasureFromString(sf->measure);
    for (int i = 0; i < sf->points; ++i) {
      o.cutoffs_hz.push_back(sf->f_min * std::pow(f_max / sf->f_min, double(i) / (sf->points - 1)));
    }
    if (o.measure == stability::SweepMeasure::kArea) {
      const stability::ZWidth z0(mf.plant, T, sf->delay, loop);
      const stability::DelaySummary s0 = z0.Summarize();
      o.area_B_max = std::isnan(sf->area_b_max) ? s0.B_max : sf->area_b_max;
      if (!(o.area_B_max > 0.0 && std::isfinite(o.area_B_max))) {
        throw InputError("--area-b-max: give a finite B > 0 (the loop without filter has no finite B_max > 0)");
      }
      o.area_K_clip = 4.0 * std::max(s0.K_cr_max, s0.K_cr_at_zero_B);
    }
    const stability::CutoffSweepResult r = stability::SweepCutoff(mf.plant, T, sf->delay, loop, o);
    if (!sf->out.empty()) {
      std::string csv = "cutoff_hz,measure\n";
      char line[80];
      for (size_t i = 0; i < r.cutoffs_hz.size(); ++i) {
        std::snprintf(line, sizeof line, "%.9g,%.12g\n", r.cutoffs_hz[i], r.measure[i]);
        csv += line;
      }
      io::WriteTextAtomically(sf->out, csv);
    }
    if (r.best < 0) throw ComputationError("no cut-off gave a finite measure");
    std::printf("measure %s (%s); delay %d, T = %g s, %zu cut-offs from %g to %g Hz\n", sf->measure.c_str(),
                (o.measure == stability::SweepMeasure::kKcrMax
                     ? "K_CR^max [" + std::string(model::Units(mf.linear).K) + "]"
                     : "area [" + std::string(model::Units(mf.linear).K) + " x " + model::Units(mf.linear).B + "]")
                    .c_str(),
                sf->delay, T, r.cutoffs_hz.size(), r.cutoffs_hz.front(), r.cutoffs_hz.back());
    std::printf("best cut-off %.5g Hz: %.6g (lowest %.5g Hz: %.6g; highest %.5g Hz: %.6g; without filter: %.6g)\n",
                r.cutoffs_hz[r.best], r.measure[r.best], r.cutoffs_hz.front(), r.measure.front(), r.cutoffs_hz.back(),
                r.measure.back(), r.unfiltered);
    if (r.unfiltered >= r.measure[r.best]) {
      std::printf("no cut-off in the sweep beats the loop without a velocity filter (%.6g >= %.6g)\n", r.unfiltered,
                  r.measure[r.best]);
    }
    if (r.best_at_edge) {
      std::printf("the best lies at the %s end of the sweep: the optimum may be outside it (%s)\n",
                  r.best == 0 ? "lower" : "upper", r.best == 0 ? "lower --f-min" : "raise --f-max, up to Nyquist");
    }
  });
}

// zwidth relay: the relay experiment of section IV, beside the exact K_CR.
// The relay's trace CSV (t, relay force, damping force, command, position), atomically.
void WriteRelayTrace(const std::string& path, const stability::RelayResult& res, double period_s) {
  io::WriteAtomically(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw InputError("cannot create '" + tmp + "'");
    std::fputs("t,relay_force,damping_force,command,position\n", f);
    for (size_t k = 0; k < res.position.size(); ++k) {
      std::fprintf(f, "%.9g,%.9g,%.9g,%.9g,%.12g\n", k * period_s, res.relay_force[k],
                   res.damping_force[k], res.command[k], res.position[k]);
    }
    if (std::fclose(f) != 0) throw InputError("failed writing '" + path + "'");
  });
}

// relay --json: the relay's result beside the exact critical point cp.
nlohmann::json RelayJson(const stability::RelayResult& res, const stability::CriticalPoint& cp,
                         const stability::RelayOptions& o) {
  return {{"K_cr", io::NumberOrNull(res.K_cr)}, {"f_cr_hz", io::NumberOrNull(res.f_cr_hz)},
          {"status", stability::ToString(res.status)},
          {"refined", res.refined()}, {"diverged", res.status == stability::RelayStatus::kDiverged},
          {"K_cr_peak", io::NumberOrNull(res.K_cr_peak)},
          {"f_cr_peak_hz", io::NumberOrNull(res.f_cr_peak_hz)}, {"relay_runs", res.relay_runs},
          {"unsettled", res.unsettled},
          {"uncertainty", io::NumberOrNull(res.uncertainty)}, {"below_band", res.status == stability::RelayStatus::kBelowBand},
          {"band_low_hz", io::NumberOrNull(res.band_low_hz)},
          {"K_cr_exact", io::NumberOrNull(cp.K_cr)},
          {"f_cr_exact_hz", io::NumberOrNull(cp.f_cr_hz)},
          {"delay_samples", o.delay_samples}, {"B", o.damping},
          {"period_s", o.period_s},
          {"nonlinear", o.Nonlinear()}, {"encoder_step", o.encoder_step},
          {"friction", {{"coulomb_pos", o.friction.coulomb_pos}, {"coulomb_neg", o.friction.coulomb_neg},
                        {"offset", o.friction.offset}, {"breakaway_pos", o.friction.StaticPos()},
                        {"breakaway_neg", o.friction.StaticNeg()}}},
          {"actuator", {{"saturation", o.actuator.saturation}, {"dac_step", o.actuator.dac_step}}}};
}

// Warnings on stderr: an unsettled estimate, a crossing below the record's band.
void WarnRelay(const stability::RelayResult& res) {
  if (res.refined() && !(res.uncertainty <= 1e-3)) {
    std::fprintf(stderr,
                 "warning: the estimate is uncertain to about %.2g%% (L from the two halves of the steady part "
                 "differs by %.2g%%, the oscillation was still settling); simulate longer with --seconds\n",
                 100.0 * res.uncertainty, 100.0 * res.unsettled);
  }
  if (res.status == stability::RelayStatus::kBelowBand) {
    std::fprintf(stderr,
                 "warning: the relay run at %.3g Hz, the lowest this record resolves (20 cycles in the steady part), "
                 "is already past -180 deg: the critical crossing lies below it; simulate longer with --seconds\n",
                 res.band_low_hz);
  }
}

// The relay's readings and the exact K_cr on stdout, or the JSON alone.
void PrintRelay(const stability::RelayResult& res, const stability::CriticalPoint& cp, const nlohmann::json& j,
                bool json, const model::UnitLabels& u) {
  if (json) {
    nlohmann::json out = j;
    out["provenance"] = io::ProvenanceJson();
    std::cout << out.dump() << std::endl;
  } else if (res.status == stability::RelayStatus::kDiverged) {
    std::printf("relay: the loop diverges with the relay alone, so K -> 0+ is unstable here (B past B_max_from_zero): "
                "K_cr = 0\n");
  } else {
    std::printf("relay, paper's reading (spectral peak, first harmonics): K_cr = %.6g %s at %.5g Hz\n",
                res.K_cr_peak, u.K, res.f_cr_peak_hz);
    std::printf("relay, -180 deg crossings measured by steered runs:    K_cr = %.6g %s at %.5g Hz%s\n",
                res.K_cr, u.K, res.f_cr_hz, res.refined() ? "" : " (no crossing found: the paper's reading)");
  }
  if (!json) {
    if (std::isfinite(cp.f_cr_hz)) {
      std::printf("exact (eq. 2, with this loop's filter and hand):        K_cr = %.6g %s at %.5g Hz\n",
                  cp.K_cr, u.K, cp.f_cr_hz);
    } else {  // K_cr = 0 past B_max_from_zero: no crossing, so no frequency
      std::printf("exact (eq. 2, with this loop's filter and hand):        K_cr = %.6g %s (no crossing)\n",
                  cp.K_cr, u.K);
    }
  }
}

void AddRelayCommand(CLI::App& app) {
  struct RelayFlags {
    std::string model, trace;
    stability::RelayOptions o;
    double period = kNotGiven;
    bool json = false;
    LoopFlags loop;
    FrictionFlags friction;
    double encoder_step = kNotGiven;  // else the model's
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
  r->add_option("--encoder-step", rf->encoder_step, kEncoderStepHelp);
  AddLoopFlags(r, &rf->loop);
  AddFrictionFlags(r, &rf->friction);
  r->callback([rf] {
    if (!rf->trace.empty()) io::CheckOutputFolder(rf->trace, {rf->model});
    if (!rf->trace.empty()) io::CheckOutputKind(rf->trace, "a trace CSV", io::kCsvExtensions);
    io::ModelFile mf = io::ReadModelJsonFor(rf->model, "relay");  // not const: --period may convert its delay
    rf->o.period_s = ResolvePeriod(rf->period, &mf);
    CheckDelay(rf->o.delay_samples, "--delay");
    const std::vector<stability::LoopOptions> loops = ResolveLoops(rf->loop, rf->o.period_s);
    if (loops.size() != 1) throw InputError("relay: give at most one --hand (the experiment runs one loop)");
    rf->o.loop = loops.front();
    rf->o.friction = ResolveFriction(rf->friction, mf);
    rf->o.actuator = ResolveActuator(rf->friction);
    rf->o.encoder_step = analysis::EncoderStepOf(mf, Given(rf->encoder_step), "--encoder-step");
    std::string why;
    if (!rf->o.IsValid(&why)) throw InputError(why);  // the fields' flags: io/option_names.cc
    std::fprintf(stderr, "simulating %.3g s of relay feedback (d = %d, B = %g)...\n", rf->o.seconds,
                 rf->o.delay_samples, rf->o.damping);
    const stability::RelayResult res = stability::SimulateRelay(mf.plant, rf->o);
    if (res.status == stability::RelayStatus::kNoOscillation) {
      throw ComputationError("the relay loop did not oscillate");
    }
    const stability::ZWidth z(mf.plant, rf->o.period_s, rf->o.delay_samples, rf->o.loop);
    const stability::CriticalPoint cp = z.At(rf->o.damping);
    if (!rf->trace.empty()) WriteRelayTrace(rf->trace, res, rf->o.period_s);
    const nlohmann::json j = RelayJson(res, cp, rf->o);
    WarnRelay(res);
    PrintRelay(res, cp, j, rf->json, model::Units(mf.linear));
  });
}

// One line of `zwidth check`: the object, its status, the interval holding K
// (or the nearest), K_cr and, with a std, the distance to the nearest boundary.
void PrintObjectCheck(const analysis::ObjectCheck& c, const io::SceneObject& o, const std::string& note) {
  const io::ObjectVerdict& v = c.verdict;
  const int k = v.stable ? v.interval : v.nearest_interval;
  char buf[200];
  std::string where = "no K > 0 is stable at this B";
  if (k >= 0) {
    std::snprintf(buf, sizeof buf, "%s (%.6g, %.6g)", v.stable ? "in" : "nearest stable K", v.intervals[k].K_lo,
                  v.intervals[k].K_hi);
    where = buf;
  }
  std::string sigma;
  if (std::isfinite(c.sigmas_to_boundary)) {
    std::snprintf(buf, sizeof buf, "  %+.3g std from the boundary K = %.6g +- %.3g (%s)", c.sigmas_to_boundary,
                  c.boundary_K, c.boundary_K_std, v.stable ? "nominally stable" : "nominally unstable");
    sigma = buf;
  }
  const char* status = c.status == analysis::SceneStatus::kStable     ? "stable  "
                       : c.status == analysis::SceneStatus::kMarginal ? "marginal"
                                                                      : "UNSTABLE";
  std::printf("%-20s K = %-10g B = %-8g %s  %s  K_cr = %-10.5g%s%s\n", io::Printable(o.name).c_str(), o.K, o.B,
              status, where.c_str(), v.critical.K_cr, sigma.c_str(), note.c_str());
}

// check, an unstable object on a device with friction (the first hand's loop):
// the amplitude below which friction still holds it, into *j and as a note.
std::string FrictionNote(const model::Plant& plant, double T, int delay, const stability::LoopOptions& loop,
                         const io::SceneObject& o, const model::Friction& friction, double encoder_step,
                         const model::UnitLabels& units, nlohmann::json* j) {
  if (!(friction.MeanCoulomb() > 0.0)) return "";
  const stability::FrictionPrediction p =
      stability::PredictFriction(plant, T, delay, loop, o.K, o.B, friction, encoder_step);
  (*j)["friction"] = analysis::FrictionPredictionJson(p);
  if (p.verdict != stability::FrictionVerdict::kStableBelow) return "";
  return "  friction holds it below " + Num(p.amplitude) + " " + units.position +
         (p.valid ? "" : " (outside validity: " + p.invalid_reason + ")");
}

// zwidth check: is each object of a haptic scene stable on this device?
void AddCheckCommand(CLI::App& app) {
  struct CheckFlags {
    std::string scene, model;
    int delay = -1;
    double period = kNotGiven;
    bool json = false;
    LoopFlags loop;
    FrictionFlags friction;
    double encoder_step = kNotGiven;  // else the model's
    analysis::SceneCheckOptions options;
  };
  auto cf = std::make_shared<CheckFlags>();
  CLI::App* c = app.add_subcommand("check", "is each object of a haptic scene stable on this device?");
  c->add_option("scene", cf->scene, "scene JSON {\"objects\": [{\"name\", \"K\", \"B\"}]}")->required();
  c->add_option("--model", cf->model, "model JSON")->required();
  c->add_option("--delay", cf->delay, "loop delay [samples]")->required();
  c->add_option("--period", cf->period, "sample period T [s] (default: the model's, else 0.001)");
  c->add_flag("--json", cf->json, "print only JSON on standard output");
  c->add_option("--marginal-sigmas", cf->options.marginal_sigmas,
                "with a model covariance: an object within this many std of the nearest boundary is 'marginal' "
                "(exit 4 when none is unstable); 0: off (default 2)");
  AddLoopFlags(c, &cf->loop);
  AddFrictionFlags(c, &cf->friction);
  c->add_option("--encoder-step", cf->encoder_step, kEncoderStepHelp);
  c->callback([cf] {
    io::ModelFile mf = io::ReadModelJsonFor(cf->model, "check --model");  // not const: --period may convert its delay
    CheckDelay(cf->delay, "--delay");
    const double T = ResolvePeriod(cf->period, &mf);
    const std::vector<io::SceneObject> objs = io::ReadScene(cf->scene);
    const std::vector<stability::LoopOptions> loops = ResolveLoops(cf->loop, T);
    const model::Friction friction = ResolveFriction(cf->friction, mf);
    const double encoder_step = analysis::EncoderStepOf(mf, Given(cf->encoder_step), "--encoder-step");
    const analysis::SceneCheck sc = analysis::CheckScene(mf.plant, mf.log_covariance, T, cf->delay, loops, objs, cf->options);
    if (!mf.log_covariance.empty() && !sc.has_std) std::fprintf(stderr, "note: no std (and no marginal status) with several hands\n");
    nlohmann::json out = analysis::SceneCheckJson(sc, objs, cf->delay, T, cf->options);
    io::AddDelays(&out, cf->delay, mf.plant.delay_samples);
    if (!cf->json) std::printf("delay: %s\n", io::DelayText(cf->delay, mf.plant.delay_samples).c_str());
    for (size_t i = 0; i < objs.size(); ++i) {
      nlohmann::json scratch;
      nlohmann::json* j = out.contains("objects") && i < out["objects"].size() ? &out["objects"][i] : &scratch;
      // The friction prediction for an object the linear loop does not hold.
      const std::string note = sc.objects[i].verdict.stable ? ""
                                   : FrictionNote(mf.plant, T, cf->delay, loops[0], objs[i], friction,
                                                  encoder_step, model::Units(mf.linear), j);
      if (!cf->json) PrintObjectCheck(sc.objects[i], objs[i], note);
    }
    out["provenance"] = io::ProvenanceJson();
    if (cf->json) std::cout << out.dump() << std::endl;
    const int code = sc.num_unstable > 0 ? 3 : sc.num_marginal > 0 ? 4 : 0;
    if (code != 0 && !cf->json) {
      std::printf("%d of %zu objects unstable, %d marginal (within %g std of a boundary) (exit status %d)\n",
                  sc.num_unstable, objs.size(), sc.num_marginal, cf->options.marginal_sigmas, code);
    }
    if (code != 0) throw ExitStatus{code};  // documented: 3 some object unstable, 4 none unstable but some marginal
  });
}

}  // namespace

void AddStabilityCommands(CLI::App& app) {
  AddBoundaryCommand(app);
  AddFilterSweepCommand(app);
  AddRelayCommand(app);
  AddCheckCommand(app);
}

}  // namespace zwidth::app
