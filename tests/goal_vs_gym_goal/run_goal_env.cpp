// Plays GoalEnv with the scripted random policy of run_gym_goal.py and prints every state in
// gym-goal's get_state() order (check.sh builds and runs it).
// Usage: run_goal_env NOISE(0|1) EPISODES KICK_TO_PROBABILITY
#include <array>
#include <cstdio>
#include <cstdlib>

#include "core/rng.hpp"
#include "envs/goal/goal_env.hpp"

namespace {

void print_state(const pamdp::goal::GoalState& s) {
  for (const pamdp::goal::Body* b : {&s.striker, &s.keeper, &s.ball}) {
    std::printf(" %.17g %.17g %.17g %.17g", b->position.x, b->position.y, b->velocity.x, b->velocity.y);
    if (b != &s.ball) {
      std::printf(" %.17g", b->orientation_rad);
    }
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: run_goal_env NOISE(0|1) EPISODES KICK_TO_PROBABILITY\n");
    return 2;
  }
  const bool noise = argv[1][0] == '1';
  const int episodes = std::atoi(argv[2]);
  const double kick = std::atof(argv[3]);
  pamdp::goal::GoalEnv env(pamdp::goal::GoalConfig{.noise = noise});
  pamdp::Rng policy(99);
  std::array<float, pamdp::goal::GoalEnv::kObservationSize> obs{};
  for (int episode = 0; episode < episodes; ++episode) {
    if (episode == 0) {
      env.reset(5, obs);
    } else {
      env.reset(obs);
    }
    std::printf("R");
    print_state(env.state());
    while (true) {
      const double a = policy.uniform();
      std::array<float, 4> params{};
      int action = 0;
      if (a < kick) {
        params[0] = static_cast<float>(-2 + 18 * policy.uniform());
        params[1] = static_cast<float>(-20 + 40 * policy.uniform());
      } else {
        action = a < (1 + kick) / 2 ? 1 : 2;
        params[static_cast<size_t>(action) + 1] = static_cast<float>(-10 + 20 * policy.uniform());
      }
      const pamdp::StepResult r = env.step({action, params}, obs);
      std::printf("S %d %.17g %d", env.last_sim_steps(), static_cast<double>(r.reward), r.terminal() ? 1 : 0);
      print_state(env.state());
      if (r.terminal()) {
        break;
      }
    }
  }
  return 0;
}
