// Shared helpers of the C++ tests: seeded random plants (eq. 1 of the paper)
// drawn from stated ranges, and a temporary folder removed with its contents.
// Library: zwidth_test_util (tests/CMakeLists.txt).
#pragma once

#include <filesystem>
#include <limits>
#include <random>
#include <string>

#include "model/plant.h"

namespace zwidth::test {

// A number as a batch table's cell holds it: 17 significant digits, so it reads back as the same double.
std::string TableCell(double v);

// A uniform range lo + span * u, u ~ U(0, 1). Given as (lo, span), not
// (lo, hi), so that each test's numbers stay the ones it wrote, to the bit.
struct Range {
  double lo = 0.0;
  double span = 1.0;
  double At(double u) const { return lo + span * u; }
};

// The ranges of a random plant, every number drawn from one stream of
// std::uniform_real_distribution<double>(0, 1) draws in this order: m, b, then
// for each mode the pole frequency, the zero frequency, the pole damping ratio
// and the zero damping ratio (or, with kDampingAfterEachFrequency, pole
// frequency, pole damping, zero frequency, zero damping).
struct RandomPlantRanges {
  enum class Order { kFrequenciesThenDampings, kDampingAfterEachFrequency };
  Range log10_m_kg_m2;        // m = 10^At(u)
  Range log10_b_over_m_rad_s;  // b = m 10^At(u)
  double hz_unit = 1.0;        // pole (and independent zero) frequencies are hz_unit * At(u) Hz
  Range pole_hz;
  bool zero_independent = false;  // true: zero frequency from pole_hz like the pole; false: v = w At(u)
  Range zero_over_pole;           // used when !zero_independent
  Range log10_zeta;               // damping ratios of poles and zeros: zeta = 10^At(u)
  Order order = Order::kFrequenciesThenDampings;
  double min_damping_rad_s = 0.0;  // c, d = max(this, 2 zeta w); 0: no floor
  // v is capped at 0.95 pi / T (below Nyquist) when true; the zero's damping
  // uses the uncapped v.
  bool cap_zero_below_nyquist = false;
};

// A seeded random plant with `modes` resonance/antiresonance pairs; T [s] is
// used only by cap_zero_below_nyquist.
model::Plant RandomPlant(std::mt19937_64& rng, const RandomPlantRanges& r, int modes, double T = 1e-3);

// A plausible device (hand_test, closed_loop_test, zwidth_test): m 10^-3.5..10^-1,
// b / m 10^0.3..10^1.5 rad/s, modes 30-400 Hz with damping ratios 0.002-0.3,
// antiresonances 0.7-1.3 of their resonance.
RandomPlantRanges PlausibleDevice();
// RandomPlant(rng, PlausibleDevice(), modes).
model::Plant RandomPlausibleDevice(std::mt19937_64& rng, int modes);

// Wide random models (the stress tests of the Z-width and the relay): m over 5
// decades from 1e-5, b / m 0.1..10 rad/s, modes 5-450 Hz with damping ratios
// 1e-3..0.5 (c, d at least 0.1 rad/s), antiresonances 0.5..1.5 of their
// resonance, capped below Nyquist.
RandomPlantRanges WideRandomModels();

// The names of TEST_P cases over delays: "d<delay>" (the INSTANTIATE_TEST_SUITE_P
// name generator).
struct DelayName {
  template <class ParamInfo>
  std::string operator()(const ParamInfo& info) const {
    return "d" + std::to_string(info.param);
  }
};

// A temporary folder, made at construction (mkdtemp under the system's
// temporary directory, name "<prefix>XXXXXX") and removed with everything in it
// at destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "zwidth_test_");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }
  // Writes bytes to path() / name (binary) and returns that path.
  std::string Write(const std::string& name, const std::string& bytes) const;

 private:
  std::filesystem::path path_;
};

// The bytes of a file ("" when it cannot be read).
std::string ReadFile(const std::filesystem::path& path);
// Writes bytes to a file (binary), replacing it.
void WriteFile(const std::filesystem::path& path, const std::string& bytes);

}  // namespace zwidth::test
