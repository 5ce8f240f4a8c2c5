#include <memory>

#include "envs/platform/platform_env.hpp"
#include "envs/registry.hpp"

namespace pamdp {

void register_platform_env(EnvRegistry& registry) {
  EnvRegistration r;
  r.name = "platform";
  r.description =
      "Platform (Masson et al. 2016, gym-platform's Platform-v0): run, hop and leap across three platforms past two "
      "enemies (9 features)";
  // env.noise, as the embedded HFO reads it: false removes the player's and enemies' noise.
  r.keys = {EnvKey::boolean("noise", true)};
  r.make = [](const EnvParams& params) {
    return std::make_unique<platform::PlatformEnv>(platform::PlatformConfig{.noise = params.boolean("noise")});
  };
  r.observation_size = [](const EnvParams&) { return platform::PlatformEnv::kObservationSize; };
  r.observation_bound = 1.0F;
  registry.add(std::move(r));
}

}  // namespace pamdp
