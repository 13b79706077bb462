// `zwidth check` as data: each object {name, K, B} of a haptic scene against
// the stable K intervals of the loop at its B, with its distance to the
// nearest boundary in units of that boundary's delta-method std when the model
// has a covariance (stability/uncertainty.h), and a third status, marginal,
// when the answer is within SceneCheckOptions::marginal_sigmas of it.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "io/stability_files.h"
#include "model/plant.h"
#include "stability/loop_options.h"

namespace zwidth::analysis {

enum class SceneStatus {
  kStable,    // K inside a stable interval, more than marginal_sigmas std from its ends (or no std known)
  kMarginal,  // within marginal_sigmas std of the nearest boundary: either answer is within the model's uncertainty
  kUnstable,  // K outside every stable interval, more than marginal_sigmas std away (or no std known)
};
std::string ToString(SceneStatus s);

struct SceneCheckOptions {
  // An object whose K lies within this many standard deviations of the
  // nearest interval end at its B is marginal; 0 turns the status off. [0, 100].
  double marginal_sigmas = 2.0;
  bool IsValid(std::string* why) const;
};

struct ObjectCheck {
  io::ObjectVerdict verdict;  // the nominal answer (stable exactly when K lies in an interval)
  SceneStatus status = SceneStatus::kUnstable;
  // The finite, positive interval end nearest to K (in std units when known,
  // else in N m/rad), its pole frequency and its delta-method std; nan when
  // no interval end exists at this B (no stable K, or one interval (0, inf)).
  double boundary_K = std::numeric_limits<double>::quiet_NaN();
  double boundary_f_hz = std::numeric_limits<double>::quiet_NaN();
  double boundary_K_std = std::numeric_limits<double>::quiet_NaN();
  // (K - boundary_K) / boundary_K_std, signed so that it is positive on the
  // stable side of that boundary; nan without a std.
  double sigmas_to_boundary = std::numeric_limits<double>::quiet_NaN();
};

struct SceneCheck {
  std::vector<ObjectCheck> objects;
  bool has_std = false;  // the model had a covariance and one loop (one hand) was checked
  int num_unstable = 0, num_marginal = 0;
};

// Checks every object on the loops (one per hand: stable means stable for
// every hand; the std is computed for one loop only). log_covariance may be
// empty (no std, no marginal status). Throws InputError for invalid options.
SceneCheck CheckScene(const model::Plant& plant, const std::vector<double>& log_covariance, double period_s,
                      int delay_samples, const std::vector<stability::LoopOptions>& loops,
                      const std::vector<io::SceneObject>& objects, const SceneCheckOptions& options = {});

// The object's entry of `check --json`: ObjectVerdict::ToJson plus status,
// boundary_K, boundary_f_hz, boundary_K_std and sigmas_to_boundary.
nlohmann::json ObjectCheckJson(const ObjectCheck& c, const io::SceneObject& o);
// What `check --json` prints (and zwidth.check returns): delay_samples,
// period_s, marginal_sigmas (null without a std) and the objects.
nlohmann::json SceneCheckJson(const SceneCheck& sc, const std::vector<io::SceneObject>& objects, int delay_samples,
                              double period_s, const SceneCheckOptions& options);

}  // namespace zwidth::analysis
