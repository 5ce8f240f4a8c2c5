// A trained DDPG actor as a Policy: greedy arg-max over the unmasked action scores and that
// action's parameters from the output (reference §7.3 with ε = 0), played by one copy of the
// actor (the online one unless told).
#pragma once

#include <vector>

#include "actor/exploration.hpp"
#include "core/policy.hpp"
#include "learner/ddpg.hpp"

namespace pamdp {

class GreedyActorPolicy final : public Policy {
 public:
  GreedyActorPolicy(Ddpg& ddpg, const ActionSpace& space, const ExplorationConfig& exploration,
                    ActorCopy copy = ActorCopy::kOnline)
      : ddpg_(ddpg),
        copy_(copy),
        select_(space, exploration, 0),
        output_(static_cast<size_t>(ddpg.output_width())),
        num_actions_(space.num_actions()) {}

  ParamAction act(std::span<const float> obs) override {
    ddpg_.act(obs, output_, copy_);
    const int id = select_.greedy(output_);
    return {id, std::span<const float>(output_).subspan(static_cast<size_t>(num_actions_))};
  }

 private:
  Ddpg& ddpg_;
  ActorCopy copy_;
  EpsilonGreedy select_;
  std::vector<float> output_;
  int num_actions_;
};

// The copy a run's evaluations (and so its best.ckpt) judge: the average when the learner keeps
// one (ddpg.actor_average_tau > 0), else the online actor.
inline ActorCopy evaluated_copy(const Ddpg& ddpg) {
  return ddpg.averages_actor() ? ActorCopy::kAverage : ActorCopy::kOnline;
}

}  // namespace pamdp
