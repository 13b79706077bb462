// Registration of commands whose modules have not landed yet.
#include "apps/common.h"
namespace zwidth::app {
void AddExportCommand(CLI::App&) {}
}  // namespace zwidth::app
