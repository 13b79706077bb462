#include "io/atomic_file.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <utility>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "model/error.h"

namespace zwidth::io {
namespace fs = std::filesystem;
namespace {

// ---- inputs noted by CheckInputFile
std::mutex g_inputs_mutex;
std::vector<std::pair<std::string, std::pair<dev_t, ino_t>>> g_inputs;

const char* Kind(mode_t m) {
  if (S_ISDIR(m)) return "a folder";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISFIFO(m)) return "a FIFO (named pipe)";
  if (S_ISSOCK(m)) return "a socket";
  if (S_ISLNK(m)) return "a symbolic link";
  if (S_ISREG(m)) return "a regular file";
  return "not a regular file";
}

std::string Parent(const std::string& path) {
  fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

// The file that writing `path` replaces: `path` itself, or the regular file a
// symlink names. Throws InputError for anything else.
std::string Destination(const std::string& path) {
  struct stat ls;
  if (::lstat(path.c_str(), &ls) != 0) {
    if (errno != ENOENT) {
      throw InputError("output '" + path + "': " + std::strerror(errno));
    }
    struct stat ps;
    const std::string parent = Parent(path);
    if (::stat(parent.c_str(), &ps) != 0 || !S_ISDIR(ps.st_mode)) {
      throw InputError("output folder '" + parent + "' for '" + path + "' does not exist: create it first");
    }
    return path;
  }
  if (S_ISLNK(ls.st_mode)) {
    struct stat ts;
    if (::stat(path.c_str(), &ts) != 0) {
      throw InputError("output '" + path + "' is a symbolic link to nothing that exists: give a file name");
    }
    if (!S_ISREG(ts.st_mode)) {
      throw InputError("output '" + path + "' is a symbolic link to " + Kind(ts.st_mode) +
                       ", not to a regular file: give a file name to write (nothing was written)");
    }
    char* real = ::realpath(path.c_str(), nullptr);
    if (real == nullptr) throw InputError("output '" + path + "': cannot resolve the symbolic link");
    std::string target(real);
    std::free(real);
    return target;
  }
  if (!S_ISREG(ls.st_mode)) {
    if (S_ISDIR(ls.st_mode)) {
      throw InputError("output '" + path + "' is a folder, expected a file name");
    }
    throw InputError("output '" + path + "' is " + Kind(ls.st_mode) +
                     ", not a regular file: give a file name to write (nothing was written)");
  }
  return path;
}

}  // namespace

void ForgetNotedInputs() { std::lock_guard<std::mutex> lock(g_inputs_mutex); g_inputs.clear(); }

std::vector<std::string> NotedInputs() {
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  std::vector<std::string> out;
  std::vector<std::pair<dev_t, ino_t>> seen;
  for (const auto& [path, id] : g_inputs) {
    if (std::find(seen.begin(), seen.end(), id) != seen.end()) continue;
    seen.push_back(id);
    out.push_back(path);
  }
  return out;
}

namespace {

// Throws when `dest` is the same file as an input (noted, or in `inputs`).
void CheckNotAnInput(const std::string& shown, const std::string& dest, const std::vector<std::string>& inputs) {
  struct stat ds;
  if (::stat(dest.c_str(), &ds) != 0) return;  // a new file is no input
  auto refuse = [&](const std::string& input) {
    throw InputError("output '" + shown + "' is the input '" + input +
                     "' (the same file): choose another output name, the input would be destroyed");
  };
  for (const std::string& in : inputs) {
    struct stat is;
    if (in != "-" && ::stat(in.c_str(), &is) == 0 && is.st_dev == ds.st_dev && is.st_ino == ds.st_ino) refuse(in);
  }
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  for (const auto& [name, id] : g_inputs) {
    // Still that file under that name (an inode of a file deleted since may
    // have been reused by an unrelated one, in a long-lived process).
    struct stat is;
    if (id.first == ds.st_dev && id.second == ds.st_ino && ::stat(name.c_str(), &is) == 0 &&
        is.st_dev == ds.st_dev && is.st_ino == ds.st_ino) {
      refuse(name);
    }
  }
}

// ---- the temporary-path registry and its signal handler
struct Slot {
  std::atomic<int> used{0};
  char path[4096];
};
Slot g_slots[kMaxTempPaths];
std::mutex g_slots_mutex;
std::once_flag g_handlers_once;

// unlink, or empty (depth levels deep) and rmdir: async-signal-safe calls only.
void RemovePathSignalSafe(const char* p, int depth) {
  if (::unlink(p) == 0 || errno == ENOENT) return;
  if (::rmdir(p) == 0) return;
  if (depth <= 0) return;
  const int fd = ::open(p, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return;
  char buf[4096];
  char child[4096];
  const size_t plen = ::strlen(p);
  for (int round = 0; round < 64; ++round) {
    const long n = ::syscall(SYS_getdents64, fd, buf, sizeof buf);
    if (n <= 0) break;
    for (long off = 0; off < n;) {
      // struct linux_dirent64: u64 ino, s64 off, u16 reclen, u8 type, char name[]
      unsigned short reclen;
      ::memcpy(&reclen, buf + off + 16, sizeof reclen);
      const char* name = buf + off + 19;
      off += reclen;
      if (name[0] == '.' && (name[1] == 0 || (name[1] == '.' && name[2] == 0))) continue;
      const size_t nlen = ::strlen(name);
      if (plen + 1 + nlen + 1 > sizeof child) continue;
      ::memcpy(child, p, plen);
      child[plen] = '/';
      ::memcpy(child + plen + 1, name, nlen + 1);
      RemovePathSignalSafe(child, depth - 1);
    }
  }
  ::close(fd);
  ::rmdir(p);
}

void OnSignal(int sig) {
  const int saved = errno;
  for (int i = kMaxTempPaths - 1; i >= 0; --i) {
    if (g_slots[i].used.load(std::memory_order_acquire) == 1) RemovePathSignalSafe(g_slots[i].path, 2);
  }
  errno = saved;
  ::signal(sig, SIG_DFL);
  ::raise(sig);  // SA_NODEFER: delivered now, with the default action
}

// The signals that end a process by default and that a user or the system
// sends to a CLI run: ^C, kill, a closed terminal, a closed pipe (`-o - |
// head`), a file size limit (`ulimit -f`).
constexpr int kCleanupSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGXFSZ};

void InstallHandlers() {
  struct sigaction sa;
  std::memset(&sa, 0, sizeof sa);
  sa.sa_handler = OnSignal;
  sa.sa_flags = SA_NODEFER;
  sigemptyset(&sa.sa_mask);
  for (int sig : kCleanupSignals) {
    struct sigaction old;
    // A signal the caller chose to ignore (nohup) stays ignored.
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    ::sigaction(sig, &sa, nullptr);
  }
}

// A new name `base`.tmp-XXXXXX, registered before create(name) makes it, so
// that no signal can arrive between the two. create returns false when the
// name exists (another try), throws on other errors.
std::string CreateRegistered(const std::string& base, const std::function<bool(const std::string&)>& create) {
  static const char kAlphabet[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  for (int attempt = 0; attempt < 100; ++attempt) {
    unsigned x = rd() ^ (counter.fetch_add(1) * 2654435761u) ^ static_cast<unsigned>(::getpid());
    std::string name = base + ".tmp-";
    for (int i = 0; i < 6; ++i, x /= 62) name += kAlphabet[x % 62];
    RegisterTempPath(name);
    try {
      if (create(name)) return name;
    } catch (...) {
      UnregisterTempPath(name);
      throw;
    }
    UnregisterTempPath(name);
  }
  throw InputError("cannot create a temporary name beside '" + base + "'");
}

// A new empty file `base`.tmp-XXXXXX (mode 0666 less the umask), registered.
std::string CreateTemp(const std::string& base) {
  return CreateRegistered(base, [&](const std::string& name) {
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      return true;
    }
    if (errno == EEXIST) return false;
    throw InputError("cannot create a file beside '" + base + "': " + std::strerror(errno) +
                     " (is the folder writable?)");
  });
}

void SyncFile(const std::string& tmp, const std::string& shown) {
  const int fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || ::fsync(fd) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    throw InputError("failed writing '" + shown + "': " + why + " (disk full?); nothing was written");
  }
  if (::close(fd) != 0) throw InputError("failed writing '" + shown + "' (disk full?); nothing was written");
}

// Removes the (registered) temporary file however the scope is left.
struct TempGuard {
  std::string path;
  explicit TempGuard(std::string p) : path(std::move(p)) {}
  ~TempGuard() {
    ::unlink(path.c_str());
    UnregisterTempPath(path);
  }
};

// The permission bits of an existing `dest` given to `tmp` before it replaces
// it (a 0600 file stays 0600; a new file keeps 0666 less the umask).
void KeepMode(const std::string& tmp, const std::string& dest) {
  struct stat ds;
  if (::stat(dest.c_str(), &ds) == 0) ::chmod(tmp.c_str(), ds.st_mode & 07777);
}

// ---- stale temporary folders of OutputFolder
//
// Each temporary folder holds kLockName, open and flock()ed by the process
// that made it for as long as it lives (the kernel drops the lock when the
// process ends, even by SIGKILL). A sibling ".NAME.tmp-XXXXXX" folder holding
// that file which can be locked belongs to no live process: a run killed by
// SIGKILL (or a power cut), which left it. Only such folders are removed: a
// folder without the lock file is not zwidth's, one whose lock is held is a
// live run's.
constexpr const char* kLockName = ".zwidth-run.lock";

bool IsTempName(const std::string& name, const std::string& prefix) {
  if (name.size() != prefix.size() + 6 || name.compare(0, prefix.size(), prefix) != 0) return false;
  for (size_t i = prefix.size(); i < name.size(); ++i) {
    if (!std::isalnum(static_cast<unsigned char>(name[i]))) return false;
  }
  return true;
}

// Removes the stale ".NAME.tmp-XXXXXX" siblings of `base` (= folder/.NAME).
void RemoveStaleTemps(const std::string& base) {
  const fs::path b(base);
  const std::string prefix = b.filename().string() + ".tmp-";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(b.parent_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (!IsTempName(name, prefix) || !e.is_directory(ec) || e.is_symlink(ec)) continue;
    const std::string lock = (e.path() / kLockName).string();
    const int fd = ::open(lock.c_str(), O_RDWR | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) fs::remove_all(e.path(), ec);
    ::close(fd);
  }
}

}  // namespace

void CheckInputFile(const std::string& path, const std::string& what) {
  struct stat st;
  if (path.empty()) throw InputError(what + ": empty path");
  if (::stat(path.c_str(), &st) != 0) {
    throw InputError(path + ": cannot open " + what + " (" + std::strerror(errno) + "; does it exist?)");
  }
  if (!S_ISREG(st.st_mode)) {
    throw InputError(path + ": the " + what + " is " + Kind(st.st_mode) +
                     ", not a regular file: give a file (save a stream to a file first)");
  }
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  for (const auto& in : g_inputs) {
    if (in.second.first == st.st_dev && in.second.second == st.st_ino) return;
  }
  g_inputs.push_back({path, {st.st_dev, st.st_ino}});
}

void CheckOutputPath(const std::string& path, const std::vector<std::string>& inputs) {
  if (path.empty()) throw InputError("output path is empty");
  if (path == "-") return;
  const std::string dest = Destination(path);
  CheckNotAnInput(path, dest, inputs);
}

void CheckOutputKind(const std::string& path, const std::string& what, const std::vector<std::string>& extensions) {
  if (path == "-") return;
  const std::string name = std::filesystem::path(path).filename().string();
  const size_t dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0) return;  // no extension (a dot file is a name)
  std::string ext = name.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const std::string& e : extensions) if (ext == e) return;
  bool known = false;
  for (const char* e : kKnownOutputExtensions) known = known || ext == e;
  if (!known) return;
  std::string accepted;
  for (const std::string& e : extensions) accepted += (accepted.empty() ? "" : ", ") + e;
  throw InputError("output '" + path + "': this command writes " + what + ", but '" + ext.substr(0, 20) +
                   "' is the extension of another format; nothing was written. Give a name ending " + accepted +
                   " (or with no extension)");
}

void WriteAtomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  if (path.empty()) throw InputError("output path is empty");
  if (path == "-") {
    const char* dir = std::getenv("TMPDIR");
    TempGuard tmp(CreateTemp(std::string(dir && *dir ? dir : "/tmp") + "/zwidth-stdout"));
    write(tmp.path);
    std::ifstream in(tmp.path, std::ios::binary);
    std::fflush(stdout);
    char buf[1 << 16];
    while (in.read(buf, sizeof buf) || in.gcount() > 0) {
      if (std::fwrite(buf, 1, static_cast<size_t>(in.gcount()), stdout) != static_cast<size_t>(in.gcount())) break;
    }
    if (in.bad() || std::fflush(stdout) != 0 || std::ferror(stdout)) {
      throw InputError("cannot write to standard output");
    }
    return;
  }
  const std::string dest = Destination(path);
  CheckNotAnInput(path, dest, {});
  TempGuard tmp(CreateTemp(dest));
  write(tmp.path);
  SyncFile(tmp.path, path);
  // Checked again just before the rename: the destination may have changed
  // (another process) during the work.
  if (Destination(path) != dest) throw InputError("output '" + path + "' changed while writing; nothing was written");
  CheckNotAnInput(path, dest, {});
  KeepMode(tmp.path, dest);
  if (::rename(tmp.path.c_str(), dest.c_str()) != 0) {
    throw InputError("cannot write '" + path + "': " + std::strerror(errno));
  }
}

void WriteTextAtomically(const std::string& path, const std::string& content) {
  WriteAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError("cannot create '" + tmp + "' (is the folder writable?)");
    out << content;
    out.close();
    if (!out) throw InputError("failed writing '" + path + "' (disk full?); nothing was written");
  });
}

void InstallCleanupSignalHandlers() { std::call_once(g_handlers_once, InstallHandlers); }

void RegisterTempPath(const std::string& path) {
  if (path.size() + 1 > sizeof(g_slots[0].path)) return;
  std::lock_guard<std::mutex> lock(g_slots_mutex);
  for (Slot& s : g_slots) {
    if (s.used.load() == 0) {
      std::memcpy(s.path, path.c_str(), path.size() + 1);
      s.used.store(1, std::memory_order_release);
      return;
    }
  }
}

void UnregisterTempPath(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_slots_mutex);
  for (int i = kMaxTempPaths - 1; i >= 0; --i) {
    Slot& s = g_slots[i];
    if (s.used.load() == 1 && path == s.path) {
      s.used.store(0, std::memory_order_release);
      return;
    }
  }
}

// ---- OutputFolder

OutputFolder::OutputFolder(const std::string& path_given, bool force) : path_(path_given), force_(force) {
  if (path_given.empty()) throw InputError("output folder name is empty");
  std::string path = path_given;  // "out/" is the folder "out"
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  path_ = path;
  struct stat ls;
  if (::lstat(path.c_str(), &ls) == 0) {
    struct stat ts;
    if (::stat(path.c_str(), &ts) != 0 || !S_ISDIR(ts.st_mode)) {
      throw InputError("output folder '" + path + "' exists and is " +
                       (S_ISLNK(ls.st_mode) ? std::string("a symbolic link to something else") : Kind(ls.st_mode)) +
                       ", not a folder: give a new folder name");
    }
    if (S_ISLNK(ls.st_mode)) {
      char* real = ::realpath(path.c_str(), nullptr);
      if (real == nullptr) throw InputError("output folder '" + path + "': cannot resolve the symbolic link");
      path_ = real;
      std::free(real);
    }
    std::error_code ec;
    const bool empty = fs::is_empty(path_, ec);
    if (ec) throw InputError("output folder '" + path + "': " + ec.message());
    if (!empty && !force) {
      throw InputError("output folder '" + path +
                       "' is not empty: choose a new folder, empty this one, or pass OutputFolder::force to replace "
                       "zwidth's files in it (other files are kept)");
    }
  } else {
    if (errno != ENOENT) throw InputError("output folder '" + path + "': " + std::strerror(errno));
    struct stat ps;
    const std::string parent = Parent(path);
    if (::stat(parent.c_str(), &ps) != 0 || !S_ISDIR(ps.st_mode)) {
      throw InputError("output folder '" + path + "': its parent folder '" + parent +
                       "' does not exist: create it first");
    }
  }
  std::string p = path_;
  while (p.size() > 1 && p.back() == '/') p.pop_back();
  const fs::path fp(p);
  const std::string base = (fp.parent_path().empty() ? fs::path(".") : fp.parent_path()).string() + "/." +
                           fp.filename().string();
  RemoveStaleTemps(base);
  temp_ = CreateRegistered(base, [&](const std::string& name) {
    if (::mkdir(name.c_str(), 0777) == 0) return true;
    if (errno == EEXIST) return false;
    throw InputError("cannot create a folder beside '" + path + "': " + std::strerror(errno) +
                     " (is the parent folder writable?)");
  });
  path_ = p;
  const std::string lock = temp_ + "/" + kLockName;
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (lock_fd_ >= 0) ::flock(lock_fd_, LOCK_EX);
}

void OutputFolder::DropLock() {
  if (lock_fd_ < 0) return;
  ::unlink((temp_ + "/" + kLockName).c_str());
  ::close(lock_fd_);
  lock_fd_ = -1;
}

OutputFolder::~OutputFolder() {
  DropLock();
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(temp_, ec);
  }
  UnregisterTempPath(temp_);
}

void OutputFolder::Commit() {
  DropLock();  // not an output; the folder is ours until renamed (a rename keeps no lock anyway)
  std::error_code ec;
  const bool exists = fs::exists(path_, ec);
  if (!exists || !force_ || fs::is_empty(path_, ec)) {
    // rename(2) replaces an empty folder atomically and fails on a non-empty
    // one: a concurrent run into the same folder cannot mix its files with ours.
    if (::rename(temp_.c_str(), path_.c_str()) != 0) {
      const int err = errno;
      if (err == ENOTEMPTY || err == EEXIST || err == ENOTDIR) {
        throw InputError("output folder '" + path_ +
                         "' was filled by another process while this run worked: nothing was written; "
                         "run again into a new folder");
      }
      throw InputError("cannot create output folder '" + path_ + "': " + std::strerror(err));
    }
    committed_ = true;
    return;
  }
  // --force into a non-empty folder: every destination checked first, then
  // each file renamed over the one of the same name.
  std::vector<std::pair<fs::path, fs::path>> moves;
  for (auto it = fs::recursive_directory_iterator(temp_); it != fs::recursive_directory_iterator(); ++it) {
    const fs::path rel = fs::relative(it->path(), temp_);
    const fs::path dest = fs::path(path_) / rel;
    struct stat ls;
    const bool there = ::lstat(dest.c_str(), &ls) == 0;
    if (it->is_directory()) {
      if (there && !S_ISDIR(ls.st_mode)) {
        throw InputError("output '" + dest.string() + "' exists and is not a folder: nothing was written");
      }
      continue;
    }
    if (there && !S_ISREG(ls.st_mode)) {
      throw InputError("output '" + dest.string() + "' is " + Kind(ls.st_mode) +
                       ", not a regular file: nothing was written");
    }
    CheckNotAnInput(dest.string(), dest.string(), {});
    moves.push_back({it->path(), dest});
  }
  for (const auto& [from, to] : moves) {
    fs::create_directories(to.parent_path(), ec);
    KeepMode(from.string(), to.string());
    if (::rename(from.c_str(), to.c_str()) != 0) {
      throw InputError("cannot write '" + to.string() + "': " + std::strerror(errno));
    }
  }
  fs::remove_all(temp_, ec);
  committed_ = true;
}

}  // namespace zwidth::io
