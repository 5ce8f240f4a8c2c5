// An env whose continuous parameters all range over [-1, 1], mapped linearly onto another env's
// ranges before it steps: x = lo + (p + 1) (hi - lo) / 2. This is MP-DQN's
// ScaledParameterisedActionWrapper (cycraig/MP-DQN, common/wrappers.py), which its Platform and
// Goal runs play through; env.scaled_parameters turns it on for those envs here. A value past
// ±1 maps past the range, where the inner env clamps it; NaN passes through as NaN.
//
// Also the two conversions of a hand-made parameter policy (core/action_space.hpp) between the
// inner env's units and the scaled ones.
//
// step() and reset() allocate nothing. Not thread-safe: one env per thread, like the inner env.
#pragma once

#include <memory>
#include <vector>

#include "envs/env.hpp"

namespace pamdp {

class ScaledParametersEnv final : public Env {
 public:
  explicit ScaledParametersEnv(std::unique_ptr<Env> inner);

  [[nodiscard]] std::string_view name() const override { return inner_->name(); }
  [[nodiscard]] const ActionSpace& action_space() const override { return space_; }
  [[nodiscard]] int observation_size() const override { return inner_->observation_size(); }
  [[nodiscard]] int max_episode_steps() const override { return inner_->max_episode_steps(); }
  [[nodiscard]] std::string_view status_name(int status) const override { return inner_->status_name(status); }
  [[nodiscard]] std::span<const int> outcomes() const override { return inner_->outcomes(); }
  [[nodiscard]] int success_status() const override { return inner_->success_status(); }
  [[nodiscard]] std::span<const EnvCounter> counters() const override { return inner_->counters(); }

  void reset(uint64_t seed, std::span<float> obs) override { inner_->reset(seed, obs); }
  void reset(std::span<float> obs) override { inner_->reset(obs); }
  StepResult step(const ParamAction& action, std::span<float> obs) override;

  [[nodiscard]] Env& inner() { return *inner_; }

 private:
  std::unique_ptr<Env> inner_;
  ActionSpace space_;          // the inner env's, every parameter over [-1, 1]
  std::vector<float> params_;  // the inner env's units, for one step
};

// `env` itself, or wrapped in a ScaledParametersEnv when `scaled` (env.scaled_parameters).
std::unique_ptr<Env> scaled_if(bool scaled, std::unique_ptr<Env> env);

// `space`'s parameters over [-1, 1] (the action space ScaledParametersEnv shows).
ActionSpace scaled_action_space(const ActionSpace& space);

// A parameter policy in `space`'s own units from one in scaled units, and back.
ParameterPrior prior_in_units_of(const ParameterPrior& scaled, const ActionSpace& space);
ParameterPrior prior_in_scaled_units(const ParameterPrior& in_units, const ActionSpace& space);

}  // namespace pamdp
