// The table of the real HDF5 and MATLAB functions, in the static library
// zwidth_hdf5 (target zwidth::hdf5; see io/hdf5_api.h). Linked, it becomes
// Hdf5()'s provider before main; the zwidth executable never links it (it
// loads the same table from the plugin zwidth-hdf5.so, io/hdf5_plugin.cc).
#include "io/hdf5_api.h"

#include <hdf5.h>

#include "io/log_internal.h"

namespace zwidth::io::internal {

const Hdf5Api& LinkedHdf5() {
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
    a.write_batch_table_hdf5 = WriteBatchTableHdf5;
    a.read_batch_table_hdf5 = ReadBatchTableHdf5;
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

namespace {
// Runs when this object is linked, which zwidth::hdf5's link interface
// ensures (--undefined=zwidth_link_hdf5: a static library's member that
// nothing references is otherwise left out, with its initialiser).
const bool kProvided = (SetHdf5Provider(&LinkedHdf5), true);
}  // namespace

}  // namespace zwidth::io::internal

extern "C" void zwidth_link_hdf5() { static_cast<void>(zwidth::io::internal::kProvided); }
