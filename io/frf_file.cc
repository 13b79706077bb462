#include "io/frf_file.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>

#include <H5Cpp.h>

#include "io/atomic_file.h"
#include "io/log.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

void WriteCsv(const std::string& tmp, const ident::FrequencyResponse& r) {
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError("cannot create '" + tmp + "'");
  std::fputs("f_hz,H_re,H_im,coherence,H_std,H_mag,H_phase_deg,S_uu,S_yy,sample_rate_hz,"
             "num_averages,effective_averages,bin_correlation\n", f);
  for (size_t k = 0; k < r.f_hz.size(); ++k) {
    std::fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%.17g,%.17g\n",
                 r.f_hz[k], r.H[k].real(), r.H[k].imag(), r.coherence[k], r.H_std[k],
                 std::abs(r.H[k]), std::arg(r.H[k]) * 180.0 / std::numbers::pi, r.S_uu[k],
                 r.S_yy[k], r.sample_rate_hz, r.num_averages, r.effective_averages,
                 r.bin_correlation);
  }
  const bool ok = std::ferror(f) == 0;
  if (std::fclose(f) != 0 || !ok) throw InputError("failed writing '" + tmp + "'");
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
    };
    std::vector<double> re(n), im(n);
    for (hsize_t k = 0; k < n; ++k) { re[k] = r.H[k].real(); im[k] = r.H[k].imag(); }
    put("f_hz", r.f_hz); put("H_re", re); put("H_im", im);
    put("coherence", r.coherence); put("H_std", r.H_std); put("S_uu", r.S_uu); put("S_yy", r.S_yy);
    H5::Group root = file.openGroup("/");
    auto attr = [&](const char* name, double v) {
      H5::Attribute a = root.createAttribute(name, H5::PredType::IEEE_F64LE, H5::DataSpace(H5S_SCALAR));
      a.write(H5::PredType::NATIVE_DOUBLE, &v);
    };
    attr("sample_rate_hz", r.sample_rate_hz);
    attr("num_averages", r.num_averages);
    attr("effective_averages", r.effective_averages);
    attr("bin_correlation", r.bin_correlation);
    attr("window_length", r.window_length);
  } catch (const H5::Exception& e) {
    throw InputError("cannot write HDF5 '" + tmp + "': " + e.getDetailMsg());
  }
}

}  // namespace

void WriteFrequencyResponse(const std::string& path, const ident::FrequencyResponse& r) {
  const bool h5 = DetectLogFormat(path) == LogFormat::kHdf5;
  WriteAtomically(path, [&](const std::string& tmp) { h5 ? WriteH5(tmp, r) : WriteCsv(tmp, r); });
}

bool IsFrequencyResponseFile(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return false;
  return line.rfind("f_hz", 0) == 0 || line.rfind("\"f_hz\"", 0) == 0;
}

ident::FrequencyResponse ReadFrequencyResponseCsv(const std::string& path, double rate) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open frequency-response file");
  std::string line;
  if (!std::getline(in, line)) throw InputError(path + ": empty file");
  std::map<std::string, int> col;
  {
    size_t start = 0;
    int idx = 0;
    while (true) {
      size_t c = line.find(',', start);
      std::string name = line.substr(start, c == std::string::npos ? std::string::npos : c - start);
      while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
      col[name] = idx++;
      if (c == std::string::npos) break;
      start = c + 1;
    }
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
    size_t start = 0;
    while (true) {
      size_t c = line.find(',', start);
      const size_t end = c == std::string::npos ? line.size() : c;
      double x = 0.0;
      auto [p, ec] = std::from_chars(line.data() + start, line.data() + end, x);
      if (ec != std::errc() || p != line.data() + end) {
        throw InputError(path + ": line " + std::to_string(line_no) + ", field " +
                         std::to_string(v.size() + 1) + ": not a number");
      }
      v.push_back(x);
      if (c == std::string::npos) break;
      start = c + 1;
    }
    if (v.size() < col.size()) throw InputError(path + ": line " + std::to_string(line_no) + " is truncated");
    for (double x : v) {
      if (std::isnan(x)) throw InputError(path + ": line " + std::to_string(line_no) + " has a NaN");
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
    if (i_navg >= 0) r.num_averages = static_cast<int>(v[i_navg]);
    if (i_neff >= 0) r.effective_averages = v[i_neff];
    if (i_kappa >= 0) r.bin_correlation = v[i_kappa];
  }
  if (r.f_hz.empty()) throw InputError(path + ": no data rows");
  if (rate > 0.0) r.sample_rate_hz = rate;
  if (!(r.sample_rate_hz > 0.0)) {
    throw InputError(path + ": no sample_rate_hz column; pass --rate (the log's sample rate)");
  }
  if (r.f_hz.back() >= 0.5 * r.sample_rate_hz) {
    throw InputError(path + ": frequencies reach the Nyquist frequency of " +
                     std::to_string(r.sample_rate_hz) + " Hz; wrong --rate?");
  }
  return r;
}

}  // namespace zwidth::io
