#include "io/isolated.h"

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <sys/wait.h>
#include <unistd.h>

#include "model/error.h"

namespace zwidth::io {

namespace internal {

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

}  // namespace internal

std::string RunIsolated(const std::string& path, const std::function<std::string()>& work) {
  using internal::ReadAll;
  using internal::WriteAll;
  constexpr char kDone = 1, kError = 2;
  int fds[2];
  if (::pipe(fds) != 0) return work();
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    return work();
  }
  if (pid == 0) {  // child: leave without running destructors
    ::close(fds[0]);
    const int out = fds[1];
    char type = kDone;
    std::string bytes;
    try {
      bytes = work();
    } catch (const std::exception& e) {
      type = kError;
      bytes = e.what();
    }
    const uint64_t len = bytes.size();
    const bool ok = WriteAll(out, &type, 1) && WriteAll(out, &len, sizeof len) && WriteAll(out, bytes.data(), len);
    ::close(out);
    ::_exit(ok ? 0 : 3);
  }
  ::close(fds[1]);
  char type = 0;
  uint64_t len = 0;
  std::string bytes;
  bool complete = ReadAll(fds[0], &type, 1) && ReadAll(fds[0], &len, sizeof len) && len < (uint64_t{1} << 32);
  if (complete) {
    bytes.resize(len);
    complete = ReadAll(fds[0], bytes.data(), len);
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (complete && type == kError) throw InputError(bytes);
  if (WIFSIGNALED(status)) {
    throw InputError(path + ": the HDF5 library crashed reading this file (signal " +
                     std::to_string(WTERMSIG(status)) + "): the file is corrupt or truncated");
  }
  if (!complete || type != kDone) throw InputError(path + ": could not read the file (corrupt or truncated?)");
  return bytes;
}

}  // namespace zwidth::io
