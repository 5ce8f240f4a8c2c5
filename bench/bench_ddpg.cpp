// BM_DdpgUpdate/32 (/128, /1024): one full DDPG update of the paper's networks (58 -> 1024 ->
// 512 -> 256 -> 128 -> 4+6 actor, 68 -> ... -> 1 critic) at batch 32 (128, 1024) with inverting
// gradients, through the learner's own Ddpg class; items = updates. The GPU versions are in
// bench_ddpg_cuda.cpp. BM_DdpgUpdateFast/32: the same with fast.toml's widths (256-128-64).
// BM_PdqnUpdate: P-DQN's and MP-DQN's update at those widths.
// BM_GemmRoofline: float GEMM on this core through core/gemm.hpp (OpenBLAS where it was found,
// the label says), the roofline the update is measured against (items = FLOP, so
// items_per_second reads as FLOP/s). BM_GemmEigen: Eigen's own product on the same shapes, for
// comparison.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "bench/update_bench.hpp"
#include "core/gemm.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "learner/ddpg.hpp"
#include "learner/pdqn.hpp"

namespace {

void update(benchmark::State& state, const std::vector<int>& hidden) {
  const int batch = static_cast<int>(state.range(0));
  pamdp::DdpgConfig cfg;
  cfg.hidden = hidden;
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
  state.SetLabel(pamdp::gemm_backend());
}

void BM_DdpgUpdate(benchmark::State& state) {
  update(state, pamdp::DdpgConfig{}.hidden);
}
BENCHMARK(BM_DdpgUpdate)->Arg(32)->Arg(128)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_DdpgUpdateFast(benchmark::State& state) {
  update(state, {256, 128, 64});
}
BENCHMARK(BM_DdpgUpdateFast)->Arg(32)->Unit(benchmark::kMillisecond);

// BM_PdqnUpdate/0 (/1): one P-DQN (MP-DQN) update with hfo-mpdqn.toml's networks (256-128-64
// for both), batch 32, Tackle masked as HFO's presets mask it, through the learner's own Pdqn
// class; items = updates. Read it against BM_DdpgUpdateFast/32 of the same run, which has the
// same widths.
void BM_PdqnUpdate(benchmark::State& state) {
  const bool multipass = state.range(0) != 0;
  pamdp::DdpgConfig cfg;
  cfg.hidden = {256, 128, 64};
  cfg.batch_size = 32;
  cfg.bound = pamdp::BoundMethod::kInverting;
  const pamdp::ActionSpace& space = pamdp::hfo::hfo_action_space();
  pamdp::Pdqn pdqn(58, space, cfg, 1, multipass, {pamdp::hfo::kTackle});
  const pamdp::bench::RandomHfoBatch data(32);
  const pamdp::BatchView view = data.view();
  for (auto _ : state) {
    const pamdp::UpdateStats s = pdqn.update(view);
    benchmark::DoNotOptimize(s.critic_loss);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(std::string(multipass ? "mpdqn " : "pdqn ") + pamdp::gemm_backend());
}
BENCHMARK(BM_PdqnUpdate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// C = A * B for (m x k) * (k x n): the achievable single-core GEMM rate here, through the
// update's own gemm() (the library it chose, labelled), or on one library.
enum class Through { kGemm, kEigen, kOpenBlas };

void gemm_rate(benchmark::State& state, Through through) {
  const auto m = state.range(0);
  const auto k = state.range(1);
  const auto n = state.range(2);
  const Eigen::MatrixXf A = Eigen::MatrixXf::Random(m, k);
  const Eigen::MatrixXf B = Eigen::MatrixXf::Random(k, n);
  Eigen::MatrixXf C(m, n);
  for (auto _ : state) {
    if (through == Through::kEigen) {
      C.noalias() = A * B;
    } else if (through == Through::kOpenBlas) {
      pamdp::gemm_on<float>(pamdp::GemmLibrary::kOpenBlas, pamdp::Op::kNone, A, pamdp::Op::kNone, B, C,
                            /*accumulate=*/false);
    } else {
      pamdp::gemm<float>(pamdp::Op::kNone, A, pamdp::Op::kNone, B, C, /*accumulate=*/false);
    }
    benchmark::DoNotOptimize(C.data());
  }
  state.SetItemsProcessed(state.iterations() * 2 * m * k * n);
  state.SetLabel(through == Through::kEigen      ? "Eigen"
                 : through == Through::kOpenBlas ? "OpenBLAS"
                                                 : pamdp::gemm_backend());
}

void BM_GemmRoofline(benchmark::State& state) {
  gemm_rate(state, Through::kGemm);
}
BENCHMARK(BM_GemmRoofline)
    ->Args({2048, 2048, 2048})
    ->Args({512, 1024, 32})
    ->Args({1024, 512, 32})
    ->Unit(benchmark::kMillisecond);

void BM_GemmEigen(benchmark::State& state) {
  gemm_rate(state, Through::kEigen);
}
BENCHMARK(BM_GemmEigen)->Args({2048, 2048, 2048})->Args({1024, 512, 32})->Unit(benchmark::kMillisecond);

// OpenBLAS where it is built in, whichever library gemm() chose: on AVX-512 builds gemm()
// runs on Eigen, and this row is what it would get from OpenBLAS in the same run.
void BM_GemmOpenBlas(benchmark::State& state) {
  if (!pamdp::gemm_library_available(pamdp::GemmLibrary::kOpenBlas)) {
    state.SkipWithError("OpenBLAS is not built in");
    return;
  }
  gemm_rate(state, Through::kOpenBlas);
}
BENCHMARK(BM_GemmOpenBlas)->Args({2048, 2048, 2048})->Args({1024, 512, 32})->Unit(benchmark::kMillisecond);

}  // namespace
