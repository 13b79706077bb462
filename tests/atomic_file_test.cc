// Issue 11: where zwidth may write (io/atomic_file.h: atomic files, output
// folders). Hostile files are written by the tests, in a temporary folder;
// tests/hostile_test.sh checks the same from the command line. The reader
// child's isolation is in isolated_test.cc, the readers' checks in log_test.cc,
// frf_file_test.cc and model_json_test.cc.
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

#include "io/atomic_file.h"
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
    InstallCleanupSignalHandlers();  // as the zwidth command does
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

// Issue 30: a closed pipe (`-o - | head`) and a file size limit (`ulimit -f`)
// end the process too; the handler removes the temporaries first.
class CleanupSignal : public ::testing::TestWithParam<int> {};

TEST_P(CleanupSignal, RemovesTheTemporaryFileThenDiesOfTheSignal) {
  TempDir dir("zwidth_safety_");
  const int sig = GetParam();
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    InstallCleanupSignalHandlers();
    WriteAtomically(dir / "big.csv", [sig](const std::string& tmp) {
      WriteFile(tmp, std::string(1 << 16, 'x'));
      ::raise(sig);
    });
    ::_exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), sig);
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

INSTANTIATE_TEST_SUITE_P(AtomicFile, CleanupSignal, ::testing::Values(SIGPIPE, SIGXFSZ),
                         [](const ::testing::TestParamInfo<int>& i) { return i.param == SIGPIPE ? "Sigpipe" : "Sigxfsz"; });

// A library never replaces its host's handlers (Python's SIGINT ->
// KeyboardInterrupt was replaced by the first save()).
TEST(AtomicFile, WritingLeavesTheHostsSignalHandlersAlone) {
  TempDir dir("zwidth_safety_");
  struct sigaction mine = {}, before = {}, after = {};
  mine.sa_handler = [](int) {};
  sigemptyset(&mine.sa_mask);
  ASSERT_EQ(::sigaction(SIGINT, &mine, &before), 0);
  WriteTextAtomically(dir / "a.txt", "a");
  OutputFolder(dir / "out", false).Commit();
  ASSERT_EQ(::sigaction(SIGINT, &before, &after), 0);
  EXPECT_EQ(after.sa_handler, mine.sa_handler);
}

TEST(AtomicFile, OverwritingKeepsTheFilesPermissionBits) {
  TempDir dir("zwidth_safety_");
  WriteFile(dir / "secret.csv", "old");
  ASSERT_EQ(::chmod((dir / "secret.csv").c_str(), 0600), 0);
  WriteTextAtomically(dir / "secret.csv", "new");
  struct stat st;
  ASSERT_EQ(::stat((dir / "secret.csv").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  EXPECT_EQ(ReadFile(dir / "secret.csv"), "new");
}

// After SIGKILL a run's hidden temporary folder stays; the next run for the
// same output removes it, but never a live run's nor a folder zwidth did not
// make (no lock file in it).
TEST(OutputFolder, TheNextRunRemovesAKilledRunsFolderOnly) {
  TempDir dir("zwidth_safety_");
  auto child = [&](bool wait_forever) {
    int ready[2];
    EXPECT_EQ(::pipe(ready), 0);
    const pid_t pid = ::fork();
    if (pid == 0) {
      OutputFolder* f = new OutputFolder(dir / "out", false);  // never destroyed
      WriteFile(f->temp_path() + "/model.json", "{}");
      (void)!::write(ready[1], "x", 1);
      if (wait_forever) ::pause();
      ::raise(SIGKILL);
    }
    char c;
    EXPECT_EQ(::read(ready[0], &c, 1), 1);
    ::close(ready[0]);
    ::close(ready[1]);
    return pid;
  };
  int status = 0;
  const pid_t live = child(true);
  const pid_t killed = child(false);
  ASSERT_EQ(::waitpid(killed, &status, 0), killed);
  fs::create_directory(dir / ".out.tmp-Abc123");  // not zwidth's: no lock file
  auto temps = [&] {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir.path())) n += e.path().filename().string().rfind(".out.tmp-", 0) == 0;
    return n;
  };
  ASSERT_EQ(temps(), 3);
  {
    OutputFolder f(dir / "out", false);
    EXPECT_EQ(temps(), 3);  // the killed run's went, this one's came
    f.Commit();
  }
  EXPECT_EQ(temps(), 2);  // the live run's and the foreign one
  EXPECT_TRUE(fs::exists(dir / ".out.tmp-Abc123"));
  EXPECT_FALSE(fs::exists(dir / "out/.zwidth-run.lock"));
  ::kill(live, SIGKILL);
  ASSERT_EQ(::waitpid(live, &status, 0), live);
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

}  // namespace
}  // namespace zwidth::io
