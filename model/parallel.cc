#include "model/parallel.h"

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include "model/error.h"

namespace zwidth {

namespace {

std::atomic<int> g_num_threads{0};  // SetNumThreads; 0 = not set
thread_local bool t_serial = false;  // a ScopedSerialThread lives on this thread

// The cgroup's CPU quota in CPUs, rounded up (v2 cpu.max "quota period", v1
// cfs_quota_us / cfs_period_us); 0 when none or unreadable.
int CgroupCpus() {
  double quota = -1, period = 0;
  std::ifstream v2("/sys/fs/cgroup/cpu.max");
  std::string q;
  if (v2 >> q >> period) {
    if (q == "max") return 0;
    quota = std::atof(q.c_str());
  } else {
    std::ifstream a("/sys/fs/cgroup/cpu/cpu.cfs_quota_us"), b("/sys/fs/cgroup/cpu/cpu.cfs_period_us");
    if (!(a >> quota && b >> period)) return 0;
  }
  if (quota <= 0 || period <= 0) return 0;
  return std::max(1, static_cast<int>(std::ceil(quota / period)));
}

}  // namespace

int AvailableCpus() {
  static const int cpus = [] {
    int n = 0;
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0) n = CPU_COUNT(&set);
    if (n <= 0) n = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const int quota = CgroupCpus();
    return quota > 0 ? std::min(n, quota) : n;
  }();
  return cpus;
}

void SetNumThreads(int n) {
  if (n < 0) throw InputError("num_threads = " + std::to_string(n) + ": must be >= 1 (0 for the default)");
  g_num_threads.store(n);
}

ScopedSerialThread::ScopedSerialThread() : was_serial_(t_serial) { t_serial = true; }
ScopedSerialThread::~ScopedSerialThread() { t_serial = was_serial_; }

int NumThreads() {
  if (t_serial) return 1;
  if (const int n = g_num_threads.load(); n > 0) return n;
  if (const char* env = std::getenv("ZWIDTH_NUM_THREADS"); env && *env) {
    char* end = nullptr;
    errno = 0;
    const long n = std::strtol(env, &end, 10);
    if (*end != '\0' || errno != 0 || n < 1 || n > 4096) {
      throw InputError(std::string("ZWIDTH_NUM_THREADS = '") + env +
                       "': expected a whole number of threads from 1 to 4096 (unset it for the cores available)");
    }
    return static_cast<int>(n);
  }
  return AvailableCpus();
}

}  // namespace zwidth
