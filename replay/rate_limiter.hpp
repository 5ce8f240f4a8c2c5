// How fast a replay shard lets the learner sample relative to what actors insert: Reverb's
// SampleToInsertRatio, with the formulas of docs/protocol.md (spi = samples per insert):
//
//   sample of n allowed  when  inserts >= min_size  and
//                              samples + n <= spi * (inserts - min_size) + slack * spi
//   insert allowed       when  inserts < min_size  or
//                              spi * (inserts - min_size) <= samples + slack * spi
//
// The insert test looks at the state before a batch and admits the whole batch, so inserts
// can run ahead by at most one batch past the slack. The `inserts >= min_size` gate on
// sampling is the warm-up (replay.warmup): without it a large slack would allow sampling
// before the shard holds min_size transitions.
//
// Progress: while inserts are held back, samples of up to 2 * slack * spi are allowed, so a
// sampler whose requests are no larger than that never deadlocks with a blocked inserter.
//
// Not thread-safe (the shard's one thread owns it). Every call is O(1) and allocates nothing.
// Misuse (n < 1, a bad config) stops the process; recording an operation the limiter did not
// allow is not checked here (the shard checks before it inserts or samples).
#pragma once

#include <cstdint>

namespace pamdp {

struct RateLimiterConfig {
  double samples_per_insert = 32.0;  // spi > 0
  int64_t min_size = 1;              // inserts before the first sample (>= 0)
  int64_t slack = 2000;              // in inserts: allowed drift from the ratio (>= 0)
  bool operator==(const RateLimiterConfig&) const = default;
};

class RateLimiter {
 public:
  // Checks the config (spi > 0 and finite, min_size >= 0, slack >= 0); misuse aborts.
  explicit RateLimiter(const RateLimiterConfig& config);

  [[nodiscard]] bool can_insert(int64_t n) const;
  [[nodiscard]] bool can_sample(int64_t n) const;
  void on_insert(int64_t n);
  void on_sample(int64_t n);

  [[nodiscard]] int64_t inserts() const { return inserts_; }
  [[nodiscard]] int64_t samples() const { return samples_; }
  [[nodiscard]] const RateLimiterConfig& config() const { return config_; }
  // Restores counters (a shard resuming from a snapshot). Both must be >= 0.
  void set_counters(int64_t inserts, int64_t samples);

 private:
  RateLimiterConfig config_;
  int64_t inserts_ = 0;
  int64_t samples_ = 0;
};

}  // namespace pamdp
