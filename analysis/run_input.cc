#include "analysis/run_input.h"

#include <exception>
#include <optional>
#include <system_error>
#include <thread>
#include <utility>

#include "analysis/laps.h"
#include "io/model_json.h"
#include "model/error.h"

namespace zwidth::analysis {

RunInput EstimateAndFit(RunInput in, const EstimateFitOptions& o, const std::vector<int>& delays,
                        const RunMessages& m, double* ms) {
  Laps laps;
  auto stage = [&](const std::string& name) {
    const double t = laps.Lap();
    if (m.stage) m.stage(name, t);
    if (ms) *ms += t;
  };
  if (ms) *ms = 0.0;
  LogsEstimateOptions eo = o.estimate;
  eo.for_fit = true;
  std::optional<FrictionInput> friction;  // refused (coulomb on several logs) before anything is read
  if (o.friction) {
    std::string warning;
    friction = FrictionInputFor(in.logs, false, eo.select, eo.welch, *o.friction, &warning);
    if (!warning.empty() && m.fit.warning) m.fit.warning(warning);
  }
  LogsEstimate est = EstimateFromLogs(in.logs, eo, m.estimate);
  in.response = std::move(est.response);
  in.total_samples = est.total_samples;
  in.whole_record = eo.whole_record;
  const bool linear = io::LinearUnitsOf(o.linear, est.infos, "ModelFile::linear");
  stage("estimate (read + Welch)");
  // The reference's delay is counted in its own period: in the log's (or refused).
  if (in.reference) {
    const std::string note = io::ConvertDelayToPeriod(&*in.reference, in.response.frf.period_s(), "the reference");
    if (!note.empty() && m.note) m.note(note);
  }
  std::exception_ptr ref_error;
  std::optional<ReferenceStability> ref;
  {
    std::jthread ref_thread;
    if (in.reference && o.reference_thread) {
      try {
        ref_thread = std::jthread([&] {
          try {
            ref = ReferenceStabilityOf(*in.reference, in.response.frf.period_s(), delays);
          } catch (...) {
            ref_error = std::current_exception();
          }
        });
      } catch (const std::system_error&) {
        // No thread to be had: Analyse computes the reference after the fit.
      }
    }
    FitMessages fm = m.fit;
    fm.linear = linear;
    in.model = FitToModelFile(in.response.frf, o.fit, in.source, fm, &in.fit, friction ? &*friction : nullptr,
                              &in.friction_fit);
  }  // joined
  if (ref_error) std::rethrow_exception(ref_error);
  in.reference_stability = std::move(ref);
  for (std::string& w : in.fit.warnings) w = m.fit.Words(w);  // the report shows the caller's words
  stage(in.reference ? "fit (+ reference Z-width)" : "fit");
  return in;
}

RunAnalysis EstimateFitAndAnalyse(RunInput in, const EstimateFitOptions& estimate_fit, RunOptions options,
                                  const LoopForPeriod& loop, const RunMessages& messages, double* ms) {
  std::string why;  // before anything is read
  if (!options.IsValid(&why)) throw InputError(why);
  in = EstimateAndFit(std::move(in), estimate_fit, options.delays, messages, ms);
  options.linear = in.model.linear;  // the caller's units, or the logs' headers'
  if (loop) options.loop = loop(in.response.frf.period_s());
  return Analyse(std::move(in), options);
}

}  // namespace zwidth::analysis
