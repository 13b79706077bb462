// The module zwidth-hdf5.so that the zwidth executable loads on first use
// (io/hdf5_api.h): this file plus zwidth_hdf5 (the HDF5 and MATLAB readers
// and writers), the part of zwidth_io they reference, and libhdf5/libmatio.
#include "io/hdf5_api.h"
#include "zwidth_abi_hash.h"  // generated (cmake/abi_hash.cmake)

extern "C" __attribute__((visibility("default"))) const void* zwidth_hdf5_plugin(unsigned long long key) {
  if (key != (zwidth::io::internal::kHdf5ApiKey ^ ZWIDTH_ABI_HASH)) return nullptr;  // built from other headers
  return &zwidth::io::internal::LinkedHdf5();
}
