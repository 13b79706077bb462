#include "tests/test_util.h"

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <numbers>
#include <stdexcept>

namespace zwidth::test {

std::string TableCell(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}


model::Plant RandomPlant(std::mt19937_64& rng, const RandomPlantRanges& r, int modes, double T) {
  std::uniform_real_distribution<double> U(0, 1);
  model::Plant p;
  p.m = std::pow(10.0, r.log10_m_kg_m2.At(U(rng)));
  p.b = p.m * std::pow(10.0, r.log10_b_over_m_rad_s.At(U(rng)));
  const auto frequency_rad_s = [&] { return 2 * std::numbers::pi * r.hz_unit * r.pole_hz.At(U(rng)); };
  const auto zeta = [&] { return std::pow(10.0, r.log10_zeta.At(U(rng))); };
  for (int i = 0; i < modes; ++i) {
    const double w = frequency_rad_s();
    double v = 0, zc = 0, zd = 0;
    if (r.order == RandomPlantRanges::Order::kFrequenciesThenDampings) {
      v = r.zero_independent ? frequency_rad_s() : w * r.zero_over_pole.At(U(rng));
      zc = zeta();
      zd = zeta();
    } else {
      zc = zeta();
      v = r.zero_independent ? frequency_rad_s() : w * r.zero_over_pole.At(U(rng));
      zd = zeta();
    }
    const double v_kept = r.cap_zero_below_nyquist ? std::min(v, 0.95 * std::numbers::pi / T) : v;
    p.modes.push_back({w, std::max(r.min_damping_rad_s, 2 * zc * w), v_kept, std::max(r.min_damping_rad_s, 2 * zd * v)});
  }
  return p;
}

RandomPlantRanges PlausibleDevice() {
  RandomPlantRanges r;
  r.log10_m_kg_m2 = {-3.5, 2.5};
  r.log10_b_over_m_rad_s = {0.3, 1.2};
  r.pole_hz = {30.0, 370.0};
  r.zero_over_pole = {0.7, 0.6};
  r.log10_zeta = {-2.7, 2.2};
  r.order = RandomPlantRanges::Order::kDampingAfterEachFrequency;
  return r;
}

RandomPlantRanges WideRandomModels() {
  RandomPlantRanges r;
  r.log10_m_kg_m2 = {-5, 5};
  r.log10_b_over_m_rad_s = {-1, 2};
  r.pole_hz = {5, 445};
  r.zero_over_pole = {0.5, 1};
  r.log10_zeta = {-3, 2.7};
  r.min_damping_rad_s = 0.1;
  r.cap_zero_below_nyquist = true;
  return r;
}

model::Plant RandomPlausibleDevice(std::mt19937_64& rng, int modes) { return RandomPlant(rng, PlausibleDevice(), modes); }

TempDir::TempDir(const std::string& prefix) {
  std::string t = (std::filesystem::temp_directory_path() / (prefix + "XXXXXX")).string();
  if (::mkdtemp(t.data()) == nullptr) throw std::runtime_error("mkdtemp failed for " + t);
  path_ = t;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string TempDir::Write(const std::string& name, const std::string& bytes) const {
  const std::string p = (path_ / name).string();
  WriteFile(p, bytes);
  return p;
}

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteFile(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

}  // namespace zwidth::test
