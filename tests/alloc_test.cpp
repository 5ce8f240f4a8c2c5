// Proves the hot paths allocate nothing (envs/env.hpp, core/policy.hpp): every global
// operator new in this binary is replaced by one that counts while a CountAllocations scope
// is open. Its own binary, so the replacement affects no other test.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include "core/policy.hpp"
#include "counting_new.hpp"
#include "envs/goal/goal_env.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/platform/platform_env.hpp"
#include "envs/scaled_parameters.hpp"
#include "envs/toy/reach_stop.hpp"

using pamdp::testing::alloc::CountAllocations;

namespace pamdp {
namespace {

TEST(CountingAllocator, SeesAllocations) {
  // Guards against a harness that counts nothing (e.g. the replacement not linked in).
  long n = 0;
  {
    CountAllocations scope;
    auto v = std::make_unique<std::vector<int>>(100);
    n = scope.count();
  }
  EXPECT_GE(n, 2);
}

// Plays HFO episodes with a mix of every action. Everything the loop needs is built before
// the counting scope opens; the first reset is outside too, so one-time lazy set-up (static
// tables) is not blamed on the hot path.
void expect_hfo_hot_path_allocation_free(bool noise, bool goalie = false) {
  hfo::SoccerSimConfig config;
  config.noise = noise;
  config.goalie = goalie;
  hfo::HfoEnv env(config);
  std::vector<float> obs(static_cast<size_t>(env.observation_size()));
  RandomPolicy random(env.action_space(), 3);
  hfo::ScriptedOffense scripted;
  env.reset(1, obs);
  (void)env.step(random.act(obs), obs);

  long allocations = 0;
  int steps = 0;
  {
    CountAllocations scope;
    for (int ep = 0; ep < 20; ++ep) {
      env.reset(obs);
      Policy& policy = ep % 2 == 0 ? static_cast<Policy&>(scripted) : static_cast<Policy&>(random);
      policy.begin_episode();
      StepResult r;
      do {
        r = env.step(policy.act(obs), obs);
        ++steps;
      } while (!r.terminal());
    }
    env.reset(99, obs);
    allocations = scope.count();
  }
  EXPECT_GT(steps, 500) << "too few steps to prove anything";
  EXPECT_EQ(allocations, 0) << "HfoEnv::step/reset or a policy's act() allocated during " << steps << " steps";
}

TEST(HfoEnvAllocations, StepAndResetAllocateNothingWithNoise) {
  expect_hfo_hot_path_allocation_free(true);
}
TEST(HfoEnvAllocations, StepAndResetAllocateNothingWithoutNoise) {
  expect_hfo_hot_path_allocation_free(false);
}
// 1v1: the NPC goalie's decision and catch run inside step().
TEST(HfoEnvAllocations, StepAndResetAllocateNothingWithGoalie) {
  expect_hfo_hot_path_allocation_free(true, true);
}

// Two offense agents and the goalie, with `field_defenders` of agent2d's field defenders beside
// it: each player's features and reward, and every defender's decision, per step.
void expect_team_allocation_free(int field_defenders, int min_steps) {
  hfo::SoccerSimConfig config;
  config.goalie = true;
  config.offense_agents = 2;
  config.field_defenders = field_defenders;
  hfo::HfoTeamEnv env(config);
  const size_t n = static_cast<size_t>(env.observation_size());
  std::vector<float> obs(2 * n);
  std::array<float, 2> rewards{};
  RandomPolicy p0(env.action_space(), 3);
  RandomPolicy p1(env.action_space(), 4);
  env.reset(1, obs);
  long allocations = 0;
  int steps = 0;
  {
    CountAllocations scope;
    for (int ep = 0; ep < 20; ++ep) {
      env.reset(obs);
      int status = 0;
      do {
        const std::array<ParamAction, 2> actions{p0.act(std::span<const float>(obs).first(n)),
                                                 p1.act(std::span<const float>(obs).subspan(n, n))};
        status = env.step(actions, obs, rewards);
        ++steps;
      } while (status == 0);
    }
    allocations = scope.count();
  }
  EXPECT_GT(steps, min_steps);
  EXPECT_EQ(allocations, 0) << "HfoTeamEnv::step/reset allocated during " << steps << " steps";
}

// 2v1 (issue 79).
TEST(HfoTeamEnvAllocations, StepAndResetAllocateNothing) {
  expect_team_allocation_free(0, 500);
}

// 2v3 (issue 83): the goalie and two field defenders.
TEST(HfoTeamEnvAllocations, StepAndResetAllocateNothingWithFieldDefenders) {
  expect_team_allocation_free(2, 200);
}

// Plays `episodes` random episodes of `env` inside a counting scope (reset() and reset(seed)
// too) and expects no allocation; `min_steps` guards against a harness that plays nothing.
void expect_env_allocation_free(Env& env, int episodes, int min_steps) {
  std::vector<float> obs(static_cast<size_t>(env.observation_size()));
  RandomPolicy policy(env.action_space(), 5);
  env.reset(1, obs);
  (void)env.step(policy.act(obs), obs);
  long allocations = 0;
  int steps = 0;
  {
    CountAllocations scope;
    for (int ep = 0; ep < episodes; ++ep) {
      env.reset(obs);
      StepResult r;
      do {
        r = env.step(policy.act(obs), obs);
        ++steps;
      } while (!r.terminal());
    }
    env.reset(99, obs);
    allocations = scope.count();
  }
  EXPECT_GT(steps, min_steps);
  EXPECT_EQ(allocations, 0);
}

TEST(ReachStopAllocations, StepAndResetAllocateNothing) {
  toy::ReachStopEnv env;
  expect_env_allocation_free(env, 50, 50);
}

// Robot Soccer Goal: every internal simulation step of a decision runs inside step().
TEST(GoalEnvAllocations, StepAndResetAllocateNothing) {
  goal::GoalEnv env;
  expect_env_allocation_free(env, 200, 200);
}

// Platform: every tick of a decision, noise included, runs inside step().
TEST(PlatformEnvAllocations, StepAndResetAllocateNothing) {
  platform::PlatformEnv env;
  expect_env_allocation_free(env, 200, 200);
}

// Parameters over [-1, 1] (env.scaled_parameters): the mapping reuses one buffer.
TEST(ScaledParametersAllocations, StepAndResetAllocateNothing) {
  ScaledParametersEnv env(std::make_unique<goal::GoalEnv>());
  expect_env_allocation_free(env, 200, 200);
}

}  // namespace
}  // namespace pamdp
