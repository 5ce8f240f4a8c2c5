#include <memory>

#include "envs/registry.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp {

void register_toy_env(EnvRegistry& registry) {
  EnvRegistration r;
  r.name = "reach_stop";
  r.description = "toy task: reach the target on a line, then STOP (3 features)";
  r.make = [](const EnvParams&) { return std::make_unique<toy::ReachStopEnv>(); };
  r.observation_size = [](const EnvParams&) { return toy::ReachStopEnv::kObservationSize; };
  r.observation_bound = toy::ReachStopEnv::kObservationBound;
  registry.add(std::move(r));
}

}  // namespace pamdp
