// The HDF5 side of io/frf_file.cc (in the plugin zwidth-hdf5.so for the zwidth
// executable, see io/hdf5_api.h): /frf/<column> datasets and root attributes.
#include <cmath>
#include <string>
#include <vector>

#include <H5Cpp.h>

#include "io/h5_safety.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "model/error.h"

namespace zwidth::io::internal {

void WriteFrfHdf5(const std::string& tmp, const ident::FrequencyResponse& r) {
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
    auto attr = [&](const char* name, double v) { WriteDoubleAttr(root, name, v); };
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

// /frf/{f_hz,H_re,H_im[,coherence,H_std,S_uu,S_yy]} and root attributes, as
// WriteFrfHdf5 writes them, read in this process (RunIsolated calls it in a child)
// and packed as doubles: n, the four scalars, then the seven columns.
std::string ReadFrfHdf5Packed(const std::string& path) {
  H5::Exception::dontPrint();
  try {
    if (!H5::H5File::isHdf5(path)) throw InputError(path + ": not an HDF5 file");
    H5::H5File file(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, SafeH5Access());
    if (!H5LinkExists(file.getId(), path, "/frf")) {
      throw InputError(path + ": no group /frf (not written by `zwidth estimate`?)");
    }
    size_t n = 0;
    auto get = [&](const char* name, bool required) {
      const std::string full = std::string("/frf/") + name;
      std::vector<double> v;
      if (!H5LinkExists(file.getId(), path, full)) {
        if (required) throw InputError(path + ": no dataset '" + full + "'");
        return v;
      }
      H5::DataSet ds = file.openDataSet(full);
      CheckH5DatasetLocal(ds.getId(), path + ":" + full);
      H5::DataSpace sp = ds.getSpace();
      if (sp.getSimpleExtentNdims() != 1) throw InputError(path + ":" + full + ": expected a 1-D dataset");
      hsize_t len = 0;
      sp.getSimpleExtentDims(&len);
      // A corrupt header can claim 1e12 values (the fuzzer found one): that
      // must not become an allocation.
      if (len > kMaxFrfBins) {
        throw InputError(path + ":" + full + ": " + std::to_string(len) + " values, more than a response has (" +
                         std::to_string(kMaxFrfBins) + "): corrupt file?");
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
      return ReadH5ScalarAttribute(file.getId(), name, path);
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

bool HasFrfGroup(const std::string& path) {
  H5::Exception::dontPrint();
  try {
    if (!H5::H5File::isHdf5(path)) return false;
    H5::H5File file(path, H5F_ACC_RDONLY, H5::FileCreatPropList::DEFAULT, SafeH5Access());
    return H5LinkExists(file.getId(), path, "/frf");
  } catch (const H5::Exception&) {
    return false;  // not readable as HDF5: the log reader says why
  } catch (const InputError&) {
    return false;  // an external link: the reader says why
  }
}

}  // namespace zwidth::io::internal
