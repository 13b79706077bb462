// zwidth: from a haptic device's logs to a validated model and its Z-width.
// Exit codes: 0 success; 2 bad request or bad file (nothing written);
// 1 a computation that failed (e.g. a fit that did not converge).
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "apps/common.h"
#include "apps/help.h"
#include "build_info.h"
#include "model/error.h"

int main(int argc, char** argv) {
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
  zwidth::app::AddExciteCommand(app);
  zwidth::app::AddValidateCommand(app);
  zwidth::app::OrganizeHelp(app);  // after every command: topics, examples, --help-all, completion
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const zwidth::InputError& e) {
    std::fprintf(stderr, "zwidth: error: %s\n", zwidth::app::WithFlags(e.what()).c_str());
    return 2;
  } catch (const zwidth::ComputationError& e) {
    std::fprintf(stderr, "zwidth: computation failed: %s\n", zwidth::app::WithFlags(e.what()).c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "zwidth: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
