#include "app/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace pamdp::app {

ProgressBar::ProgressBar(std::string unit, int64_t total, bool enabled)
    : unit_(std::move(unit)),
      total_(total),
      active_(enabled && total > 0 && isatty(fileno(stderr)) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_ - std::chrono::seconds(1)) {}

ProgressBar::~ProgressBar() {
  if (drawn_) {
    finish();
  }
}

std::string ProgressBar::format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) {
    return "?";
  }
  const auto s = static_cast<long long>(seconds + 0.5);
  char text[32];
  if (s >= 3600) {
    std::snprintf(text, sizeof(text), "%lldh%02lldm", s / 3600, (s % 3600) / 60);
  } else if (s >= 60) {
    std::snprintf(text, sizeof(text), "%lldm%02llds", s / 60, s % 60);
  } else {
    std::snprintf(text, sizeof(text), "%llds", s);
  }
  return text;
}

void ProgressBar::update(int64_t done) {
  if (!active_) {
    return;
  }
  if (first_done_ < 0) {
    first_done_ = done;  // a resumed run starts part-way: its rate counts from here
  }
  last_done_ = done;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(200)) {
    return;
  }
  last_draw_ = now;
  draw(done);
}

void ProgressBar::draw(int64_t done) {
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = secs > 0.0 ? static_cast<double>(done - std::max<int64_t>(0, first_done_)) / secs : 0.0;
  const double frac = std::clamp(static_cast<double>(done) / static_cast<double>(total_), 0.0, 1.0);
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(frac * kWidth);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) {
    bar[i] = i < filled ? '#' : '-';
  }
  bar[kWidth] = '\0';
  const double eta = rate > 0.0 ? static_cast<double>(total_ - done) / rate : NAN;
  std::fprintf(stderr, "\r\033[2K[%s] %3.0f%% %lld/%lld %s | %.0f/s | %s elapsed | ETA %s", bar, frac * 100.0,
               static_cast<long long>(done), static_cast<long long>(total_), unit_.c_str(), rate,
               format_duration(secs).c_str(), done >= total_ ? "0s" : format_duration(eta).c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::clear() {
  if (drawn_) {
    std::fprintf(stderr, "\r\033[2K");
    std::fflush(stderr);
    last_draw_ = std::chrono::steady_clock::now() - std::chrono::seconds(1);  // redraw at the next update
  }
}

void ProgressBar::finish() {
  if (!active_) {
    return;
  }
  draw(last_done_);
  std::fprintf(stderr, "\n");
  std::fflush(stderr);
  drawn_ = false;
  active_ = false;
}

}  // namespace pamdp::app
