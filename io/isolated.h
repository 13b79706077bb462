// Work on an untrusted file in a child process. libhdf5 (1.10) can read out of
// bounds, even crash, on a corrupt file (our fuzzing found an H5Aexists crash);
// in a forked child such a crash becomes an InputError, not the end of zwidth.
#pragma once

#include <cstddef>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace zwidth::io {

// Sends one frame from the child to the parent (the child exits if the parent
// is gone).
using FrameSender = std::function<void(const void* data, size_t size)>;

// Runs produce(send) in a forked child; the parent receives each frame, in
// order, through consume(), while the child still runs (so a long file streams
// through in bounded memory). An exception thrown by produce() comes back as an
// InputError with its message; a crash of the child as an InputError naming
// `path`; an exception thrown by consume() ends the child and propagates.
// Where pipe() or fork() fail, produce() runs in this process.
// The child dies with its parent (PR_SET_PDEATHSIG) and runs under resource
// limits: kChildCpuSeconds of CPU and, outside sanitizer builds, kChildAddressSpaceBytes
// of address space (a corrupt file cannot make it allocate or loop without end).
// In sanitizer builds a child that exits with a code other than zwidth's own
// (a sanitizer report: ASan/UBSan exit with 1 by default, see ASAN_OPTIONS
// exitcode), or dies of SIGABRT (abort_on_error=1), aborts this process, so that tests and fuzzers count it as a crash.
//
// Its cost, measured (bench/io_benchmark.cc, the shipped 30 s log, on a
// 2-core VM shared with other builds): fork + pipe + wait alone 1.3-2.5 ms
// wall, 0.6-0.8 ms CPU (BM_IsolationOnly); the read 0.9-1.6 ms in process
// against 7.8-15 ms in the child (BM_ReadHdf5Log/0 and /1), most of it page
// faults of the fresh child (~700 a read: libhdf5 callocs its metadata cache
// at every file open, and every page first written after fork() faults).
// Kept: a crash, an endless loop or a huge allocation in libhdf5 or libmatio
// on a hostile file (our fuzzing found a crash) must end as an InputError,
// and no in-process guard (signal handlers, seccomp) survives a corrupted
// heap. A few ms per file is small beside loading libhdf5 itself (~12 ms,
// the plugin zwidth-hdf5.so). The plugin is loaded by the parent before the
// fork (io/log.cc), once per process: loading it in each child instead would
// keep its ~40 libraries out of the parent but pay them for every file, and
// the parent needs them anyway to write HDF5.
void RunIsolated(const std::string& path, const std::function<void(const FrameSender&)>& produce,
                 const std::function<void(std::string_view frame)>& consume);

// Held by this process's own calls into libhdf5 and libmatio (every
// WriteAtomically, whose writer may be HDF5's) and by RunIsolated across
// fork(): libhdf5 is built thread-safe, with one global lock, and a child
// forked while another thread held it (a Python thread saving a .h5 while
// three others read logs) inherited it held and hung for good at its first
// HDF5 call. Recursive: a writer may itself read an input in a child.
std::recursive_mutex& LibraryForkMutex();

// True in an ASan/UBSan build of zwidth's io library (then a child's sanitizer
// report aborts the parent, see above).
bool SanitizedBuild();

inline constexpr long kChildCpuSeconds = 600;
inline constexpr unsigned long long kChildAddressSpaceBytes = 4ull << 30;

// Runs argv[0] (searched in PATH) with arguments argv[1..], without a shell:
// no string is ever interpreted. Its working folder is `cwd` (when not empty),
// its standard input /dev/null, its standard error appended to `stderr_path`
// (when not empty). It receives SIGTERM when this process dies. Returns its exit
// status, 127 when it cannot be started (not installed), 128 + signal when killed.
int RunProgram(const std::vector<std::string>& argv, const std::string& cwd, const std::string& stderr_path);

}  // namespace zwidth::io
