// Registration of commands whose modules have not landed yet.
#include "apps/common.h"
namespace zwidth::app {
}  // namespace zwidth::app
