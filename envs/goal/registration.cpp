#include <memory>

#include "envs/goal/goal_env.hpp"
#include "envs/registry.hpp"

namespace pamdp {

void register_goal_env(EnvRegistry& registry) {
  EnvRegistration r;
  r.name = "goal";
  r.description = "Robot Soccer Goal (Masson et al. 2016, gym-goal): kick past a keeper (17 features)";
  // Declared as the hfo env declares it (EnvRegistry::add checks): acceleration noise on or off.
  r.keys = {EnvKey::boolean("noise", true)};
  r.make = [](const EnvParams& p) {
    return std::make_unique<goal::GoalEnv>(goal::GoalConfig{.noise = p.boolean("noise")});
  };
  r.observation_size = [](const EnvParams&) { return goal::GoalEnv::kObservationSize; };
  r.observation_bound = goal::GoalEnv::kObservationBound;
  registry.add(std::move(r));
}

}  // namespace pamdp
