// Live metrics of one process, in the Prometheus text exposition format 0.0.4
// (core/metrics_http.hpp serves them over HTTP at /metrics).
//
// A Registry holds counters and gauges registered once at start-up with a name, a help line and
// constant labels; the references it returns stay valid for the registry's lifetime.
//   - Updating (Counter::add/set, Gauge::set/add) is one relaxed atomic operation: no lock, no
//     allocation, safe from any thread, so hot paths (env steps, inserts, updates) may do it.
//   - render() takes the registry's lock, runs the collect hooks (which copy values kept
//     elsewhere into metrics) and formats the text; it allocates and runs on the HTTP thread.
//   - Registration takes the same lock; it allocates and is meant for start-up. Misuse (a bad
//     name, the same name and labels twice, a counter not named *_total, one name registered
//     both as a counter and as a gauge) throws std::invalid_argument.
// Names carry their unit (_seconds_total, _transitions, _ratio); see docs/architecture.md for
// the list every role exposes.
//
// parse_exposition() reads the same format back (pamdp monitor, tests).
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pamdp::metrics {

using Labels = std::vector<std::pair<std::string, std::string>>;

// A count that only goes up (events, transitions, seconds spent).
class Counter {
 public:
  void add(int64_t n = 1) { value_.fetch_add(n, std::memory_order_relaxed); }
  // Mirrors a running total kept elsewhere (it must not decrease).
  void set(int64_t total) { value_.store(total, std::memory_order_relaxed); }
  [[nodiscard]] int64_t value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<int64_t> value_{0};
};

// A value that goes up and down (sizes, rates, losses).
class Gauge {
 public:
  void set(double v) { value_.store(v, std::memory_order_relaxed); }
  void add(double d) { value_.fetch_add(d, std::memory_order_relaxed); }
  [[nodiscard]] double value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};
static_assert(std::atomic<double>::is_always_lock_free && std::atomic<int64_t>::is_always_lock_free);

class Registry {
 public:
  Registry() = default;
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  Counter& counter(const std::string& name, const std::string& help, const Labels& labels = {});
  Gauge& gauge(const std::string& name, const std::string& help, const Labels& labels = {});
  // Runs on the rendering thread before every render, under the registry's lock (so it must not
  // call back into the registry). For values another object keeps in its own atomics.
  void on_collect(std::function<void()> hook);

  // The text exposition of every metric, families in registration order.
  [[nodiscard]] std::string render() const;

 private:
  enum class Kind { kCounter, kGauge };
  struct Family {
    std::string name;
    std::string help;
    Kind kind;
  };
  struct Series {
    size_t family;
    std::string labels;  // rendered: {a="x",b="y"} or empty
    Counter* counter = nullptr;
    Gauge* gauge = nullptr;
  };
  size_t family(const std::string& name, const std::string& help, Kind kind);
  std::string add_series(size_t family, const Labels& labels);

  mutable std::mutex mutex_;
  std::vector<Family> families_;
  std::vector<Series> series_;
  std::deque<Counter> counters_;  // deques: references stay valid as they grow
  std::deque<Gauge> gauges_;
  std::vector<std::function<void()>> hooks_;
};

// One sample line of a text exposition.
struct Sample {
  std::string name;
  Labels labels;
  double value = 0.0;
  [[nodiscard]] const std::string* label(std::string_view key) const;
};

// Parses a text exposition (format 0.0.4): comments are skipped, timestamps ignored. Lines that
// do not parse are skipped and counted in *bad_lines when given.
std::vector<Sample> parse_exposition(std::string_view text, int* bad_lines = nullptr);

// The same float formatting the exposition uses (integers without a fraction, NaN, +Inf, -Inf).
std::string format_value(double v);

}  // namespace pamdp::metrics
