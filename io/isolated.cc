#include "io/isolated.h"

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "model/error.h"

#if defined(__SANITIZE_ADDRESS__)
#define ZWIDTH_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(undefined_behavior_sanitizer)
#define ZWIDTH_SANITIZED 1
#endif
#endif
#ifndef ZWIDTH_SANITIZED
#define ZWIDTH_SANITIZED 0
#endif

namespace zwidth::io {
namespace {

// In a fresh child: die with the parent, default signal actions (the parent's
// temporary-file handler is not the child's business).
void BecomeChild(pid_t parent, int death_signal) {
  ::prctl(PR_SET_PDEATHSIG, death_signal);
  if (::getppid() != parent) ::_exit(3);  // the parent died before prctl
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) ::signal(sig, SIG_DFL);
}

// write()/read() of exactly n bytes, retried on EINTR; false on error or EOF.
bool WriteAll(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

bool ReadAll(int fd, void* data, size_t n) {
  char* p = static_cast<char*>(data);
  while (n > 0) {
    const ssize_t r = ::read(fd, p, n);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    n -= static_cast<size_t>(r);
  }
  return true;
}

// On the pipe: a type byte, a uint64 length, the payload.
constexpr char kData = 1, kError = 2, kEnd = 3;
constexpr uint64_t kMaxFrame = uint64_t{1} << 30;

bool WriteFrame(int fd, char type, const void* data, uint64_t n) {
  return WriteAll(fd, &type, 1) && WriteAll(fd, &n, sizeof n) && WriteAll(fd, data, n);
}

// The child: limits, produce onto the pipe `out`, and leave without running
// destructors (exit 2 after an error frame, 3 when the parent is gone).
[[noreturn]] void RunChild(const std::string& path, const std::function<void(const FrameSender&)>& produce, int out,
                           pid_t parent) {
  BecomeChild(parent, SIGKILL);
  const rlimit cpu = {kChildCpuSeconds, kChildCpuSeconds + 5};
  ::setrlimit(RLIMIT_CPU, &cpu);
  if (!ZWIDTH_SANITIZED) {  // ASan reserves terabytes of address space for its shadow
    const rlimit as = {kChildAddressSpaceBytes, kChildAddressSpaceBytes};
    ::setrlimit(RLIMIT_AS, &as);
  }
  int code = 0;
  try {
    produce([&](const void* data, size_t n) {
      if (!WriteFrame(out, kData, data, n)) ::_exit(3);  // the parent is gone
    });
    WriteFrame(out, kEnd, nullptr, 0);
  } catch (const std::bad_alloc&) {
    const std::string msg = path + ": reading it needs more memory than a valid file would "
                                   "(corrupt sizes in the file?)";
    WriteFrame(out, kError, msg.data(), msg.size());
    code = 2;
  } catch (const std::exception& e) {
    const std::string msg = e.what();
    WriteFrame(out, kError, msg.data(), msg.size());
    code = 2;
  }
  ::close(out);
  ::_exit(code);
}

// The parent: hands every data frame to consume until the end frame (returns
// true) or an error frame (*error) or a broken pipe (false).
bool ReadFrames(int in, const std::string& path, const std::function<void(std::string_view frame)>& consume,
                std::string* error) {
  std::string frame;
  char type = 0;
  uint64_t n = 0;
  while (ReadAll(in, &type, 1) && ReadAll(in, &n, sizeof n) && n <= kMaxFrame) {
    frame.resize(n);
    if (!ReadAll(in, frame.data(), n)) return false;
    if (type == kData) {
      consume(frame);
    } else if (type == kError) {
      *error = frame.empty() ? path + ": unreadable file" : frame;
      return false;
    } else {
      return type == kEnd;
    }
  }
  return false;
}

// How the child ended, as the user's error (InputError) or a sanitizer's abort.
void CheckChild(const std::string& path, int status, const std::string& error, bool done) {
  // A sanitizer ends a process it reports on with its exitcode (1 by default),
  // or with SIGABRT under abort_on_error=1 (scripts/sanitize).
  if (ZWIDTH_SANITIZED && ((WIFEXITED(status) && WEXITSTATUS(status) != 0 && WEXITSTATUS(status) != 2 &&
                            WEXITSTATUS(status) != 3) ||
                           (WIFSIGNALED(status) && WTERMSIG(status) == SIGABRT))) {
    std::fprintf(stderr, "zwidth: the reader child for %s ended with status %d: a sanitizer report (see above)\n",
                 path.c_str(), status);
    std::abort();
  }
  if (!error.empty()) throw InputError(error);
  if (WIFSIGNALED(status) && (WTERMSIG(status) == SIGXCPU || WTERMSIG(status) == SIGKILL)) {
    throw InputError(path + ": reading this file took more than the " + std::to_string(kChildCpuSeconds) +
                     " s of CPU allowed, or was killed (corrupt file?)");
  }
  if (WIFSIGNALED(status)) {
    throw InputError(path + ": the HDF5 library crashed reading this file (signal " +
                     std::to_string(WTERMSIG(status)) + "): the file is corrupt or truncated");
  }
  if (!done) throw InputError(path + ": could not read the file (corrupt or truncated?)");
}

}  // namespace

void RunIsolated(const std::string& path, const std::function<void(const FrameSender&)>& produce,
                 const std::function<void(std::string_view frame)>& consume) {
  auto in_process = [&] {
    produce([&](const void* data, size_t n) { consume(std::string_view(static_cast<const char*>(data), n)); });
  };
  int fds[2];
  if (::pipe(fds) != 0) return in_process();
  std::fflush(nullptr);
  const pid_t parent = ::getpid();
  std::unique_lock<std::recursive_mutex> no_library_call_in_flight(LibraryForkMutex());
  const pid_t pid = ::fork();
  no_library_call_in_flight.unlock();  // in the parent; the child's copy is never used
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    return in_process();
  }
  if (pid == 0) {
    ::close(fds[0]);
    RunChild(path, produce, fds[1], parent);
  }
  ::close(fds[1]);
  const int in = fds[0];
  auto reap = [&](bool kill_child) {
    if (kill_child) ::kill(pid, SIGKILL);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    ::close(in);
    return status;
  };
  std::string error;
  bool done = false;
  try {
    done = ReadFrames(in, path, consume, &error);
  } catch (...) {
    reap(true);
    throw;
  }
  CheckChild(path, reap(false), error, done);
}

std::recursive_mutex& LibraryForkMutex() {
  static std::recursive_mutex m;
  return m;
}

bool SanitizedBuild() { return ZWIDTH_SANITIZED != 0; }

int RunProgram(const std::vector<std::string>& argv, const std::string& cwd, const std::string& stderr_path) {
  if (argv.empty()) return 127;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::fflush(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) return 127;
  if (pid == 0) {
    BecomeChild(parent, SIGTERM);
    if (!cwd.empty() && ::chdir(cwd.c_str()) != 0) ::_exit(127);
    const int in = ::open("/dev/null", O_RDONLY);
    if (in >= 0) ::dup2(in, 0);
    if (!stderr_path.empty()) {
      const int err = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
      if (err >= 0) ::dup2(err, 2);
    }
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return 127;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + WTERMSIG(status);
}

}  // namespace zwidth::io
