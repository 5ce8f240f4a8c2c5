// A one-line progress bar for fixed-length work (`pamdp eval` episodes, `pamdp train` with an
// update budget): done/total, percent, rate and ETA, redrawn in place on stderr at most five
// times a second. It draws nothing when stderr is not a terminal (logs, CI, pipes) or when
// disabled, so scripted output stays clean.
//
// update() is cheap enough for every env step (one clock read; it formats only when it
// redraws). Not thread-safe.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace pamdp::app {

class ProgressBar {
 public:
  // `unit` names what is counted ("episodes", "updates").
  ProgressBar(std::string unit, int64_t total, bool enabled = true);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void update(int64_t done);
  // Erases the bar so a log line can be printed on the same terminal; the next update redraws.
  void clear();
  // Draws the final state and ends the line.
  void finish();

  [[nodiscard]] bool active() const { return active_; }
  // "1m05s", "2h10m": how ETAs are written.
  static std::string format_duration(double seconds);

 private:
  void draw(int64_t done);

  std::string unit_;
  int64_t total_;
  bool active_;
  bool drawn_ = false;
  int64_t first_done_ = -1;
  int64_t last_done_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace pamdp::app
