// Small pieces shared by the commands that run training (`train`, `learner`).
#pragma once

#include <ctime>
#include <string>

namespace pamdp::app {

// runs/<local time>-<label>, e.g. runs/20261121-120000-seed1.
inline std::string timestamped_run_dir(const std::string& label) {
  const std::time_t t = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", std::localtime(&t));
  return "runs/" + std::string(stamp) + "-" + label;
}

}  // namespace pamdp::app
