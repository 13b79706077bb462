// Issue 11: what zwidth may read and where it may write (io/atomic_file.h),
// the reader child's isolation (io/isolated.h), and the readers' shape, depth
// and range checks. Hostile files are written by the tests, in a temporary
// folder; tests/hostile_test.sh checks the same from the command line.
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstring>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <hdf5.h>

#include "io/atomic_file.h"
#include "io/frf_file.h"
#include "io/isolated.h"
#include "io/log.h"
#include "io/model_json.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {
namespace fs = std::filesystem;

using test::ReadFile;
using test::TempDir;
using test::WriteFile;

// Names in the folder holding ".tmp-" (leftover temporaries).
int Leftovers(const TempDir& dir) {
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir.path())) n += e.path().filename().string().find(".tmp-") != std::string::npos;
  return n;
}

TEST(AtomicFile, RefusesDevicesFifosAndFoldersAndLeavesThemAlone) {
  TempDir dir("zwidth_safety_");
  std::vector<std::string> hostile = {"/dev/null", "/dev/full", dir / "fifo", dir / "folder", dir / "link_to_fifo"};
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_directory(dir / "folder");
  fs::create_symlink(dir / "fifo", dir / "link_to_fifo");
  if (::mknod((dir / "chardev").c_str(), S_IFCHR | 0600, makedev(1, 3)) == 0) hostile.push_back(dir / "chardev");
  for (const std::string& p : hostile) {
    SCOPED_TRACE(p);
    EXPECT_THROW(CheckOutputPath(p), InputError);
    EXPECT_THROW(WriteTextAtomically(p, "x"), InputError);
  }
  struct stat st;
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  ASSERT_EQ(::lstat((dir / "fifo").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  ASSERT_EQ(::lstat((dir / "link_to_fifo").c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode));
  EXPECT_EQ(Leftovers(dir), 0);
}

TEST(AtomicFile, RefusesAnInputByInodeThroughHardAndSymbolicLinks) {
  TempDir dir("zwidth_safety_");
  WriteFile(dir / "log.csv", "precious");
  fs::create_hard_link(dir / "log.csv", dir / "hard.csv");
  fs::create_symlink(dir / "log.csv", dir / "soft.csv");
  EXPECT_THROW(CheckOutputPath(dir / "hard.csv", {dir / "log.csv"}), InputError);
  CheckInputFile(dir / "log.csv", "log");  // noted as an input of this process
  for (const char* name : {"log.csv", "hard.csv", "soft.csv"}) {
    SCOPED_TRACE(name);
    EXPECT_THROW(WriteTextAtomically(dir / name, "replaced"), InputError);
  }
  EXPECT_EQ(ReadFile(dir / "log.csv"), "precious");
  EXPECT_EQ(Leftovers(dir), 0);
}

TEST(AtomicFile, FollowsASymlinkToARegularFileAndKeepsTheLink) {
  TempDir dir("zwidth_safety_");
  WriteFile(dir / "target.txt", "old");
  fs::create_symlink(dir / "target.txt", dir / "link.txt");
  WriteTextAtomically(dir / "link.txt", "new");
  EXPECT_TRUE(fs::is_symlink(dir / "link.txt"));
  EXPECT_EQ(ReadFile(dir / "target.txt"), "new");
}

TEST(AtomicFile, AFailingWriterLeavesTheOldFileAndNoTemporary) {
  TempDir dir("zwidth_safety_");
  WriteFile(dir / "out.csv", "old");
  EXPECT_THROW(WriteAtomically(dir / "out.csv", [](const std::string& tmp) {
                 WriteFile(tmp, "half");
                 throw InputError("disk full");
               }),
               InputError);
  EXPECT_EQ(ReadFile(dir / "out.csv"), "old");
  EXPECT_EQ(Leftovers(dir), 0);
}

TEST(AtomicFile, SigtermRemovesRegisteredFilesAndFoldersThenKills) {
  TempDir dir("zwidth_safety_");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    OutputFolder* folder = new OutputFolder(dir / "run", false);  // never destroyed: the signal ends us
    fs::create_directories(fs::path(folder->temp_path()) / "figures");
    WriteFile(folder->temp_path() + "/model.json", "{}");
    WriteFile(folder->temp_path() + "/figures/bode.svg", "<svg/>");
    WriteAtomically(dir / "big.csv", [](const std::string& tmp) {
      WriteFile(tmp, std::string(1 << 20, 'x'));
      ::raise(SIGTERM);
    });
    ::_exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_TRUE(fs::is_empty(dir.path())) << "left: " << fs::directory_iterator(dir.path())->path();
}

TEST(OutputFolder, AppearsWholeOnCommitAndNotAtAllOnFailure) {
  TempDir dir("zwidth_safety_");
  {
    OutputFolder f(dir / "out", false);
    WriteFile(f.temp_path() + "/a.txt", "a");
    EXPECT_FALSE(fs::exists(dir / "out"));
  }  // not committed: a failure
  EXPECT_TRUE(fs::is_empty(dir.path()));
  {
    OutputFolder f(dir / "out", false);
    WriteFile(f.temp_path() + "/a.txt", "a");
    f.Commit();
  }
  EXPECT_EQ(ReadFile(dir / "out/a.txt"), "a");
  {
    OutputFolder f(dir / "slash/", false);  // a trailing slash names the same folder
    WriteFile(f.temp_path() + "/b.txt", "b");
    f.Commit();
  }
  EXPECT_EQ(ReadFile(dir / "slash/b.txt"), "b");
  EXPECT_THROW(OutputFolder(dir / "out", false), InputError);  // not empty
  WriteFile(dir / "plain", "x");
  EXPECT_THROW(OutputFolder(dir / "plain", false), InputError);  // not a folder
  EXPECT_THROW(OutputFolder(dir / "no/such/parent", false), InputError);
}

TEST(OutputFolder, TwoRunsIntoOneFolderCannotMix) {
  TempDir dir("zwidth_safety_");
  OutputFolder first(dir / "out", false), second(dir / "out", false);
  WriteFile(first.temp_path() + "/model.json", "first");
  WriteFile(first.temp_path() + "/report.html", "first");
  WriteFile(second.temp_path() + "/model.json", "second");
  WriteFile(second.temp_path() + "/report.html", "second");
  first.Commit();
  EXPECT_THROW(second.Commit(), InputError);
  EXPECT_EQ(ReadFile(dir / "out/model.json"), "first");
  EXPECT_EQ(ReadFile(dir / "out/report.html"), "first");
}

TEST(OutputFolder, ForceReplacesItsFilesAndKeepsTheOthers) {
  TempDir dir("zwidth_safety_");
  fs::create_directory(dir / "out");
  WriteFile(dir / "out/notes.txt", "mine");
  WriteFile(dir / "out/model.json", "old");
  {
    OutputFolder f(dir / "out", true);
    WriteFile(f.temp_path() + "/model.json", "new");
    f.Commit();
  }
  EXPECT_EQ(ReadFile(dir / "out/notes.txt"), "mine");
  EXPECT_EQ(ReadFile(dir / "out/model.json"), "new");
  EXPECT_EQ(Leftovers(dir), 0);
}

TEST(RunProgram, NoShellInterpretsTheFolderNameOrTheArguments) {
  TempDir dir("zwidth_safety_");
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

// An HDF5 log whose sample_rate_hz attribute holds `n` values.
void WriteLogWithArrayRate(const std::string& path, hsize_t n) {
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t len = 4096;
  std::vector<double> u(len), y(len);
  for (hsize_t k = 0; k < len; ++k) { u[k] = std::sin(0.1 * k * k); y[k] = std::cos(0.03 * k); }
  const hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  const hid_t space = H5Screate_simple(1, &len, nullptr);
  for (auto [name, data] : {std::pair{"/input/torque", &u}, std::pair{"/output/position", &y}}) {
    const hid_t d = H5Dcreate2(f, name, H5T_IEEE_F64LE, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data->data());
    H5Dclose(d);
  }
  const hid_t aspace = H5Screate_simple(1, &n, nullptr);
  const hid_t a = H5Acreate2(f, "sample_rate_hz", H5T_IEEE_F64LE, aspace, H5P_DEFAULT, H5P_DEFAULT);
  std::vector<double> rates(n, 1000.0);
  H5Awrite(a, H5T_NATIVE_DOUBLE, rates.data());
  H5Aclose(a);
  H5Sclose(aspace);
  H5Sclose(space);
  H5Pclose(lcpl);
  H5Fclose(f);
}

TEST(Hdf5Log, AnArrayAttributeIsRefusedInTheChildAndInProcess) {
  TempDir dir("zwidth_safety_");
  for (hsize_t n : {2, 1000}) {
    SCOPED_TRACE(n);
    WriteLogWithArrayRate(dir / "log.h5", n);
    const std::string expect = "attribute sample_rate_hz has " + std::to_string(n) + " values";
    try {
      ReadLog(dir / "log.h5");
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
    EXPECT_THROW(internal::StreamHdf5InProcess(dir / "log.h5", {}, [](const double*, const double*, size_t) {}),
                 InputError);
  }
  WriteLogWithArrayRate(dir / "log.h5", 1);  // one value: a scalar in all but name
  EXPECT_EQ(ReadLog(dir / "log.h5").info.sample_rate_hz, 1000.0);
}

TEST(FrfCsv, ADuplicatedColumnIsRefusedNotReadPastItsRow) {
  TempDir dir("zwidth_safety_");
  std::string text = "f_hz,H_re,H_im,coherence,coherence,coherence,coherence\n";
  // Four distinct names, so the old reader let rows of four fields through and
  // read "coherence" at position 6: past the row's buffer.
  for (int k = 1; k <= 20; ++k) text += std::to_string(k) + ",1,0,1\n";
  WriteFile(dir / "frf.csv", text);
  try {
    ReadFrequencyResponse(dir / "frf.csv", 1000.0);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("column 'coherence' appears twice"), std::string::npos) << e.what();
  }
}

std::string Nested(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

TEST(ModelJson, NestingIsBoundedBeforeParsing) {
  const std::string head = R"({"m": 1e-3, "b": 5e-3, "modes": [], "fit": )";
  // "fit" sits at depth 1, so its value may nest kMaxJsonDepth - 1 levels.
  EXPECT_NO_THROW(ParseModelJson(head + Nested(kMaxJsonDepth - 1) + "}", "ok.json"));
  EXPECT_THROW(ParseModelJson(head + Nested(kMaxJsonDepth) + "}", "deep.json"), InputError);
  EXPECT_THROW(ParseModelJson(Nested(100000), "deep.json"), InputError);
  // Brackets inside strings are text, not nesting.
  EXPECT_NO_THROW(ParseModelJson(R"({"m": 1e-3, "b": 5e-3, "modes": [], "name": ")" + std::string(1000, '[') +
                                     R"(\"]"})", "name.json"));
}

TEST(ModelJson, DelaysAndParametersOutsideTheirRangesAreRefused) {
  const std::string head = R"({"m": 1e-3, "b": 5e-3, "modes": [], "delay_samples": )";
  for (const char* d : {"4294967298", "2147483647", "18446744073709551615", "-1", "1001"}) {
    SCOPED_TRACE(d);
    EXPECT_THROW(ParseModelJson(head + d + "}", "model.json"), InputError);
  }
  EXPECT_EQ(ParseModelJson(head + "1000}", "model.json").plant.delay_samples, 1000);
  EXPECT_THROW(ParseModelJson(R"({"m": 1e-300, "b": 5e-3, "modes": []})", "model.json"), InputError);
  EXPECT_THROW(ParseModelJson(R"({"m": 1e-3, "b": 5e300, "modes": []})", "model.json"), InputError);
  std::string modes;
  for (size_t i = 0; i <= kMaxModes; ++i) modes += std::string(i ? "," : "") + R"({"omega": 400, "c": 80, "v": 380, "d": 70})";
  EXPECT_THROW(ParseModelJson(R"({"m": 1e-3, "b": 5e-3, "modes": [)" + modes + "]}", "model.json"), InputError);
}

TEST(ModelJson, AModelFileMustBeARegularFile) {
  EXPECT_THROW(ReadModelJson("/dev/zero"), InputError);
  TempDir dir("zwidth_safety_");
  ASSERT_EQ(::mkfifo((dir / "model.json").c_str(), 0600), 0);
  EXPECT_THROW(ReadModelJson(dir / "model.json"), InputError);  // refused at once, never opened
}

}  // namespace
}  // namespace zwidth::io
