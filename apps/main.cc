// zwidth: from a haptic device's logs to a validated model and its Z-width.
// Exit codes: 0 success; 2 bad request or bad file (nothing written);
// 1 a computation that failed (e.g. a fit that did not converge); 3, 4 from
// ExitStatus (check, batch); the full list is apps/help.cc kExitStatusText.
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "apps/common.h"
#include "apps/help.h"
#include "build_info.h"
#include "io/atomic_file.h"
#include "io/printable.h"
#include "model/error.h"

namespace {

// Results printed on standard output must have arrived: a full disk or a
// closed file behind stdout (> /dev/full) is an error (exit 2), not success.
int CheckStdout(int code) {
  std::cout.flush();
  errno = 0;
  const bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout);
  if (!failed) return code;
  std::fprintf(stderr, "zwidth: error: writing the results to standard output failed (%s): the output is "
               "incomplete; free space or write to a file with -o\n", errno ? std::strerror(errno) : "write error");
  return code == 0 ? 2 : code;
}

}  // namespace

int main(int argc, char** argv) {
  // A signal that ends the command removes its temporary files first.
  zwidth::io::InstallCleanupSignalHandlers();
  // One OpenBLAS thread, whatever the environment says: the fit's matrices are
  // small (tens of parameters), so a pool buys nothing, and each pool thread
  // starts by reserving its own 128 MiB buffer. Under `ulimit -v 150000` that
  // mmap() fails and OpenBLAS 0.3.21 retries it for ever; at exit, its library
  // destructor (blas_thread_shutdown_) joins that thread, so `fit` wrote its
  // output and never exited (gdb backtrace, OPENBLAS_NUM_THREADS=8). Set before
  // any BLAS is mapped: the fit plugin that brings it is dlopen()ed later.
  ::setenv("OPENBLAS_NUM_THREADS", "1", 1);
  CLI::App app{"zwidth: haptic device identification and Z-width (stable K, B) analysis"};
  app.require_subcommand(1);
  zwidth::app::SetCommandLine(argc, argv);
  namespace bi = zwidth::build_info;
  app.set_version_flag("--version", std::string("zwidth ") + bi::kVersion + "\nbuilt with Ceres " + bi::kCeres +
                                        ", Eigen " + bi::kEigen + ", FFTW " + bi::kFftw + ", HDF5 " + bi::kHdf5 +
                                        ", CLI11 " + bi::kCli11 + ", nlohmann-json " + bi::kNlohmannJson);
  zwidth::app::AddSimulateCommand(app);
  zwidth::app::AddEstimateCommand(app);
  zwidth::app::AddFitCommands(app);
  zwidth::app::AddStabilityCommands(app);
  zwidth::app::AddExportCommand(app);
  zwidth::app::AddRunCommand(app);
  zwidth::app::AddBatchCommand(app);
  zwidth::app::AddExciteCommand(app);
  zwidth::app::AddValidateCommand(app);
  zwidth::app::AddWallCommand(app);
  zwidth::app::GuardNumericFlags(&app);
  zwidth::app::OrganizeHelp(app);  // after every command: topics, examples, --help-all, completion
  // CLI11's own messages quote what was typed ("Could not convert: --b-points = ...",
  // "The following argument was not expected: ..."): escaped like every other message,
  // so an ESC or a newline typed in an argument is shown, not obeyed.
  app.failure_message([](const CLI::App* a, const CLI::Error& e) {
    return zwidth::io::PrintableLines(CLI::FailureMessage::simple(a, e));
  });
  try {
    zwidth::app::CheckListFlags(app, argc, argv);
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const zwidth::app::ExitStatus& e) {
    return CheckStdout(e.code);
  } catch (const zwidth::InputError& e) {
    std::fprintf(stderr, "zwidth: error: %s\n", zwidth::io::Printable(zwidth::app::WithFlags(e.what())).c_str());
    return 2;
  } catch (const zwidth::ComputationError& e) {
    std::fprintf(stderr, "zwidth: computation failed: %s\n", zwidth::io::Printable(zwidth::app::WithFlags(e.what())).c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "zwidth: internal error: %s\n", zwidth::io::Printable(e.what()).c_str());
    return 1;
  }
  return CheckStdout(0);
}
