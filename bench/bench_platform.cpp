// BM_PlatformStep: one decision step of the Platform env (envs/platform/), with its noise, under a
// fixed action cycle that runs, hops and leaps; items = decision steps. A decision step is 20
// simulation ticks for RUN and up to about 150 for a jump, so the counter "ticks" reports the
// ticks per second too.
#include <benchmark/benchmark.h>

#include <array>
#include <vector>

#include "envs/platform/platform_env.hpp"

namespace {

void BM_PlatformStep(benchmark::State& state) {
  pamdp::platform::PlatformEnv env;
  std::vector<float> obs(static_cast<size_t>(env.observation_size()));
  env.reset(7, obs);
  // Mostly runs, as a learned policy plays, with a hop and a leap in every eight steps.
  const std::array<float, 3> params{20.0F, 300.0F, 250.0F};
  constexpr std::array<int, 8> kCycle{0, 0, 0, 1, 0, 0, 0, 2};
  size_t k = 0;
  int64_t ticks = 0;
  for (auto _ : state) {
    const auto r = env.step({kCycle[k++ & 7U], params}, obs);
    ticks += env.last_ticks();
    if (r.terminal()) {
      env.reset(obs);
    }
    benchmark::DoNotOptimize(obs.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["ticks"] = benchmark::Counter(static_cast<double>(ticks), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PlatformStep);

}  // namespace
