#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>

#include "report/report_internal.h"

namespace zwidth::report {

GnuplotProcess::GnuplotProcess(const std::filesystem::path& folder) {
  // Everything the child needs, made before fork (the child only calls
  // async-signal-safe functions, then exec).
  const std::string cwd = folder.string(), log = (folder / "gnuplot.log").string();
  char arg0[] = "gnuplot", arg1[] = "/dev/stdin";
  char* const argv[] = {arg0, arg1, nullptr};
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return;
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    return;
  }
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(3);  // the parent died before prctl
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) ::signal(sig, SIG_DFL);
    if (::chdir(cwd.c_str()) != 0 || ::dup2(fds[0], 0) < 0) ::_exit(127);
    const int err = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
    if (err >= 0) ::dup2(err, 2);
    ::execvp(argv[0], argv);
    ::_exit(127);
  }
  ::close(fds[0]);
  pid_ = pid;
  to_child_ = fds[1];
}

GnuplotProcess::~GnuplotProcess() {
  if (pid_ > 0) Wait();  // the script is empty: gnuplot ends at once
}

int GnuplotProcess::Wait() {
  if (to_child_ >= 0) ::close(to_child_);
  to_child_ = -1;
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0) {
    if (errno != EINTR) {
      pid_ = -1;
      return 127;
    }
  }
  pid_ = -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + WTERMSIG(status);
}

int GnuplotProcess::Run(const std::string& script) {
  if (pid_ <= 0) return 127;
  // A gnuplot that ended early (not installed: exit 127) closes the pipe; the
  // write then fails with EPIPE, and the SIGPIPE it raises is blocked here
  // and taken back, so that it never ends zwidth.
  sigset_t pipe_only, old;
  sigemptyset(&pipe_only);
  sigaddset(&pipe_only, SIGPIPE);
  ::pthread_sigmask(SIG_BLOCK, &pipe_only, &old);
  const char* p = script.data();
  size_t left = script.size();
  while (left > 0) {
    const ssize_t n = ::write(to_child_, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // EPIPE: gnuplot is gone; its exit status says why
    p += n;
    left -= static_cast<size_t>(n);
  }
  sigset_t pending;
  sigpending(&pending);
  if (sigismember(&pending, SIGPIPE)) {
    const timespec zero = {0, 0};
    ::sigtimedwait(&pipe_only, nullptr, &zero);
  }
  ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
  return Wait();
}

}  // namespace zwidth::report
