// A random minibatch with HFO's widths, shared by the update benchmarks (bench/update_bench.hpp)
// and the allocation test of the update (tests/learning/mlp_alloc_test.cpp). No Google
// Benchmark dependency, so tests can include it.
#pragma once

#include <Eigen/Core>
#include <cstdint>

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

}  // namespace pamdp::bench
