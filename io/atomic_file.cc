#include "io/atomic_file.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "model/error.h"

namespace zwidth::io {
namespace fs = std::filesystem;

void CheckOutputFolder(const std::string& path) {
  if (path.empty()) throw InputError("output path is empty");
  fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) parent = ".";
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw InputError("output folder '" + parent.string() + "' for '" + path +
                     "' does not exist: create it first");
  }
  if (fs::is_directory(path, ec)) {
    throw InputError("output '" + path + "' is a folder, expected a file name");
  }
}

void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string&)>& write) {
  CheckOutputFolder(path);
  std::random_device rd;
  const std::string tmp = path + ".tmp-" + std::to_string(rd() % 1000000000u);
  try {
    write(tmp);
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw InputError("cannot write '" + path + "': " + ec.message());
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

void WriteTextAtomically(const std::string& path, const std::string& content) {
  WriteAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw InputError("cannot create '" + tmp + "' (is the folder writable?)");
    out << content;
    out.close();
    if (!out) throw InputError("failed writing '" + path + "' (disk full?)");
  });
}

}  // namespace zwidth::io
