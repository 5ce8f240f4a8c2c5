// BM_DdpgUpdateCuda/32 (/128, /1024): the same update as BM_DdpgUpdate (paper widths, obs 58,
// 4 actions + 6 parameters, inverting gradients) through the CUDA backend (docs/gpu.md);
// items = updates, so items_per_second is updates/s. Updates are pipelined (the batch copy of
// one overlaps the previous), as in the learner, so this is the sustained rate.
// BM_GemmRooflineCuda: cuBLAS float32 SGEMM on the same device (items = FLOP), the roofline the
// update's GFLOP/s is compared with.
// Without a CUDA device (or in a build without CUDA) both report "no CUDA device" and skip.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "bench/update_bench.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "learner/cuda/cuda_update_backend.hpp"
#include "learner/ddpg.hpp"
#include "learner/update_backend.hpp"

namespace {

bool have_device(benchmark::State& state) {
  if (pamdp::cuda_device_count() > 0) {
    return true;
  }
  state.SkipWithError("no CUDA device");
  return false;
}

void BM_DdpgUpdateCuda(benchmark::State& state) {
  if (!have_device(state)) {
    return;
  }
  const int batch = static_cast<int>(state.range(0));
  pamdp::DdpgConfig cfg;
  cfg.batch_size = batch;
  cfg.bound = pamdp::BoundMethod::kInverting;
  const pamdp::ActionSpace& space = pamdp::hfo::hfo_action_space();
  pamdp::Ddpg ddpg(58, space, cfg, 1);
  const std::unique_ptr<pamdp::UpdateBackend> backend = pamdp::make_update_backend(ddpg, pamdp::UpdateDevice::kCuda);
  const pamdp::bench::RandomHfoBatch data(batch);
  const pamdp::BatchView view = data.view();
  for (int i = 0; i < 10; ++i) {  // first launches of the graphs
    backend->update(view);
  }
  backend->finish();
  for (auto _ : state) {
    const pamdp::UpdateStats s = backend->update(view);
    benchmark::DoNotOptimize(s.critic_loss);
  }
  backend->finish();
  state.SetItemsProcessed(state.iterations());
  pamdp::bench::report_update_flop(state, ddpg, batch);
  state.SetLabel(pamdp::cuda_device_description());
}
BENCHMARK(BM_DdpgUpdateCuda)->Arg(32)->Arg(128)->Arg(1024)->Unit(benchmark::kMicrosecond);

// C = A * B for (m x k) * (k x n) in float32 on the device, timed with CUDA events.
void BM_GemmRooflineCuda(benchmark::State& state) {
  if (!have_device(state)) {
    return;
  }
  const auto m = static_cast<int>(state.range(0));
  const auto k = static_cast<int>(state.range(1));
  const auto n = static_cast<int>(state.range(2));
  const double flop = 2.0 * m * k * n;
  const int reps = static_cast<int>(std::clamp(1e11 / flop, 1.0, 10000.0));  // a few ms per iteration
  for (auto _ : state) {
    state.SetIterationTime(pamdp::time_device_sgemm(m, n, k, reps) / reps);
  }
  state.SetItemsProcessed(static_cast<int64_t>(static_cast<double>(state.iterations()) * flop));
}
BENCHMARK(BM_GemmRooflineCuda)
    ->Args({4096, 4096, 4096})
    ->Args({2048, 2048, 2048})
    ->Args({512, 1024, 32})
    ->Args({1024, 512, 32})
    ->Args({1024, 59, 32})
    ->UseManualTime()
    ->Iterations(20)
    ->Unit(benchmark::kMicrosecond);

}  // namespace
