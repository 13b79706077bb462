#include "io/frf_file.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>

#include <H5Cpp.h>

#include "io/atomic_file.h"
#include "io/h5_safety.h"
#include "io/io_internal.h"
#include "io/isolated.h"
#include "io/log.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

void WriteCsv(const std::string& tmp, const ident::FrequencyResponse& r) {
  std::string text =
      "f_hz,H_re,H_im,coherence,H_std,H_mag,H_phase_deg,S_uu,S_yy,sample_rate_hz,"
      "num_averages,effective_averages,bin_correlation";
  const bool used = r.used_by_fit.size() == r.f_hz.size();  // the fit's bins, when known
  text += used ? ",used_by_fit\n" : "\n";
  internal::CsvLine line(&text);
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    line.G(r.f_hz[k], 17).G(r.H[k].real(), 17).G(r.H[k].imag(), 17).G(r.coherence[k], 17).G(r.H_std[k], 17);
    line.G(std::abs(r.H[k]), 17).G(std::arg(r.H[k]) * 180.0 / std::numbers::pi, 17).G(r.S_uu[k], 17);
    line.G(r.S_yy[k], 17).G(r.sample_rate_hz, 17).Int(r.num_averages).G(r.effective_averages, 17);
    line.G(r.bin_correlation, 17);
    if (used) line.Int(r.used_by_fit[k] ? 1 : 0);
    line.End();
  }
  internal::WriteWholeFile(tmp, text, tmp);
}

void WriteH5(const std::string& tmp, const ident::FrequencyResponse& r) {
  H5::Exception::dontPrint();
  try {
    H5::H5File file(tmp, H5F_ACC_TRUNC);
    H5::Group g = file.createGroup("/frf");
    const hsize_t n = r.f_hz.size();
    H5::DataSpace space(1, &n);
    auto put = [&](const char* name, const std::vector<double>& v) {
      H5::DataSet ds = g.createDataSet(name, H5::PredType::IEEE_F64LE, space);
      ds.write(v.data(), H5::PredType::NATIVE_DOUBLE);
      ds.close();
    };
    std::vector<double> re(n), im(n);
    for (hsize_t k = 0; k < n; ++k) { re[k] = r.H[k].real(); im[k] = r.H[k].imag(); }
    put("f_hz", r.f_hz); put("H_re", re); put("H_im", im);
    put("coherence", r.coherence); put("H_std", r.H_std); put("S_uu", r.S_uu); put("S_yy", r.S_yy);
    if (r.used_by_fit.size() == n) put("used_by_fit", std::vector<double>(r.used_by_fit.begin(), r.used_by_fit.end()));
    H5::Group root = file.openGroup("/");
    auto attr = [&](const char* name, double v) { internal::WriteDoubleAttr(root, name, v); };
    attr("sample_rate_hz", r.sample_rate_hz);
    attr("num_averages", r.num_averages);
    attr("effective_averages", r.effective_averages);
    attr("bin_correlation", r.bin_correlation);
    attr("window_length", r.window_length);
    // Closed inside the try: an error at flush or close (a full disk) fails
    // the write instead of vanishing in a destructor.
    root.close();
    g.close();
    file.flush(H5F_SCOPE_GLOBAL);
    file.close();
  } catch (const H5::Exception& e) {
    throw InputError("cannot write HDF5 '" + tmp + "': " + e.getDetailMsg());
  }
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

// The most values a response holds: the bins of a Welch window of 2^21
// samples (about 35 min at 1 kHz in one window). More is refused before it is
// read, so a small corrupt file cannot become gigabytes.
constexpr size_t kMaxBins = size_t{1} << 20;

ident::FrequencyResponse ReadCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open frequency-response file");
  std::string line;
  if (!std::getline(in, line)) throw InputError(path + ": empty file");
  std::map<std::string, int> col;
  size_t num_columns = 0;
  std::vector<std::string_view> fields;
  internal::SplitFields(line, ',', &fields);
  for (std::string_view f : fields) {
    std::string name(f);
    while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
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
            i_neff = index("effective_averages"), i_kappa = index("bin_correlation");
  ident::FrequencyResponse r;
  r.num_averages = 0;
  r.effective_averages = 0;
  r.bin_correlation = 1.0;
  size_t line_no = 1;
  std::vector<double> v;
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
    r.coherence.push_back(i_coh >= 0 ? v[i_coh] : 1.0);
    r.H_std.push_back(i_std >= 0 ? v[i_std] : 1e-3 * std::abs(h));
    r.S_uu.push_back(i_suu >= 0 ? v[i_suu] : 0.0);
    r.S_yy.push_back(i_syy >= 0 ? v[i_syy] : 0.0);
    r.S_uy.push_back(0.0);
    if (i_rate >= 0) r.sample_rate_hz = v[i_rate];
    if (i_navg >= 0) r.num_averages = Count(v[i_navg], path, "num_averages");
    if (i_neff >= 0) r.effective_averages = v[i_neff];
    if (i_kappa >= 0) r.bin_correlation = v[i_kappa];
  }
  if (r.f_hz.empty()) throw InputError(path + ": no data rows");
  return r;
}

// The rate (--rate wins over the file's) and the checks common to both formats.
void Finish(ident::FrequencyResponse& r, const std::string& path, double rate) {
  if (!(std::isfinite(r.effective_averages) && r.effective_averages >= 0.0)) {
    throw InputError(path + ": effective_averages = " + Num(r.effective_averages) + " must be finite, >= 0");
  }
  if (!(std::isfinite(r.bin_correlation) && r.bin_correlation > 0.0)) {
    throw InputError(path + ": bin_correlation = " + Num(r.bin_correlation) + " must be finite, > 0");
  }
  if (rate > 0.0) r.sample_rate_hz = rate;
  if (!(r.sample_rate_hz > 0.0) || !std::isfinite(r.sample_rate_hz)) {
    throw InputError(path + ": no sample_rate_hz column or attribute; pass ReadFrequencyResponse::sample_rate_hz (the log's sample rate)");
  }
  if (r.f_hz.back() >= 0.5 * r.sample_rate_hz) {
    char msg[160];
    std::snprintf(msg, sizeof msg, ": frequencies reach %g Hz, the Nyquist frequency of %g Hz; wrong ReadFrequencyResponse::sample_rate_hz?",
                  r.f_hz.back(), 0.5 * r.sample_rate_hz);
    throw InputError(path + msg);
  }
}

// /frf/{f_hz,H_re,H_im[,coherence,H_std,S_uu,S_yy]} and root attributes, as
// WriteH5 writes them, read in this process (RunIsolated calls it in a child)
// and packed as doubles: n, the four scalars, then the seven columns.
std::string ReadH5Packed(const std::string& path) {
  H5::Exception::dontPrint();
  try {
    if (!H5::H5File::isHdf5(path)) throw InputError(path + ": not an HDF5 file");
    H5::H5File file(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, internal::SafeH5Access());
    if (!internal::H5LinkExists(file.getId(), path, "/frf")) {
      throw InputError(path + ": no group /frf (not written by `zwidth estimate`?)");
    }
    size_t n = 0;
    auto get = [&](const char* name, bool required) {
      const std::string full = std::string("/frf/") + name;
      std::vector<double> v;
      if (!internal::H5LinkExists(file.getId(), path, full)) {
        if (required) throw InputError(path + ": no dataset '" + full + "'");
        return v;
      }
      H5::DataSet ds = file.openDataSet(full);
      internal::CheckH5DatasetLocal(ds.getId(), path + ":" + full);
      H5::DataSpace sp = ds.getSpace();
      if (sp.getSimpleExtentNdims() != 1) throw InputError(path + ":" + full + ": expected a 1-D dataset");
      hsize_t len = 0;
      sp.getSimpleExtentDims(&len);
      // A corrupt header can claim 1e12 values (the fuzzer found one): that
      // must not become an allocation.
      if (len > kMaxBins) {
        throw InputError(path + ":" + full + ": " + std::to_string(len) + " values, more than a response has (" +
                         std::to_string(kMaxBins) + "): corrupt file?");
      }
      if (ds.getTypeClass() != H5T_FLOAT) throw InputError(path + ":" + full + ": not a floating-point dataset");
      if (n == 0) n = len;
      if (len != n || len == 0) throw InputError(path + ":" + full + ": length " + std::to_string(len) +
                                                 ", expected " + std::to_string(n));
      v.resize(len);
      ds.read(v.data(), H5::PredType::NATIVE_DOUBLE);
      for (size_t k = 0; k < len; ++k) {
        if (!std::isfinite(v[k])) {
          throw InputError(path + ":" + full + ": value " + std::to_string(k) + " is not finite");
        }
      }
      return v;
    };
    const std::vector<double> f = get("f_hz", true), re = get("H_re", true), im = get("H_im", true);
    std::vector<double> coh = get("coherence", false), sd = get("H_std", false);
    std::vector<double> suu = get("S_uu", false), syy = get("S_yy", false);
    if (coh.empty()) coh.assign(n, 1.0);
    if (sd.empty()) {
      sd.resize(n);
      for (size_t k = 0; k < n; ++k) sd[k] = 1e-3 * std::hypot(re[k], im[k]);
    }
    if (suu.empty()) suu.assign(n, 0.0);
    if (syy.empty()) syy.assign(n, 0.0);
    for (size_t k = 1; k < n; ++k) {
      if (!(f[k] > f[k - 1])) throw InputError(path + ":/frf/f_hz: not increasing at " + std::to_string(k));
    }
    auto attr = [&](const char* name, double fallback) {
      if (!file.attrExists(name)) return fallback;
      return internal::ReadH5ScalarAttribute(file.getId(), name, path);
    };
    std::vector<double> packed = {static_cast<double>(n), attr("sample_rate_hz", 0.0), attr("num_averages", 0.0),
                                  attr("effective_averages", 0.0), attr("bin_correlation", 1.0)};
    const std::vector<double>* columns[] = {&f, &re, &im, &coh, &sd, &suu, &syy};
    for (const std::vector<double>* col : columns) {
      packed.insert(packed.end(), col->begin(), col->end());
    }
    return std::string(reinterpret_cast<const char*>(packed.data()), packed.size() * sizeof(double));
  } catch (const H5::Exception& e) {
    throw InputError(path + ": HDF5 error (" + e.getDetailMsg() + "): truncated or corrupt file?");
  }
}

ident::FrequencyResponse ReadH5(const std::string& path, bool isolated) {
  std::string bytes;
  if (isolated) {
    RunIsolated(
        path, [&](const FrameSender& send) { const std::string b = ReadH5Packed(path); send(b.data(), b.size()); },
        [&](std::string_view frame) { bytes = frame; });
  } else {
    bytes = ReadH5Packed(path);
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

}  // namespace

void CheckFiniteResponse(const ident::FrequencyResponse& r, const std::string& source) {
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    const double values[] = {r.f_hz[k], r.H[k].real(), r.H[k].imag(), r.coherence[k], r.H_std[k],
                             k < r.S_uu.size() ? r.S_uu[k] : 0.0, k < r.S_yy.size() ? r.S_yy[k] : 0.0};
    for (double v : values) {
      if (!std::isfinite(v)) {
        throw InputError(source + ": the frequency response has non-finite values (at bin " + std::to_string(k) +
                         ", f = " + Num(r.f_hz[k]) + " Hz): input scaled out of range (values near 1e308 "
                         "overflow the spectra); rescale the log's columns to SI units");
      }
    }
  }
}

void WriteFrequencyResponse(const std::string& path, const ident::FrequencyResponse& r) {
  CheckFiniteResponse(r, path);
  const bool h5 = DetectLogFormat(path) == LogFormat::kHdf5;
  WriteAtomically(path, [&](const std::string& tmp) { h5 ? WriteH5(tmp, r) : WriteCsv(tmp, r); });
}

bool IsFrequencyResponseFile(const std::string& path) {
  CheckInputFile(path, "input file");
  if (DetectLogFormat(path) == LogFormat::kHdf5) {
    bool frf = false;
    RunIsolated(
        path,
        [&](const FrameSender& send) {
          H5::Exception::dontPrint();
          char yes = 0;
          try {
            if (H5::H5File::isHdf5(path)) {
              H5::H5File file(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, internal::SafeH5Access());
              yes = internal::H5LinkExists(file.getId(), path, "/frf");
            }
          } catch (const H5::Exception&) {
            // not readable as HDF5: the log reader says why
          } catch (const InputError&) {
            // an external link: the reader says why
          }
          send(&yes, 1);
        },
        [&](std::string_view frame) { frf = frame == std::string_view("\1", 1); });
    return frf;
  }
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return false;
  return line.rfind("f_hz", 0) == 0 || line.rfind("\"f_hz\"", 0) == 0;
}

ident::FrequencyResponse ReadFrequencyResponse(const std::string& path, double rate) {
  CheckInputFile(path, "frequency-response file");
  ident::FrequencyResponse r = DetectLogFormat(path) == LogFormat::kHdf5 ? ReadH5(path, true) : ReadCsv(path);
  Finish(r, path, rate);
  return r;
}

namespace internal {
ident::FrequencyResponse ReadFrequencyResponseInProcess(const std::string& path, double rate) {
  ident::FrequencyResponse r = DetectLogFormat(path) == LogFormat::kHdf5 ? ReadH5(path, false) : ReadCsv(path);
  Finish(r, path, rate);
  return r;
}
}  // namespace internal

}  // namespace zwidth::io
