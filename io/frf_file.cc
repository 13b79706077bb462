#include "io/frf_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include "io/atomic_file.h"
#include "io/frf_file_internal.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "io/isolated.h"
#include "io/log.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

void WriteCsv(const std::string& tmp, const ident::FrequencyResponse& r) {
  internal::CsvFile line(tmp);
  line.Text("f_hz,H_re,H_im,coherence,H_std,H_mag,H_phase_deg,S_uu,S_yy,sample_rate_hz,"
            "num_averages,effective_averages,bin_correlation");
  const bool used = r.used_by_fit.size() == r.f_hz.size();  // the fit's bins, when known
  // The robust method's noise and nonlinear-distortion variances, when known.
  const bool noise = r.noise_var.size() == r.f_hz.size(), distortion = r.distortion_var.size() == r.f_hz.size();
  line.Text(noise ? ",noise_var" : "");
  line.Text(distortion ? ",distortion_var" : "");
  line.Text(used ? ",used_by_fit\n" : "\n");
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    line.G(r.f_hz[k], 17).G(r.H[k].real(), 17).G(r.H[k].imag(), 17).G(r.coherence[k], 17).G(r.H_std[k], 17);
    line.G(std::abs(r.H[k]), 17).G(std::arg(r.H[k]) * 180.0 / std::numbers::pi, 17).G(r.S_uu[k], 17);
    line.G(r.S_yy[k], 17).G(r.sample_rate_hz, 17).Int(r.num_averages).G(r.effective_averages, 17);
    line.G(r.bin_correlation, 17);
    if (noise) line.G(r.noise_var[k], 17);
    if (distortion) line.G(r.distortion_var[k], 17);
    if (used) line.Int(r.used_by_fit[k] ? 1 : 0);
    line.End();
  }
  line.Close(tmp);
}

std::string Num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// A whole count in [0, 2^31) stored as a double; anything else is an InputError.
int Count(double v, const std::string& path, const char* name) {
  if (!(v >= 0.0 && v < 2147483648.0) || v != std::floor(v)) {
    throw InputError(path + ": " + name + " = " + Num(v) + " is not a whole number >= 0");
  }
  return static_cast<int>(v);
}

constexpr size_t kMaxBins = internal::kMaxFrfBins;

// A column the file does not give (coherence, H_std): FillAbsent decides.
const double kAbsent = std::nan("");

// The header names of a response made elsewhere (MATLAB, Octave, a script)
// as those of `zwidth estimate`'s files: f -> f_hz, coh -> coherence,
// std -> H_std, n_avg -> num_averages, fs -> sample_rate_hz.
std::string CanonicalColumn(std::string name) {
  while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
  if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
  static const std::map<std::string, std::string> aliases = {
      {"f", "f_hz"}, {"coh", "coherence"}, {"std", "H_std"}, {"n_avg", "num_averages"}, {"fs", "sample_rate_hz"}};
  const auto it = aliases.find(name);
  return it == aliases.end() ? name : it->second;
}

// The header line of a response CSV, without the UTF-8 BOM a spreadsheet
// saves first (the log reader drops it too): with it, "f_hz" was not found and
// the file was read as a log ("no column 'torque'").
bool ReadHeader(std::istream& in, std::string* line) {
  if (!std::getline(in, *line)) return false;
  if (line->rfind("\xEF\xBB\xBF", 0) == 0) line->erase(0, 3);
  return true;
}

ident::FrequencyResponse ReadCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open frequency-response file");
  std::string line;
  if (!ReadHeader(in, &line)) throw InputError(path + ": empty file");
  std::map<std::string, int> col;
  size_t num_columns = 0;
  std::vector<std::string_view> fields;
  internal::SplitFields(line, ',', &fields);
  for (std::string_view f : fields) {
    std::string name = CanonicalColumn(std::string(f));
    if (!col.emplace(name, static_cast<int>(num_columns)).second) {
      throw InputError(path + ": line 1: column '" + name + "' appears twice in the header; "
                       "each column name must be unique");
    }
    ++num_columns;
  }
  for (const char* need : {"f_hz", "H_re", "H_im"}) {
    if (!col.count(need)) throw InputError(path + ": no column '" + std::string(need) + "' in the header");
  }
  // Column positions, -1 where absent.
  auto index = [&](const char* name) { auto it = col.find(name); return it == col.end() ? -1 : it->second; };
  const int i_f = index("f_hz"), i_re = index("H_re"), i_im = index("H_im"), i_coh = index("coherence"),
            i_std = index("H_std"), i_suu = index("S_uu"), i_syy = index("S_yy"),
            i_rate = index("sample_rate_hz"), i_navg = index("num_averages"),
            i_neff = index("effective_averages"), i_kappa = index("bin_correlation"),
            i_noise = index("noise_var"), i_distortion = index("distortion_var");
  ident::FrequencyResponse r;
  r.num_averages = 0;
  r.effective_averages = 0;
  r.bin_correlation = 1.0;
  size_t line_no = 1;
  std::vector<double> v;
  // The columns that hold one value for the whole response, repeated on every
  // row: a row that disagrees is refused (the last row silently won before).
  const std::pair<int, const char*> constants[] = {{i_rate, "sample_rate_hz"}, {i_navg, "num_averages"},
                                                   {i_neff, "effective_averages"}, {i_kappa, "bin_correlation"}};
  std::vector<double> first_row;
  size_t first_line = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    v.clear();
    internal::SplitFields(line, ',', &fields);
    for (std::string_view f : fields) {
      double x = 0.0;
      auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), x);
      if (ec != std::errc() || p != f.data() + f.size()) {
        throw InputError(path + ": line " + std::to_string(line_no) + ", field " +
                         std::to_string(v.size() + 1) + ": not a number");
      }
      v.push_back(x);
    }
    if (v.size() != num_columns) {
      throw InputError(path + ": line " + std::to_string(line_no) + " has " + std::to_string(v.size()) +
                       " fields, the header has " + std::to_string(num_columns) + " (truncated or damaged row?)");
    }
    if (r.f_hz.size() >= kMaxBins) {
      throw InputError(path + ": more than " + std::to_string(kMaxBins) + " rows, more than a response has");
    }
    for (double x : v) {
      if (!std::isfinite(x)) {
        throw InputError(path + ": line " + std::to_string(line_no) + " has a value that is not finite");
      }
    }
    const std::complex<double> h(v[i_re], v[i_im]);
    const double f = v[i_f];
    if (!r.f_hz.empty() && !(f > r.f_hz.back())) {
      throw InputError(path + ": line " + std::to_string(line_no) + ": f_hz is not increasing");
    }
    r.f_hz.push_back(f);
    r.H.push_back(h);
    r.coherence.push_back(i_coh >= 0 ? v[i_coh] : kAbsent);
    r.H_std.push_back(i_std >= 0 ? v[i_std] : kAbsent);
    r.S_uu.push_back(i_suu >= 0 ? v[i_suu] : 0.0);
    r.S_yy.push_back(i_syy >= 0 ? v[i_syy] : 0.0);
    r.S_uy.push_back(0.0);
    if (i_noise >= 0) r.noise_var.push_back(v[i_noise]);
    if (i_distortion >= 0) r.distortion_var.push_back(v[i_distortion]);
    if (i_rate >= 0) r.sample_rate_hz = v[i_rate];
    if (i_navg >= 0) r.num_averages = Count(v[i_navg], path, "num_averages");
    if (i_neff >= 0) r.effective_averages = v[i_neff];
    if (i_kappa >= 0) r.bin_correlation = v[i_kappa];
    if (first_row.empty()) {
      first_row = v;
      first_line = line_no;
    }
    for (const auto& [i, name] : constants) {
      if (i >= 0 && v[i] != first_row[i]) {
        throw InputError(path + ": line " + std::to_string(line_no) + ": " + name + " = " + Num(v[i]) +
                         " differs from " + Num(first_row[i]) + " on line " + std::to_string(first_line) +
                         ": a response has one " + name + "; repair the file (rows of two responses mixed?)");
      }
    }
  }
  if (r.f_hz.empty()) throw InputError(path + ": no data rows");
  return r;
}

// The rates a log may have (io/log.h: 10 Hz..1 MHz), from a file as from a
// flag or a Python argument: 0.001 is a period typed for a rate.
void CheckRate(double rate, const std::string& source, const std::string& name) {
  if (rate >= 10.0 && rate <= 1e6) return;
  throw InputError(source + ": " + name + " = " + Num(rate) + " Hz: a sample rate must lie in [10, 1e6] Hz" +
                   (rate > 0.0 && rate <= 0.1 ? " (is it the period? for " + Num(rate) + " s the rate is " +
                                                    Num(1.0 / rate) + " Hz)"
                                              : ""));
}

// A response reaches at most Nyquist (a Welch estimate's last bin is Nyquist
// itself, up to rounding); above it the rate is wrong (a kHz typed for Hz).
void CheckBelowNyquist(const ident::FrequencyResponse& r, const std::string& source, const char* rate_name) {
  const double nyquist = 0.5 * r.sample_rate_hz;
  if (r.f_hz.back() > nyquist * (1.0 + 1e-12)) {
    char msg[200];
    std::snprintf(msg, sizeof msg, ": the frequencies f_hz reach %s Hz, above the Nyquist frequency of %s Hz; wrong %s?",
                  Num(r.f_hz.back()).c_str(), Num(nyquist).c_str(), rate_name);
    throw InputError(source + msg);
  }
}

// Per bin: a std of 0 would weight the fit by 1/0 (an infinite chi2 or one bin
// alone deciding it), a coherence outside [0, 1] or a negative frequency is
// no response an estimate gives.
void CheckBinValues(const ident::FrequencyResponse& r, const std::string& path) {
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    const std::string where = path + ": bin " + std::to_string(k) + " (f = " + Num(r.f_hz[k]) + " Hz): ";
    if (!(r.H_std[k] > 0.0)) {
      throw InputError(where + "H_std = " + Num(r.H_std[k]) + ", a per-bin std must be > 0 (the fit weights each "
                       "bin by 1/std): write the std the estimate gave, or drop the H_std column (then |H| x 1e-3)");
    }
    if (!(r.coherence[k] >= 0.0 && r.coherence[k] <= 1.0)) {
      throw InputError(where + "coherence = " + Num(r.coherence[k]) + " is outside [0, 1]");
    }
    if (!(r.f_hz[k] >= 0.0)) throw InputError(where + "f_hz = " + Num(r.f_hz[k]) + ": a frequency must be >= 0");
    const double suu = k < r.S_uu.size() ? r.S_uu[k] : 0.0, syy = k < r.S_yy.size() ? r.S_yy[k] : 0.0;
    if (!(suu >= 0.0 && syy >= 0.0)) {
      throw InputError(where + "S_uu = " + Num(suu) + ", S_yy = " + Num(syy) + ": a power spectral density is >= 0");
    }
  }
}

// A response made elsewhere may lack the per-bin std or the coherence (NaN
// here). The std is then derived from the coherence and the averages when the
// file gives both (ident::CoherenceStd, Bendat & Piersol: |H| sqrt((1 - g^2) /
// (2 n g^2)), n = effective_averages, else num_averages), else |H| x 1e-3
// (equal relative weights, no absolute scale); an absent coherence is 1.
// Returns what was done, "" when the file gave the std.
std::string FillAbsent(ident::FrequencyResponse& r, const std::string& path) {
  if (r.f_hz.empty()) return "";
  const bool no_coh = std::isnan(r.coherence.front()), no_std = std::isnan(r.H_std.front());
  for (double& c : r.coherence) if (no_coh) c = 1.0;
  if (!no_std) return "";
  const double n = r.effective_averages > 0.0 ? r.effective_averages : r.num_averages;
  if (no_coh) {
    for (size_t k = 0; k < r.H.size(); ++k) r.H_std[k] = 1e-3 * std::abs(r.H[k]);
    return path + ": no H_std nor coherence: each bin weighted by |H| x 1e-3 (equal relative weights; the fit's "
                  "chi2 has no absolute scale)";
  }
  if (!(n >= 1.0)) {
    throw InputError(path + ": the response gives a coherence but no per-bin std (H_std) and no number of averages: "
                     "add a num_averages column (or variable; the segments the estimate averaged) to derive the std "
                     "from the coherence, or give H_std");
  }
  for (size_t k = 0; k < r.H.size(); ++k) {
    if (!(r.coherence[k] > 0.0)) {
      throw InputError(path + ": bin " + std::to_string(k) + " (f = " + Num(r.f_hz[k]) + " Hz): coherence " +
                       Num(r.coherence[k]) + " gives no std (no linear relation there): drop the bin or give H_std");
    }
    r.H_std[k] = ident::CoherenceStd(std::abs(r.H[k]), r.coherence[k], n);
  }
  return path + ": H_std derived from the coherence and " + Num(n) + " averages (Bendat & Piersol: |H| sqrt((1 - "
                "coh) / (2 n coh)))";
}

// The rate (--rate wins over the file's) and the checks common to both formats.
void Finish(ident::FrequencyResponse& r, const std::string& path, double rate, std::string* note) {
  const std::string filled = FillAbsent(r, path);
  if (note) *note = filled;
  if (!(std::isfinite(r.effective_averages) && r.effective_averages >= 0.0)) {
    throw InputError(path + ": effective_averages = " + Num(r.effective_averages) + " must be finite, >= 0");
  }
  if (!(std::isfinite(r.bin_correlation) && r.bin_correlation > 0.0)) {
    throw InputError(path + ": bin_correlation = " + Num(r.bin_correlation) + " must be finite, > 0");
  }
  CheckBinValues(r, path);
  if (rate > 0.0) r.sample_rate_hz = rate;
  if (std::isnan(r.sample_rate_hz) || std::isinf(r.sample_rate_hz)) {  // given, but no rate ("no attribute" before)
    throw InputError(path + ": the file's sample_rate_hz = " + Num(r.sample_rate_hz) + " is not a finite number: "
                     "write the log's sample rate there (10..1e6 Hz), or pass ReadFrequencyResponse::sample_rate_hz");
  }
  if (!(r.sample_rate_hz > 0.0)) {
    throw InputError(path + ": no sample_rate_hz column or attribute; pass ReadFrequencyResponse::sample_rate_hz (the log's sample rate)");
  }
  CheckRate(r.sample_rate_hz, path, rate > 0.0 ? "ReadFrequencyResponse::sample_rate_hz" : "the file's sample_rate_hz");
  CheckBelowNyquist(r, path, "ReadFrequencyResponse::sample_rate_hz");
}

// True for a MATLAB .mat file (v5/v7 or v7.3: their 128-byte text header).
bool IsMatFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[6] = {};
  return in.read(head, sizeof head) && std::memcmp(head, "MATLAB", 6) == 0;
}

// An HDF5 (/frf) or .mat response, parsed in a child when `isolated`.
ident::FrequencyResponse ReadPacked(const std::string& path, bool isolated) {
  const internal::Hdf5Api& h5 = internal::Hdf5();
  const auto read = IsMatFile(path) ? h5.read_frf_mat_packed : h5.read_frf_hdf5_packed;
  std::string bytes;
  if (isolated) {
    RunIsolated(
        path,
        [&](const FrameSender& send) {
          const std::string b = read(path);
          send(b.data(), b.size());
        },
        [&](std::string_view frame) { bytes = frame; });
  } else {
    bytes = read(path);
  }
  std::vector<double> v(bytes.size() / sizeof(double));
  std::memcpy(v.data(), bytes.data(), v.size() * sizeof(double));
  if (v.size() < 5) throw InputError(path + ": could not read the frequency response");
  const size_t n = static_cast<size_t>(v[0]);
  if (v.size() != 5 + 7 * n) throw InputError(path + ": could not read the frequency response");
  ident::FrequencyResponse r;
  r.sample_rate_hz = v[1];
  r.num_averages = Count(v[2], path, "num_averages");
  r.effective_averages = v[3];
  r.bin_correlation = v[4];
  const double* c = v.data() + 5;
  r.f_hz.assign(c, c + n);
  r.H.resize(n);
  for (size_t k = 0; k < n; ++k) r.H[k] = {c[n + k], c[2 * n + k]};
  r.coherence.assign(c + 3 * n, c + 4 * n);
  r.H_std.assign(c + 4 * n, c + 5 * n);
  r.S_uu.assign(c + 5 * n, c + 6 * n);
  r.S_yy.assign(c + 6 * n, c + 7 * n);
  r.S_uy.assign(n, 0.0);
  return r;
}

// HDF5 or .mat (v5 or v7.3): read through the plugin's table.
bool IsPackedFormat(const std::string& path) { return DetectLogFormat(path) != LogFormat::kCsv; }

}  // namespace

void CheckResponseValues(const ident::FrequencyResponse& r, const std::string& source) {
  const size_t n = r.f_hz.size();
  if (n == 0) throw InputError(source + ": f_hz is empty");
  auto bad = [&](const std::string& what) { throw InputError(source + ": " + what); };
  if (r.H.size() != n || r.coherence.size() != n || r.H_std.size() != n) {
    bad("f_hz has " + std::to_string(n) + " values, H " + std::to_string(r.H.size()) + ", coherence " +
        std::to_string(r.coherence.size()) + ", H_std " + std::to_string(r.H_std.size()) + ": they must agree");
  }
  for (size_t k = 0; k < n; ++k) {
    const std::string at = "[" + std::to_string(k) + "]";
    if (!std::isfinite(r.f_hz[k])) bad("f_hz" + at + " = " + Num(r.f_hz[k]) + " must be finite");
    if (k > 0 && !(r.f_hz[k] > r.f_hz[k - 1])) bad("f_hz" + at + ": f_hz is not increasing");
    if (!(std::isfinite(r.H[k].real()) && std::isfinite(r.H[k].imag()))) bad("H" + at + " is not finite");
    if (!std::isfinite(r.H_std[k])) bad("H_std" + at + " = " + Num(r.H_std[k]) + " must be finite");
  }
  CheckBinValues(r, source);  // the reader's per-bin rules: H_std > 0, coherence in [0, 1], f >= 0
  if (r.num_averages < 1) bad("num_averages = " + std::to_string(r.num_averages) + " must be >= 1");
  CheckRate(r.sample_rate_hz, source, "sample_rate_hz");
  CheckBelowNyquist(r, source, "sample_rate_hz");
}

void CheckFiniteResponse(const ident::FrequencyResponse& r, const std::string& source) {
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    const double suu = k < r.S_uu.size() ? r.S_uu[k] : 0.0, syy = k < r.S_yy.size() ? r.S_yy[k] : 0.0;
    const std::pair<const char*, double> values[] = {
        {"f_hz", r.f_hz[k]}, {"H", std::abs(r.H[k].real()) + std::abs(r.H[k].imag())}, {"coherence", r.coherence[k]},
        {"H_std", r.H_std[k]}, {"S_uu", suu}, {"S_yy", syy}};
    for (const auto& [name, v] : values) {
      if (std::isfinite(v)) continue;
      const std::string where = source + ": the frequency response has non-finite values (" + name + " at bin " +
                                std::to_string(k) + ", f = " + Num(r.f_hz[k]) + " Hz)";
      if (!std::isfinite(suu) || !std::isfinite(syy)) {  // the spectra themselves overflowed
        throw InputError(where + ": input scaled out of range (the spectra overflow: values near 1e154 or more "
                         "square past 1e308); rescale the log's columns to SI units (LogSelect::input_scale, "
                         "LogSelect::output_scale)");
      }
      if (std::string(name) == "H_std") {
        throw InputError(where + ": the per-bin std cannot be estimated (a single segment has no scatter); "
                         "give more segments (several runs, a longer log)");
      }
      throw InputError(where + " (S_uu " + Num(suu) + ", S_yy " + Num(syy) + ")");
    }
  }
}

void CheckInputPower(const ident::FrequencyResponse& r, const std::string& source) {
  double peak = 0.0;
  for (double s : r.S_uu) if (std::isfinite(s)) peak = std::max(peak, s);
  if (!(peak > 0.0)) return;  // a constant input is refused by the log readers
  std::vector<size_t> dead;
  for (size_t k = 0; k < r.S_uu.size() && k < r.f_hz.size(); ++k) {
    if (!(r.S_uu[k] > kNoInputPower * peak)) dead.push_back(k);
  }
  if (dead.empty()) return;
  const size_t n = r.f_hz.size(), lo = dead.front(), hi = dead.back();
  const bool block = hi - lo + 1 == dead.size();
  std::string msg = source + ": no input power at " +
                    (lo == hi ? Num(r.f_hz[lo]) : Num(r.f_hz[lo]) + "-" + Num(r.f_hz[hi])) + " Hz (" +
                    (block ? "" : std::to_string(dead.size()) + " bins in that range, ") +
                    "input PSD below 1e-24 of its peak: the excitation has no content there and the response is "
                    "0/0): ";
  if (block && hi == n - 1 && lo > 0) {
    msg += "limit the band with WelchOptions::fmax_hz " + Num(r.f_hz[lo - 1]);
  } else if (block && lo == 0 && hi < n - 1) {
    msg += "limit the band with WelchOptions::fmin_hz " + Num(r.f_hz[hi + 1]);
  } else {
    msg += "limit the band with WelchOptions::fmin_hz/WelchOptions::fmax_hz to the excitation's "
           "(and for a periodic excitation, make the segment its period)";
  }
  throw InputError(msg);
}

void WriteFrequencyResponse(const std::string& path, const ident::FrequencyResponse& r) {
  CheckFiniteResponse(r, path);
  const bool h5 = DetectLogFormat(path) == LogFormat::kHdf5;
  if (h5) {
    internal::WriteHdf5Atomically(path, [&](const internal::Hdf5Api& api, const std::string& tmp) {
      api.write_frf_hdf5(tmp, r);
    });
  } else {
    WriteAtomically(path, [&](const std::string& tmp) { WriteCsv(tmp, r); });
  }
}

bool IsFrequencyResponseFile(const std::string& path) {
  CheckInputFile(path, "input file");
  if (IsPackedFormat(path)) {
    bool frf = false;
    const internal::Hdf5Api& h5 = internal::Hdf5();
    const auto has = IsMatFile(path) ? h5.has_frf_mat_variables : h5.has_frf_group;
    RunIsolated(
        path,
        [&](const FrameSender& send) {
          const char yes = has(path) ? 1 : 0;
          send(&yes, 1);
        },
        [&](std::string_view frame) { frf = frame == std::string_view("\1", 1); });
    return frf;
  }
  std::ifstream in(path);
  std::string line;
  if (!ReadHeader(in, &line)) return false;
  // zwidth estimate's header, or one from elsewhere that starts f,...H_re.
  std::vector<std::string_view> fields;
  internal::SplitFields(line, ',', &fields);
  if (fields.empty() || CanonicalColumn(std::string(fields[0])) != "f_hz") return false;
  for (std::string_view f : fields) if (CanonicalColumn(std::string(f)) == "H_re") return true;
  return line.rfind("f_hz", 0) == 0 || line.rfind("\"f_hz\"", 0) == 0;
}

ident::FrequencyResponse ReadFrequencyResponse(const std::string& path, double rate) {
  return ReadFrequencyResponse(path, rate, nullptr);
}

ident::FrequencyResponse ReadFrequencyResponse(const std::string& path, double rate, std::string* note) {
  CheckInputFile(path, "frequency-response file");
  ident::FrequencyResponse r = IsPackedFormat(path) ? ReadPacked(path, true) : ReadCsv(path);
  Finish(r, path, rate, note);
  return r;
}

namespace internal {
ident::FrequencyResponse ReadFrequencyResponseInProcess(const std::string& path, double rate) {
  ident::FrequencyResponse r = IsPackedFormat(path) ? ReadPacked(path, false) : ReadCsv(path);
  Finish(r, path, rate, nullptr);
  return r;
}
}  // namespace internal

}  // namespace zwidth::io
