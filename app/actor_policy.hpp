// A trained DDPG actor as a Policy: greedy arg-max over the unmasked action scores and that
// action's parameters from the output (reference §7.3 with ε = 0).
#pragma once

#include <vector>

#include "actor/exploration.hpp"
#include "core/policy.hpp"
#include "learner/ddpg.hpp"

namespace pamdp::app {

class GreedyActorPolicy final : public Policy {
 public:
  GreedyActorPolicy(Ddpg& ddpg, const ActionSpace& space, const ExplorationConfig& exploration)
      : ddpg_(ddpg),
        select_(space, exploration, 0),
        output_(static_cast<size_t>(ddpg.output_width())),
        num_actions_(space.num_actions()) {}

  ParamAction act(std::span<const float> obs) override {
    ddpg_.act(obs, output_);
    const int id = select_.greedy(output_);
    return {id, std::span<const float>(output_).subspan(static_cast<size_t>(num_actions_))};
  }

 private:
  Ddpg& ddpg_;
  EpsilonGreedy select_;
  std::vector<float> output_;
  int num_actions_;
};

}  // namespace pamdp::app
