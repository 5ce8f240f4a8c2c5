#include <memory>

#include "envs/platform/platform_env.hpp"
#include "envs/registry.hpp"
#include "envs/scaled_parameters.hpp"

namespace pamdp {

void register_platform_env(EnvRegistry& registry) {
  EnvRegistration r;
  r.name = "platform";
  r.description =
      "Platform (Masson et al. 2016, gym-platform's Platform-v0): run, hop and leap across three platforms past two "
      "enemies (9 features)";
  // env.noise, as the embedded HFO reads it: false removes the player's and enemies' noise.
  // env.scaled_parameters, as goal declares it: every parameter over [-1, 1], as MP-DQN plays it.
  r.keys = {EnvKey::boolean("noise", true), EnvKey::boolean("scaled_parameters", false)};
  r.make = [](const EnvParams& params) {
    return scaled_if(
        params.boolean("scaled_parameters"),
        std::make_unique<platform::PlatformEnv>(platform::PlatformConfig{.noise = params.boolean("noise")}));
  };
  r.observation_size = [](const EnvParams&) { return platform::PlatformEnv::kObservationSize; };
  r.observation_bound = 1.0F;
  // MP-DQN's hand-made starting parameters for Platform (cycraig/MP-DQN run_platform_pdqn.py,
  // --initialise-params: initial_params_ = [3, 10, 400] for run, hop and leap), whatever the state.
  r.parameter_prior = [](const EnvParams& params) -> std::optional<ParameterPrior> {
    constexpr int kObs = platform::PlatformEnv::kObservationSize;
    const ParameterPrior raw{kObs, std::vector<float>(3 * kObs, 0.0F), {3.0F, 10.0F, 400.0F}};
    if (params.boolean("scaled_parameters")) {
      return prior_in_scaled_units(raw, platform::PlatformEnv(platform::PlatformConfig{}).action_space());
    }
    return raw;
  };
  registry.add(std::move(r));
}

}  // namespace pamdp
