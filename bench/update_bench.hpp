// What BM_DdpgUpdate and BM_DdpgUpdateCuda share: the random batch they update on
// (bench/random_batch.hpp) and the FLOP count of one update they report.
#pragma once

#include <benchmark/benchmark.h>

#include <vector>

#include "bench/random_batch.hpp"
#include "learner/ddpg.hpp"

namespace pamdp::bench {

// FLOP of one update: forward 2*MACs per sample; target actor, target critic, critic, actor and
// critic again forward; critic backward (params + input) ~2x forward, critic backward to inputs
// only ~1x, actor backward (params) ~1x (no input gradient).
inline double update_flop(Ddpg& ddpg, int batch) {
  auto macs = [](const std::vector<int>& w) {
    double m = 0;
    for (size_t i = 0; i + 1 < w.size(); ++i) {
      m += static_cast<double>(w[i]) * w[i + 1];
    }
    return m;
  };
  const double a = 2.0 * macs(ddpg.actor().widths()) * batch;
  const double c = 2.0 * macs(ddpg.critic().widths()) * batch;
  return (2 * a + 3 * c) + 2 * c + 1 * c + 1 * a;
}

// The counters both update benchmarks report next to items (updates) per second.
inline void report_update_flop(benchmark::State& state, Ddpg& ddpg, int batch) {
  const double flop = update_flop(ddpg, batch);
  state.counters["GFLOP_per_update"] = flop / 1e9;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flop * static_cast<double>(state.iterations()) / 1e9, benchmark::Counter::kIsRate);
}

}  // namespace pamdp::bench
