#include "replay/rate_limiter.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pamdp {
namespace {

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "RateLimiter: %s\n", what);
  std::abort();
}

}  // namespace

RateLimiter::RateLimiter(const RateLimiterConfig& config) : config_(config) {
  if (!(config.samples_per_insert > 0.0) || !std::isfinite(config.samples_per_insert)) {
    misuse("samples_per_insert must be a finite number > 0");
  }
  if (config.min_size < 0 || config.slack < 0) {
    misuse("min_size and slack must be >= 0");
  }
}

// Doubles, as in Reverb: spi is fractional in general, and counts stay far below 2^53.
bool RateLimiter::can_insert(int64_t n) const {
  if (n < 1) {
    misuse("can_insert needs n >= 1");
  }
  if (inserts_ < config_.min_size) {
    return true;
  }
  const double spi = config_.samples_per_insert;
  return spi * static_cast<double>(inserts_ - config_.min_size) <=
         static_cast<double>(samples_) + static_cast<double>(config_.slack) * spi;
}

bool RateLimiter::can_sample(int64_t n) const {
  if (n < 1) {
    misuse("can_sample needs n >= 1");
  }
  if (inserts_ < config_.min_size) {
    return false;
  }
  const double spi = config_.samples_per_insert;
  return static_cast<double>(samples_ + n) <=
         spi * static_cast<double>(inserts_ - config_.min_size) + static_cast<double>(config_.slack) * spi;
}

void RateLimiter::on_insert(int64_t n) {
  if (n < 1) {
    misuse("on_insert needs n >= 1");
  }
  inserts_ += n;
}

void RateLimiter::on_sample(int64_t n) {
  if (n < 1) {
    misuse("on_sample needs n >= 1");
  }
  samples_ += n;
}

void RateLimiter::set_counters(int64_t inserts, int64_t samples) {
  if (inserts < 0 || samples < 0) {
    misuse("set_counters needs counters >= 0");
  }
  inserts_ = inserts;
  samples_ = samples;
}

}  // namespace pamdp
