#include "analysis/scene_check.h"

#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "model/error.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

namespace zwidth::analysis {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One finite, positive end of a stable interval at the object's B, with the
// side of it that is stable (+1: K above it, the end is a K_lo; -1: below).
struct End {
  double K, f_hz;
  int stable_side;
};

std::vector<End> FiniteEnds(const std::vector<stability::KInterval>& intervals) {
  std::vector<End> ends;
  for (const stability::KInterval& iv : intervals) {
    if (iv.K_lo > 0.0 && std::isfinite(iv.K_lo)) ends.push_back({iv.K_lo, iv.f_lo_hz, +1});
    if (std::isfinite(iv.K_hi)) ends.push_back({iv.K_hi, iv.f_hi_hz, -1});
  }
  return ends;
}

// The end nearest to K (in std units when every std is known), its std and
// the signed distance; fills the boundary fields of c.
void NearestBoundary(double K, double B, const std::vector<End>& ends, const stability::PerturbedPlants* plants,
                     const std::vector<double>& cov, int delay, const stability::LoopOptions& loop, ObjectCheck* c) {
  if (ends.empty()) return;
  std::vector<double> stds(ends.size(), kNaN);
  if (plants != nullptr) {
    std::vector<stability::CriticalPoint> points;
    for (const End& e : ends) {
      stability::CriticalPoint p;
      p.B = B;
      p.K_cr = e.K;
      p.f_cr_hz = e.f_hz;
      points.push_back(p);
    }
    stds = stability::KcrStd(*plants, cov, delay, points, loop);
  }
  // An end with a std comes first (distances in std and in N m/rad do not compare), then the nearest.
  std::pair<int, double> best{2, 0.0};
  for (size_t i = 0; i < ends.size(); ++i) {
    const bool have_std = std::isfinite(stds[i]) && stds[i] > 0.0;
    const std::pair<int, double> key{have_std ? 0 : 1, std::abs(K - ends[i].K) / (have_std ? stds[i] : 1.0)};
    if (key >= best) continue;
    best = key;
    c->boundary_K = ends[i].K;
    c->boundary_f_hz = ends[i].f_hz;
    c->boundary_K_std = have_std ? stds[i] : kNaN;
    c->sigmas_to_boundary = have_std ? ends[i].stable_side * (K - ends[i].K) / stds[i] : kNaN;
  }
}

}  // namespace

std::string ToString(SceneStatus s) {
  switch (s) {
    case SceneStatus::kStable: return "stable";
    case SceneStatus::kMarginal: return "marginal";
    case SceneStatus::kUnstable: return "unstable";
  }
  return "?";
}

bool SceneCheckOptions::IsValid(std::string* why) const {
  if (!(marginal_sigmas >= 0.0 && marginal_sigmas <= 100.0)) {
    *why = "marginal_sigmas must lie in [0, 100] (standard deviations; 0 turns the marginal status off)";
    return false;
  }
  return true;
}

SceneCheck CheckScene(const model::Plant& plant, const std::vector<double>& cov, double T, int delay,
                      const std::vector<stability::LoopOptions>& loops, const std::vector<io::SceneObject>& objects,
                      const SceneCheckOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("scene check options: " + why);
  if (loops.empty()) throw InputError("scene check: no loop to check (give at least one LoopOptions)");
  std::vector<stability::SampledPlant> sampled;
  std::vector<stability::ZWidth> zs;  // one per hand: stable means stable for every hand
  for (const stability::LoopOptions& l : loops) {
    sampled.emplace_back(plant, T, l.hand);
    zs.emplace_back(sampled.back(), delay, l);
  }
  SceneCheck out;
  out.has_std = !cov.empty() && loops.size() == 1;
  std::optional<stability::PerturbedPlants> plants;
  if (out.has_std) {
    stability::CheckLogCovariance(plant, cov);
    plants = stability::SamplePerturbedPlants(plant, T, loops[0].hand);
  }
  for (const io::SceneObject& obj : objects) {
    stability::CriticalPoint cp = zs[0].At(obj.B);
    std::vector<stability::KInterval> iv = zs[0].StableIntervals(obj.B);
    for (size_t h = 1; h < zs.size(); ++h) {
      iv = stability::IntersectIntervals(iv, zs[h].StableIntervals(obj.B));
      const stability::CriticalPoint c = zs[h].At(obj.B);
      if (c.K_cr < cp.K_cr) cp = c;
    }
    ObjectCheck c;
    c.verdict = io::Classify(obj, cp, iv);
    NearestBoundary(obj.K, obj.B, FiniteEnds(c.verdict.intervals), plants ? &*plants : nullptr, cov, delay, loops[0], &c);
    const bool near = o.marginal_sigmas > 0.0 && std::abs(c.sigmas_to_boundary) < o.marginal_sigmas;
    c.status = near ? SceneStatus::kMarginal : c.verdict.stable ? SceneStatus::kStable : SceneStatus::kUnstable;
    out.num_unstable += c.status == SceneStatus::kUnstable;
    out.num_marginal += c.status == SceneStatus::kMarginal;
    out.objects.push_back(std::move(c));
  }
  return out;
}

nlohmann::json ObjectCheckJson(const ObjectCheck& c, const io::SceneObject& o) {
  nlohmann::json j = c.verdict.ToJson(o);
  j["status"] = ToString(c.status);
  j["boundary_K"] = io::NumberOrNull(c.boundary_K);
  j["boundary_f_hz"] = io::NumberOrNull(c.boundary_f_hz);
  j["boundary_K_std"] = io::NumberOrNull(c.boundary_K_std);
  j["sigmas_to_boundary"] = io::NumberOrNull(c.sigmas_to_boundary);
  return j;
}

nlohmann::json SceneCheckJson(const SceneCheck& sc, const std::vector<io::SceneObject>& objects, int delay,
                              double T, const SceneCheckOptions& o) {
  nlohmann::json out = {{"delay_samples", delay}, {"period_s", T}, {"objects", nlohmann::json::array()},
                        {"marginal_sigmas", sc.has_std ? nlohmann::json(o.marginal_sigmas) : nlohmann::json(nullptr)}};
  for (size_t i = 0; i < objects.size(); ++i) out["objects"].push_back(ObjectCheckJson(sc.objects[i], objects[i]));
  return out;
}

}  // namespace zwidth::analysis
