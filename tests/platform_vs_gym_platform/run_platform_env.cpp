// Plays actions read from stdin ("id param" pairs) on envs/platform with the noise off and
// prints one JSON line per decision step: its tick count, status, reward, observation and the
// player's and enemies' x and y. For tests/platform_vs_gym_platform/compare.py.
#include <array>
#include <cstdio>
#include <iostream>
#include <vector>

#include "envs/platform/platform_env.hpp"

int main() {
  using pamdp::platform::PlatformEnv;
  PlatformEnv env({.noise = false});
  std::vector<float> obs(PlatformEnv::kObservationSize);
  env.reset(1, obs);
  int id = 0;
  double param = 0.0;
  while (std::cin >> id >> param) {
    std::array<float, 3> params{0.0F, 0.0F, 0.0F};
    params[static_cast<size_t>(id)] = static_cast<float>(param);
    const pamdp::StepResult r = env.step({id, params}, obs);
    std::printf(
        "{\"ticks\":%d,\"terminal\":%s,\"reward\":%.17g,\"px\":%.17g,\"py\":%.17g,\"e0\":%.17g,\"e1\":%.17g,\"obs\":[",
        env.last_ticks(), r.terminal() ? "true" : "false", static_cast<double>(r.reward), env.player().x,
        env.player().y, env.enemy(0).x, env.enemy(1).x);
    for (size_t i = 0; i < obs.size(); ++i) {
      std::printf("%s%.9g", i > 0 ? "," : "", static_cast<double>(obs[i]));
    }
    std::printf("]}\n");
    if (r.terminal()) {
      break;
    }
  }
  return 0;
}
