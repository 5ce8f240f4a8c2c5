// What BM_DdpgUpdate and BM_DdpgUpdateCuda share: the random batch they update on and the FLOP
// count of one update they report.
#pragma once

#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/rng.hpp"
#include "learner/ddpg.hpp"

namespace pamdp::bench {

// A random minibatch with HFO's widths (58 features, 4 scores + 6 parameters): states and
// scores in [-1, 1], parameters in [-100, 100], small rewards, no terminals. Owns its storage;
// view() is valid while it lives.
class RandomHfoBatch {
 public:
  static constexpr int kObs = 58;
  static constexpr int kWidth = 10;

  explicit RandomHfoBatch(int batch, uint64_t seed = 2) : batch_(batch), rng_(seed) {
    states_ = random(kObs, batch, -1.0F, 1.0F);
    next_states_ = random(kObs, batch, -1.0F, 1.0F);
    actions_ = random(kWidth, batch, -1.0F, 1.0F);
    actions_.bottomRows(6) *= 100.0F;
    rewards_ = random(batch, 1, -0.1F, 0.1F);
    terminal_ = Eigen::VectorXf::Zero(batch);
    returns_ = Eigen::VectorXf::Zero(batch);
  }

  [[nodiscard]] BatchView view() const {
    return BatchView{
        Eigen::Map<const Eigen::MatrixXf>(states_.data(), kObs, batch_),
        Eigen::Map<const Eigen::MatrixXf>(actions_.data(), kWidth, batch_),
        Eigen::Map<const Eigen::VectorXf>(rewards_.data(), batch_),
        Eigen::Map<const Eigen::MatrixXf>(next_states_.data(), kObs, batch_),
        Eigen::Map<const Eigen::VectorXf>(terminal_.data(), batch_),
        Eigen::Map<const Eigen::VectorXf>(returns_.data(), batch_),
    };
  }

 private:
  Eigen::MatrixXf random(int rows, int cols, float lo, float hi) {
    Eigen::MatrixXf m(rows, cols);
    for (Eigen::Index i = 0; i < m.size(); ++i) {
      m.data()[i] = static_cast<float>(rng_.uniform(lo, hi));
    }
    return m;
  }

  int batch_;
  Rng rng_;
  Eigen::MatrixXf states_, next_states_, actions_;
  Eigen::VectorXf rewards_, terminal_, returns_;
};

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
