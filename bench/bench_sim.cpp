// BM_SimStep: one embedded-HFO env step (physics + referee + 58 features + reward) driven by
// a fixed-cost scripted action stream, items = env steps.
// BM_SimStepTeam/N: one cycle of N offense agents against the goalie (HfoTeamEnv), each agent's
// action, features and reward; items = cycles (issue 79's target: >= 500 k/s for 2v1, given as
// a ratio to BM_SimStep in the same run).
// BM_GoalStep: one Robot Soccer Goal decision step (every internal simulation step it runs, and
// the 17 features), items = decision steps; the counter sim_steps is the internal step rate.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <vector>

#include "core/rng.hpp"
#include "envs/goal/goal_env.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/hfo_team_env.hpp"

namespace {

void run_sim_steps(benchmark::State& state, const pamdp::hfo::SoccerSimConfig& config) {
  pamdp::hfo::HfoEnv env(config);
  std::vector<float> obs(static_cast<size_t>(env.observation_size()));
  env.reset(7, obs);
  // A cheap, deterministic action cycle that exercises dash, turn and kick; computing a
  // policy here would measure the policy, not the simulator.
  std::array<float, 6> params{80.0F, 0.0F, 30.0F, 0.0F, 60.0F, 10.0F};
  constexpr std::array<int, 8> kCycle{0, 0, 1, 0, 3, 0, 0, 3};
  size_t k = 0;
  for (auto _ : state) {
    const auto r = env.step({kCycle[k++ & 7U], params}, obs);
    if (r.terminal()) {
      env.reset(obs);
    }
    benchmark::DoNotOptimize(obs.data());
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_SimStep(benchmark::State& state) {
  run_sim_steps(state, {});
}
BENCHMARK(BM_SimStep);

// The same with the NPC goalie (1v1, 66 features): its decision, command and physics per step.
void BM_SimStepGoalie(benchmark::State& state) {
  run_sim_steps(state, {.goalie = true});
}
BENCHMARK(BM_SimStepGoalie);

// `agents` offense agents against the goalie and `defenders` of agent2d's field defenders.
void run_team_steps(benchmark::State& state, int agents, int defenders) {
  pamdp::hfo::SoccerSimConfig config;
  config.goalie = true;
  config.offense_agents = agents;
  config.field_defenders = defenders;
  pamdp::hfo::HfoTeamEnv env(config);
  const int n = env.agents();
  std::vector<float> obs(static_cast<size_t>(n * env.observation_size()));
  std::vector<float> rewards(static_cast<size_t>(n));
  env.reset(7, obs);
  std::array<float, 6> params{80.0F, 0.0F, 30.0F, 0.0F, 60.0F, 10.0F};
  constexpr std::array<int, 8> kCycle{0, 0, 1, 0, 3, 0, 0, 3};
  std::vector<pamdp::ParamAction> actions(static_cast<size_t>(n));
  size_t k = 0;
  for (auto _ : state) {
    for (int i = 0; i < n; ++i) {
      actions[static_cast<size_t>(i)] = {kCycle[(k + static_cast<size_t>(3 * i)) & 7U], params};
    }
    ++k;
    if (env.step(actions, obs, rewards) != 0) {
      env.reset(obs);
    }
    benchmark::DoNotOptimize(obs.data());
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_SimStepTeam(benchmark::State& state) {
  run_team_steps(state, static_cast<int>(state.range(0)), 0);
}
BENCHMARK(BM_SimStepTeam)->Arg(1)->Arg(2)->Arg(4);

// BM_SimStepDefenders/N/K: N offense agents against HFO's --defense-npcs K (the goalie and K - 1
// of agent2d's field defenders, issue 83).
void BM_SimStepDefenders(benchmark::State& state) {
  run_team_steps(state, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)) - 1);
}
BENCHMARK(BM_SimStepDefenders)->Args({1, 2})->Args({2, 2})->Args({1, 3});

void BM_GoalStep(benchmark::State& state) {
  pamdp::goal::GoalEnv env;
  std::array<float, pamdp::goal::GoalEnv::kObservationSize> obs{};
  env.reset(7, obs);
  // Random play, drawn up front so that the loop measures the env, not a policy: a uniform
  // action with every parameter uniform in its range (an exploring learner's early actions).
  const pamdp::ActionSpace& space = env.action_space();
  constexpr size_t kActions = 4096;
  std::vector<int> ids(kActions);
  std::vector<std::array<float, 4>> params(kActions);
  pamdp::Rng rng(11);
  for (size_t i = 0; i < kActions; ++i) {
    ids[i] = static_cast<int>(rng.below(static_cast<uint64_t>(space.num_actions())));
    for (size_t p = 0; p < params[i].size(); ++p) {
      params[i][p] = static_cast<float>(rng.uniform(space.params[p].lo, space.params[p].hi));
    }
  }
  size_t k = 0;
  int64_t sim_steps = 0;
  for (auto _ : state) {
    const size_t i = k++ % kActions;
    const auto r = env.step({ids[i], params[i]}, obs);
    sim_steps += env.last_sim_steps();
    if (r.terminal()) {
      env.reset(obs);
    }
    benchmark::DoNotOptimize(obs.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["sim_steps"] = benchmark::Counter(static_cast<double>(sim_steps), benchmark::Counter::kIsRate);
  state.counters["sim_steps_per_step"] =
      benchmark::Counter(static_cast<double>(sim_steps) / static_cast<double>(state.iterations()));
}
BENCHMARK(BM_GoalStep);

}  // namespace
