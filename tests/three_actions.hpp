// The small parameterized task the learners' unit tests share (tests/pdqn_test.cpp,
// tests/ddpg_passthrough_test.cpp): three actions over kObs observations, a small network
// config, a random batch of kB transitions and a random hand-made parameter policy.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/action_space.hpp"
#include "core/rng.hpp"
#include "learner/algorithm.hpp"
#include "learner/ddpg.hpp"

namespace pamdp::testing {

constexpr int kObs = 3;
constexpr int kB = 5;

// Three actions: one with one parameter, one with two, one with none (6 outputs: 3 scores, 3
// parameters).
inline ActionSpace test_space() {
  ActionSpace s;
  s.actions = {{"one", {0}}, {"two", {1, 2}}, {"none", {}}};
  s.params = {{"p0", -1.0F, 1.0F}, {"p1", -2.0F, 2.0F}, {"p2", 0.0F, 1.0F}};
  return s;
}

inline DdpgConfig small(BoundMethod bound) {
  DdpgConfig c;
  c.hidden = {6};
  c.batch_size = kB;
  c.bound = bound;
  c.gamma = 0.9;
  c.init_std = 0.5;
  c.critic_output_init_std = 0.5;
  c.critic_output_init_bias = 0.0;
  c.device = UpdateDevice::kCpu;
  return c;
}

struct Batch {
  Eigen::MatrixXf states = Eigen::MatrixXf::Random(kObs, kB);
  Eigen::MatrixXf actions = Eigen::MatrixXf::Random(6, kB);  // 3 scores, 3 parameters in (-1, 1)
  Eigen::VectorXf rewards = Eigen::VectorXf::Random(kB);
  Eigen::MatrixXf next_states = Eigen::MatrixXf::Random(kObs, kB);
  Eigen::VectorXf terminal = Eigen::VectorXf::Zero(kB);
  Eigen::VectorXf mc = Eigen::VectorXf::Zero(kB);
  Batch() {
    terminal(1) = 1.0F;
    actions.row(5) = actions.row(5).cwiseAbs();  // p2 in [0, 1]
  }
  [[nodiscard]] BatchView view() const {
    return {Eigen::Map<const Eigen::MatrixXf>(states.data(), kObs, kB),
            Eigen::Map<const Eigen::MatrixXf>(actions.data(), 6, kB),
            Eigen::Map<const Eigen::VectorXf>(rewards.data(), kB),
            Eigen::Map<const Eigen::MatrixXf>(next_states.data(), kObs, kB),
            Eigen::Map<const Eigen::VectorXf>(terminal.data(), kB),
            Eigen::Map<const Eigen::VectorXf>(mc.data(), kB)};
  }
};

// A random hand-made parameter policy for test_space() (3 parameters over kObs features):
// weights in [-1, 1], biases in [-0.5, 0.5].
inline ParameterPrior random_prior(uint64_t seed) {
  Rng rng(seed);
  ParameterPrior p{kObs, std::vector<float>(3 * kObs), std::vector<float>(3)};
  for (float& w : p.weights) {
    w = static_cast<float>(rng.uniform(-1.0, 1.0));
  }
  for (float& b : p.bias) {
    b = static_cast<float>(rng.uniform(-0.5, 0.5));
  }
  return p;
}

}  // namespace pamdp::testing
