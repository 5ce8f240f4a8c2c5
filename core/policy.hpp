// A policy maps an observation to a parameterized action. Evaluation, actors and tools drive
// any policy (scripted, random, a trained network) through this interface.
// Not thread-safe; act() must not allocate.
#pragma once

#include <span>
#include <vector>

#include "core/action_space.hpp"
#include "core/rng.hpp"

namespace pamdp {

class Policy {
 public:
  virtual ~Policy() = default;
  // Called at the start of every episode, before the first act().
  virtual void begin_episode() {}
  // Returns the action for `obs`. The returned params view stays valid until the next call.
  virtual ParamAction act(std::span<const float> obs) = 0;
};

// Uniformly random discrete action (over the allowed ones) with uniformly random parameters,
// as the paper's ε-exploration draws them. `param_lo/hi` default to the space's bounds.
class RandomPolicy final : public Policy {
 public:
  RandomPolicy(const ActionSpace& space, uint64_t seed, std::vector<int> allowed_actions = {});
  // Overrides the sampling range of one parameter (e.g. dash power U[-100, 100]).
  void set_param_range(int index, float lo, float hi);
  ParamAction act(std::span<const float> obs) override;

 private:
  std::vector<int> allowed_;
  std::vector<float> lo_;
  std::vector<float> hi_;
  std::vector<float> params_;
  Rng rng_;
};

}  // namespace pamdp
