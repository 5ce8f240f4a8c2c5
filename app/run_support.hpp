// Small pieces shared by the commands that run training (`train`, `learner`).
#pragma once

#include <algorithm>
#include <cstdint>
#include <ctime>
#include <deque>
#include <string>

namespace pamdp::app {

// runs/<local time>-<label>, e.g. runs/20261121-120000-seed1.
inline std::string timestamped_run_dir(const std::string& label) {
  const std::time_t t = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", std::localtime(&t));
  return "runs/" + std::string(stamp) + "-" + label;
}

// The last 100 episodes, for progress lines and metrics rows. Averages are 0 when empty.
class RecentEpisodes {
 public:
  void add(double ret, int64_t steps, bool success) {
    window_.push_back({ret, steps, success});
    if (window_.size() > 100) {
      window_.pop_front();
    }
  }
  [[nodiscard]] size_t size() const { return window_.size(); }
  [[nodiscard]] double success_rate() const {
    return sum([](const Episode& e) { return e.success ? 1.0 : 0.0; });
  }
  [[nodiscard]] double mean_return() const {
    return sum([](const Episode& e) { return e.ret; });
  }
  [[nodiscard]] double mean_steps() const {
    return sum([](const Episode& e) { return static_cast<double>(e.steps); });
  }

 private:
  struct Episode {
    double ret;
    int64_t steps;
    bool success;
  };
  template <typename F>
  [[nodiscard]] double sum(F value) const {
    double total = 0.0;
    for (const Episode& e : window_) {
      total += value(e);
    }
    return total / std::max<double>(1.0, static_cast<double>(window_.size()));
  }
  std::deque<Episode> window_;
};

}  // namespace pamdp::app
