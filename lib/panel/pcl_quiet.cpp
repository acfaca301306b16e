#include "panel/pcl_quiet.h"

#include <mutex>

#include <pcl/console/print.h>

namespace depthbias::panel {

void QuietPcl() {
  static std::once_flag once;
  std::call_once(once, [] { pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); });
}

}  // namespace depthbias::panel
