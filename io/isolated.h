// Work on an untrusted file in a child process. libhdf5 (1.10) can read out of
// bounds, even crash, on a corrupt file (our fuzzing found an H5Aexists crash);
// in a forked child such a crash becomes an InputError, not the end of zwidth.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace zwidth::io {

// Runs work() in a forked child and returns the bytes it returned. An exception
// thrown by work() comes back as an InputError with its message; a crash of the
// child as an InputError naming `path`. Where fork() is unavailable, work()
// runs in this process.
std::string RunIsolated(const std::string& path, const std::function<std::string()>& work);

namespace internal {
// write()/read() of exactly n bytes, retried on EINTR; false on error or EOF.
bool WriteAll(int fd, const void* data, size_t n);
bool ReadAll(int fd, void* data, size_t n);
}  // namespace internal

}  // namespace zwidth::io
