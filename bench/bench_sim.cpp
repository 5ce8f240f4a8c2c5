// BM_SimStep: one embedded-HFO env step (physics + referee + 58 features + reward) driven by
// a fixed-cost scripted action stream, items = env steps.
#include <benchmark/benchmark.h>

#include <array>
#include <vector>

#include "envs/hfo/hfo_env.hpp"

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

}  // namespace
