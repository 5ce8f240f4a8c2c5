// Proves the acting loop allocates nothing in steady state: every global operator new in this
// binary is replaced by one that counts while the actor thread has counting switched on (from
// its on_tick callback, so only that thread is measured). Its own binary, so the replacement
// affects no other test. The window spans env steps with and without the network (ε = 0.5),
// episode ends, batch sends, episode reports, heartbeats and their answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdlib>
#include <new>

#include "actor/episode_player.hpp"
#include "actor_harness.hpp"
#include "counting_new.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/scripted_team.hpp"

namespace pamdp::testing {
namespace {

TEST(ActorLoopAllocations, SteadyStateActingAllocatesNothing) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  ActorLoopConfig config = test_loop_config();
  config.exploration.epsilon_start = 0.5;
  config.exploration.epsilon_end = 0.5;

  constexpr int kTicks = 10;
  std::atomic<int> phase{0};  // 0 warming up, 1 counting, 2 done
  std::atomic<int64_t> steps_counted{0};
  std::atomic<int64_t> batches_counted{0};
  std::atomic<int64_t> episodes_counted{0};
  int ticks = 0;
  int64_t steps0 = 0;
  int64_t batches0 = 0;
  int64_t episodes0 = 0;
  auto on_tick = [&](const ActorCounters& c, double /*eps*/) {
    if (phase.load() == 0 && c.weights_version.load() >= 1 && c.batches_sent.load() >= 10) {
      steps0 = c.env_steps.load();
      batches0 = c.batches_sent.load();
      episodes0 = c.episodes.load();
      alloc::count_this_thread(true);
      alloc::start_counting(/*only_marked_threads=*/true);
      phase = 1;
    } else if (phase.load() == 1 && ++ticks >= kTicks) {
      alloc::stop_counting();
      steps_counted = c.env_steps.load() - steps0;
      batches_counted = c.batches_sent.load() - batches0;
      episodes_counted = c.episodes.load() - episodes0;
      phase = 2;
    }
  };
  ActorRunner actor(ctx, learner.join_endpoint(), config, 2, 2000, on_tick);
  const Bytes weights = [] {
    flatbuffers::FlatBufferBuilder fbb;
    const std::vector<float> params = constant_output_params({0.5F, -0.5F, 0.25F});
    const NetworkView actor{"actor", kTestWidths, params};
    wire::build_policy_weights(fbb, 1, 0, "ddpg", 0, {&actor, 1});
    return copy_bytes(wire::bytes_of(fbb));
  }();
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] {
    if (actor.counters.weights_version.load() < 1) {
      learner.publish(weights);
    }
    return phase.load() == 2;
  }));
  EXPECT_GT(steps_counted.load(), 1000);
  EXPECT_GT(batches_counted.load(), 10);
  EXPECT_GT(episodes_counted.load(), 10);
  EXPECT_EQ(alloc::allocations(), 0) << "over " << steps_counted.load() << " env steps";
}

// A team game (2v1, issue 79) through the episode player, as `pamdp train` and the actors play
// it: the network's output for each player, ε-greedy draws, demonstrations and labels by one
// scripted team player per player, each player's episode kept. Nothing allocates once built.
TEST(EpisodePlayerAllocations, ATeamGameAllocatesNothing) {
  hfo::SoccerSimConfig config;
  config.goalie = true;
  config.offense_agents = 2;
  hfo::HfoTeamEnv env(config);
  hfo::ScriptedTeamPlayer t0(1, 1);
  hfo::ScriptedTeamPlayer t1(1, 1);
  std::array<Policy*, 2> teachers{&t0, &t1};
  EpisodePlayer player(env, teachers, /*labels=*/true);
  ExplorationConfig x;
  EpsilonGreedy explore(env.action_space(), x, 5);
  Rng rng(7);
  const EpisodePlayer::Act act = [](std::span<const float> obs, std::span<float> out) {
    std::fill(out.begin(), out.end(), 0.0F);
    out[hfo::kDash] = obs[0];  // some output that depends on the observation
    out[hfo::kKick] = 0.5F;
  };
  player.begin(1, 0.5, rng);  // a first episode outside the count
  long allocations = 0;
  int steps = 0;
  {
    alloc::CountAllocations scope;
    for (int ep = 0; ep < 30; ++ep) {
      player.begin(static_cast<uint64_t>(ep), 0.5, rng);
      while (!player.ended()) {
        player.step(act, explore, 0.2);
        ++steps;
      }
    }
    allocations = scope.count();
  }
  EXPECT_GT(steps, 1000);
  EXPECT_EQ(allocations, 0) << "over " << steps << " cycles of a 2v1 game";
}

}  // namespace
}  // namespace pamdp::testing
