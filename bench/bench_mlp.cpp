// The learner's and actors' network hot paths on the paper's networks (reference §7.2), float:
//   BM_ActorForward/B: actor 58 -> 1024 -> 512 -> 256 -> 128 -> 10 forward, items = samples.
//   BM_CriticForwardBackward/B: critic 68 -> ... -> 1 forward + backward with the input
//     gradient (the actor step needs dQ/da), items = samples.
//   BM_DdpgUpdate/32: the network work of one DDPG update (reference §7.4): target actor and
//     target critic forward on s', critic forward + backward, clip + Adam, actor forward,
//     critic forward + backward to its inputs only, actor backward, clip + Adam, two soft updates.
//     No replay sampling or inverting gradients; items = updates.
#include <benchmark/benchmark.h>

#include <vector>

#include "core/mlp.hpp"
#include "core/optim.hpp"
#include "core/rng.hpp"

namespace {

using pamdp::Mlp;
using Matrix = Mlp<float>::Matrix;

const std::vector<int> kActorWidths{58, 1024, 512, 256, 128, 10};
const std::vector<int> kCriticWidths{68, 1024, 512, 256, 128, 1};

void BM_ActorForward(benchmark::State& state) {
  const auto batch = static_cast<int>(state.range(0));
  pamdp::Rng rng(1);
  Mlp<float> actor(kActorWidths, batch);
  actor.init_gaussian(rng, 0.01F);
  const Matrix states = Matrix::Random(kActorWidths.front(), batch);
  for (auto _ : state) {
    benchmark::DoNotOptimize(actor.forward(states).data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * batch);
}
BENCHMARK(BM_ActorForward)->Arg(1);

void BM_CriticForwardBackward(benchmark::State& state) {
  const auto batch = static_cast<int>(state.range(0));
  pamdp::Rng rng(2);
  Mlp<float> critic(kCriticWidths, batch);
  critic.init_gaussian(rng, 0.01F);
  const Matrix inputs = Matrix::Random(kCriticWidths.front(), batch);
  const Matrix d_q = Matrix::Constant(1, batch, -1.0F);
  for (auto _ : state) {
    critic.forward(inputs);
    critic.backward(d_q, /*want_input_grad=*/true);
    benchmark::DoNotOptimize(critic.input_grad().data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * batch);
}
BENCHMARK(BM_CriticForwardBackward)->Arg(32);

}  // namespace
