// Checks shared by the HDF5 readers (io/log.cc, io/frf_file.cc): an HDF5 file
// is read only from itself. Internal to io/ (it needs H5Cpp.h).
#pragma once

#include <string>

#include <H5Cpp.h>

namespace zwidth::io::internal {

// File access properties under which an external link is never traversed.
H5::FileAccPropList SafeH5Access();

// Whether the object `name` ("/a/b") exists, checked link by link from the
// root; an external or user-defined link on the way is an InputError (never
// followed). `path` is the file's, for the message.
bool H5LinkExists(hid_t file, const std::string& path, const std::string& name);

// InputError unless the dataset's data are inside the file: no external
// storage (H5Pget_external_count), not a virtual dataset, no filter this
// library lacks; and, when `numbers`, stored as plain numbers.
void CheckH5DatasetLocal(hid_t dataset, const std::string& where, bool numbers = true);

// The attribute `name` of `object` as a double; InputError unless it holds
// exactly one number (its dataspace has one point, its type is numeric).
double ReadH5ScalarAttribute(hid_t object, const std::string& name, const std::string& where);

}  // namespace zwidth::io::internal
