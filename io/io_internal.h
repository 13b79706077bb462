// Helpers shared by the io readers and writers (internal: not installed,
// include only from io/*.cc).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace H5 { class H5Object; }

namespace zwidth::io::internal {

// The fields of `line` between the separators `sep`, untrimmed: one more
// field than separators (an empty line gives one empty field). The views
// point into `line`.
void SplitFields(std::string_view line, char sep, std::vector<std::string_view>* out);

// A scalar IEEE double attribute `name` = v on obj (a file's group or a
// dataset), closed before return so that a write error throws here.
// Defined in io/log_hdf5.cc (with the HDF5 code, see io/hdf5_api.h).
void WriteDoubleAttr(H5::H5Object& obj, const std::string& name, double v);

}  // namespace zwidth::io::internal
