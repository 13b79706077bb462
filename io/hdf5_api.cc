// Hdf5() of the static library zwidth_io: the real functions, linked directly
// (see io/hdf5_api.h; the zwidth executable defines its own Hdf5(), which
// loads them from the plugin, so this file and what it references stay out of
// the executable).
#include "io/hdf5_api.h"

#include <hdf5.h>

#include "io/log_internal.h"

namespace zwidth::io::internal {

const Hdf5Api& Hdf5() {
  static const Hdf5Api api = [] {
    Hdf5Api a;
    a.stream_hdf5_log = StreamHdf5InProcess;
    a.stream_mat_log = StreamMatInProcess;
    a.write_hdf5_log = WriteHdf5Log;
    a.write_frf_hdf5 = WriteFrfHdf5;
    a.write_model_hdf5 = WriteModelHdf5;
    a.read_frf_hdf5_packed = ReadFrfHdf5Packed;
    a.has_frf_group = HasFrfGroup;
    a.write_model_mat = WriteModelMat;
    a.read_frf_mat_packed = ReadFrfMatPacked;
    a.has_frf_mat_variables = HasFrfMatVariables;
    // Files and what lives in them, not datatypes: the C++ library creates
    // ~125 transient ones (H5::PredType) when it starts, which in the plugin
    // is during the first write.
    a.open_objects = [] {
      return static_cast<long>(
          H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_FILE | H5F_OBJ_DATASET | H5F_OBJ_GROUP | H5F_OBJ_ATTR));
    };
    return a;
  }();
  return api;
}

long Hdf5OpenObjects() { return Hdf5().open_objects(); }

}  // namespace zwidth::io::internal
