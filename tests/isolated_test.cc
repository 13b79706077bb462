// io/isolated.h: the reader child's isolation (dies with its parent, runs
// under CPU and address-space limits, a killed child is an input error) and
// RunProgram without a shell. Moved from io_safety_test.cc.
#include <cerrno>
#include <chrono>
#include <climits>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "io/isolated.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {
namespace fs = std::filesystem;
using test::TempDir;

TEST(RunProgram, NoShellInterpretsTheFolderNameOrTheArguments) {
  TempDir dir("zwidth_isolated_test_");
  const std::string evil = dir / "it's $(touch pwned) `touch pwned2`; touch pwned3 '";
  fs::create_directory(evil);
  EXPECT_EQ(RunProgram({"touch", "made", "$(touch pwned4)"}, evil, evil + "/err.log"), 0);
  EXPECT_TRUE(fs::exists(evil + "/made"));
  EXPECT_TRUE(fs::exists(evil + "/$(touch pwned4)"));  // an argument, literally
  for (const auto& e : fs::recursive_directory_iterator(dir.path())) {
    EXPECT_NE(e.path().filename().string().rfind("pwned", 0), 0u) << e.path();
  }
  EXPECT_EQ(RunProgram({"zwidth-no-such-program"}, "", ""), 127);
  EXPECT_EQ(RunProgram({"false"}, "", ""), 1);
}

TEST(Isolated, TheReaderChildDiesWithItsParent) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t middle = ::fork();
  ASSERT_GE(middle, 0);
  if (middle == 0) {
    ::close(fds[0]);
    RunIsolated(
        "blocked.h5",
        [&](const FrameSender&) {
          const pid_t me = ::getpid();
          ::write(fds[1], &me, sizeof me);
          ::sleep(60);  // a reader blocked (a FIFO in an external link, say)
        },
        [](std::string_view) {});
    ::_exit(0);
  }
  ::close(fds[1]);
  pid_t child = 0;
  ASSERT_EQ(::read(fds[0], &child, sizeof child), static_cast<ssize_t>(sizeof child));
  ::close(fds[0]);
  ::kill(middle, SIGKILL);
  ::waitpid(middle, nullptr, 0);
  bool gone = false;
  for (int i = 0; i < 100 && !gone; ++i) {
    std::ifstream stat("/proc/" + std::to_string(child) + "/stat");
    std::string pid, comm, state;
    gone = !(stat >> pid >> comm >> state) || state == "Z";
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_TRUE(gone) << "reader child " << child << " outlived its parent";
}

TEST(Isolated, TheReaderChildRunsUnderCpuAndAddressSpaceLimits) {
  rlimit limits[2] = {};
  RunIsolated(
      "limits.h5",
      [](const FrameSender& send) {
        rlimit l[2];
        ::getrlimit(RLIMIT_CPU, &l[0]);
        ::getrlimit(RLIMIT_AS, &l[1]);
        send(l, sizeof l);
      },
      [&](std::string_view frame) {
        ASSERT_EQ(frame.size(), sizeof limits);
        std::memcpy(limits, frame.data(), sizeof limits);
      });
  EXPECT_EQ(limits[0].rlim_cur, static_cast<rlim_t>(kChildCpuSeconds));
  if (!SanitizedBuild()) EXPECT_EQ(limits[1].rlim_cur, static_cast<rlim_t>(kChildAddressSpaceBytes));
  rlimit mine;
  ::getrlimit(RLIMIT_CPU, &mine);
  EXPECT_NE(mine.rlim_cur, static_cast<rlim_t>(kChildCpuSeconds));  // the parent is not limited
}

TEST(Isolated, AKilledChildIsAnInputErrorNamingTheFile) {
  try {
    RunIsolated("corrupt.h5", [](const FrameSender&) { ::raise(SIGKILL); }, [](std::string_view) {});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt.h5"), std::string::npos) << e.what();
  }
}

TEST(Isolated, AChildsSanitizerExitCodeIsACrashInSanitizerBuilds) {
  // ASan/UBSan end a process that they report on with exit code 1 (or the
  // ASAN_OPTIONS exitcode): in a sanitizer build that must not pass as an
  // ordinary refusal, so the parent aborts and the fuzzer or test sees a crash.
  auto run = [] {
    RunIsolated("report.h5", [](const FrameSender&) { ::_exit(86); }, [](std::string_view) {});
  };
  if (SanitizedBuild()) {
    EXPECT_DEATH(run(), "sanitizer report");
  } else {
    EXPECT_THROW(run(), InputError);
  }
}

}  // namespace
}  // namespace zwidth::io
