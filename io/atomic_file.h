// Outputs are written to a temporary name in the destination folder and renamed
// into place, so that a failure never leaves a half-written file (STYLE.md).
#pragma once

#include <functional>
#include <string>

namespace zwidth::io {

// Calls write(tmp_path) and renames tmp_path to path. On any exception the
// temporary file is removed and the exception propagates. Throws InputError when
// the destination folder does not exist or is not writable.
void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string& tmp_path)>& write);

// Convenience: the whole content as text.
void WriteTextAtomically(const std::string& path, const std::string& content);

// Throws InputError unless the folder of `path` exists (used before long work,
// so that a bad -o fails at once rather than after the computation).
void CheckOutputFolder(const std::string& path);

}  // namespace zwidth::io
