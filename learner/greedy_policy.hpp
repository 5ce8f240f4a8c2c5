// A trained learner as a Policy: greedy arg-max over the unmasked action scores and that
// action's parameters from the output (reference §7.3 with ε = 0), played by one copy of the
// acting network (the online one unless told).
#pragma once

#include <vector>

#include "actor/exploration.hpp"
#include "core/policy.hpp"
#include "learner/algorithm.hpp"

namespace pamdp {

class GreedyActorPolicy final : public Policy {
 public:
  GreedyActorPolicy(Algorithm& algorithm, const ActionSpace& space, const ExplorationConfig& exploration,
                    ActorCopy copy = ActorCopy::kOnline)
      : algorithm_(algorithm),
        copy_(copy),
        select_(space, exploration, 0),
        output_(static_cast<size_t>(algorithm.output_width())),
        num_actions_(space.num_actions()) {}

  ParamAction act(std::span<const float> obs) override {
    algorithm_.act(obs, output_, copy_);
    const int id = select_.greedy(obs, output_);
    return {id, std::span<const float>(output_).subspan(static_cast<size_t>(num_actions_))};
  }

 private:
  Algorithm& algorithm_;
  ActorCopy copy_;
  EpsilonGreedy select_;
  std::vector<float> output_;
  int num_actions_;
};

}  // namespace pamdp
