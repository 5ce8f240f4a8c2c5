// BM_DdpgUpdate/32 (/128, /1024): one full DDPG update of the paper's networks (58 -> 1024 ->
// 512 -> 256 -> 128 -> 4+6 actor, 68 -> ... -> 1 critic) at batch 32 (128, 1024) with inverting
// gradients, through the learner's own Ddpg class; items = updates. The GPU versions are in
// bench_ddpg_cuda.cpp.
// BM_GemmRoofline: Eigen float GEMM on this core, the roofline the update is measured against
// (items = FLOP, so items_per_second reads as FLOP/s).
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <vector>

#include "bench/update_bench.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "learner/ddpg.hpp"

namespace {

void BM_DdpgUpdate(benchmark::State& state) {
  const int batch = static_cast<int>(state.range(0));
  pamdp::DdpgConfig cfg;
  cfg.batch_size = batch;
  cfg.bound = pamdp::BoundMethod::kInverting;
  const pamdp::ActionSpace& space = pamdp::hfo::hfo_action_space();
  pamdp::Ddpg ddpg(58, space, cfg, 1);
  const pamdp::bench::RandomHfoBatch data(batch);
  const pamdp::BatchView view = data.view();
  for (auto _ : state) {
    const pamdp::UpdateStats s = ddpg.update(view);
    benchmark::DoNotOptimize(s.critic_loss);
  }
  state.SetItemsProcessed(state.iterations());
  pamdp::bench::report_update_flop(state, ddpg, batch);
}
BENCHMARK(BM_DdpgUpdate)->Arg(32)->Arg(128)->Arg(1024)->Unit(benchmark::kMillisecond);

// C = A * B for (m x k) * (k x n): the achievable single-core GEMM rate of Eigen here.
void BM_GemmRoofline(benchmark::State& state) {
  const auto m = state.range(0);
  const auto k = state.range(1);
  const auto n = state.range(2);
  const Eigen::MatrixXf A = Eigen::MatrixXf::Random(m, k);
  const Eigen::MatrixXf B = Eigen::MatrixXf::Random(k, n);
  Eigen::MatrixXf C(m, n);
  for (auto _ : state) {
    C.noalias() = A * B;
    benchmark::DoNotOptimize(C.data());
  }
  state.SetItemsProcessed(state.iterations() * 2 * m * k * n);
}
BENCHMARK(BM_GemmRoofline)
    ->Args({2048, 2048, 2048})
    ->Args({512, 1024, 32})
    ->Args({1024, 512, 32})
    ->Unit(benchmark::kMillisecond);

}  // namespace
