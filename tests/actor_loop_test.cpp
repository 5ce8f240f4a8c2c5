// actor/: the join handshake, the acting loop and its wire traffic against a fake learner and
// fake replay shards (tests/actor_harness.hpp), over loopback TCP with ports read back.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include "actor_harness.hpp"

namespace pamdp::testing {
namespace {

// All rows of the batches in sequence order (one shard, so arrival order is sequence order).
BatchCopy concat(const std::vector<BatchCopy>& batches) {
  BatchCopy all;
  for (const BatchCopy& b : batches) {
    all.count += b.count;
    all.states.insert(all.states.end(), b.states.begin(), b.states.end());
    all.next_states.insert(all.next_states.end(), b.next_states.begin(), b.next_states.end());
    all.actions.insert(all.actions.end(), b.actions.begin(), b.actions.end());
    all.rewards.insert(all.rewards.end(), b.rewards.begin(), b.rewards.end());
    all.returns.insert(all.returns.end(), b.returns.begin(), b.returns.end());
    all.terminals.insert(all.terminals.end(), b.terminals.begin(), b.terminals.end());
  }
  return all;
}

// The episodes in shipped rows, as [begin, end): contiguous runs ending in a terminal row.
std::vector<std::pair<size_t, size_t>> episodes_in(const BatchCopy& rows) {
  std::vector<std::pair<size_t, size_t>> episodes;
  size_t begin = 0;
  for (size_t t = 0; t < rows.count; ++t) {
    if (rows.terminals[t] != 0) {
      episodes.emplace_back(begin, t + 1);
      begin = t + 1;
    }
  }
  return episodes;
}

Bytes weights_message(uint64_t version, int64_t updates, uint8_t bound, const std::vector<float>& params,
                      std::span<const int> widths = kTestWidths, std::string_view algorithm = "ddpg",
                      std::string_view network = "actor") {
  flatbuffers::FlatBufferBuilder fbb;
  const NetworkView actor{network, widths, params};
  wire::build_policy_weights(fbb, version, updates, algorithm, bound, {&actor, 1});
  return copy_bytes(wire::bytes_of(fbb));
}

// PolicyWeights as learners before the algorithm seam wrote them: DDPG's actor in the message's
// own widths and params, no algorithm, no named networks.
Bytes older_weights_message(uint64_t version, int64_t updates, const std::vector<float>& params) {
  flatbuffers::FlatBufferBuilder fbb;
  const auto w = fbb.CreateVector(kTestWidths.data(), kTestWidths.size());
  const auto p = fbb.CreateVector(params);
  const auto weights = wire::CreatePolicyWeights(fbb, version, updates, w, 0, p);
  wire::FinishEnvelopeBuffer(
      fbb, wire::CreateEnvelope(fbb, wire::kSchemaVersion, wire::Payload::PolicyWeights, weights.Union()));
  return copy_bytes(wire::bytes_of(fbb));
}

// Publishes `msg` until the actor shows weights version `version` (PUB/SUB drops what is sent
// before the subscription is connected, so the first publication may be lost).
bool publish_until_applied(FakeLearner& learner, std::vector<FakeShard*> shards, ActorRunner& actor, const Bytes& msg,
                           int64_t version) {
  return serve_until(learner, std::move(shards), [&] {
    if (actor.counters.weights_version.load() >= version) {
      return true;
    }
    learner.publish(msg);
    return false;
  });
}

TEST(ActorLoop, JoinsAndShipsTransitionsWithMonteCarloReturnsAndEpisodeReports) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  learner.actor_index = 5;
  const ActorLoopConfig config = test_loop_config();
  ActorRunner actor(ctx, learner.join_endpoint(), config, /*envs=*/2);

  ASSERT_TRUE(
      serve_until(learner, {&shard}, [&] { return shard.batches.size() >= 20 && learner.reports.size() >= 50; }));
  EXPECT_EQ(shard.invalid, 0);
  ASSERT_GE(learner.joins.size(), 1U);
  EXPECT_EQ(learner.joins[0].role, wire::Role::Actor);
  EXPECT_EQ(learner.joins[0].name, "test-actor");
  EXPECT_EQ(learner.joins[0].actor_envs, 2U);
  EXPECT_TRUE(actor.running.load());
  EXPECT_EQ(actor.config_toml, kConfigToml);  // handed through to the caller untouched

  for (size_t i = 0; i < shard.batches.size(); ++i) {
    EXPECT_EQ(shard.batches[i].sequence, i);
    EXPECT_EQ(shard.batches[i].actor_id, 5U);
    // Each ended episode goes out at once: a batch holds up to 64 rows and ends at an episode's
    // end, a terminal row (ReachStop's episodes are shorter than a batch).
    const BatchCopy& b = shard.batches[i];
    ASSERT_GE(b.count, 1U);
    EXPECT_LE(b.count, 64U);
    EXPECT_EQ(b.terminals.back(), 1) << "batch " << i << " does not end at an episode's end";
  }

  // Episodes are contiguous runs of rows ending in a terminal row.
  const BatchCopy rows = concat(shard.batches);
  const auto gamma = static_cast<float>(config.gamma);
  const std::vector<std::pair<size_t, size_t>> episodes = episodes_in(rows);
  ASSERT_GE(episodes.size(), 30U);
  for (const auto& [b, e] : episodes) {
    ASSERT_LE(e - b, 20U) << "ReachStop ends every episode within max_steps = 20";
    // G_t = r_t + gamma * G_{t+1}; the terminal row's return is its reward.
    EXPECT_FLOAT_EQ(rows.returns[e - 1], rows.rewards[e - 1]);
    for (size_t t = b; t + 1 < e; ++t) {
      EXPECT_NEAR(rows.returns[t], rows.rewards[t] + gamma * rows.returns[t + 1], 1e-5);
      EXPECT_EQ(rows.terminals[t], 0);
      for (uint32_t k = 0; k < kObs; ++k) {
        EXPECT_EQ(rows.next_states[t * kObs + k], rows.states[(t + 1) * kObs + k]) << "row " << t;
      }
    }
  }
  // Without weights the actor acts at random (ε = 1): scores and velocity in [-1, 1], varied.
  float lo = 1.0F;
  float hi = -1.0F;
  for (const float a : rows.actions) {
    ASSERT_GE(a, -1.0F);
    ASSERT_LE(a, 1.0F);
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  EXPECT_LT(lo, -0.9F);
  EXPECT_GT(hi, 0.9F);
  EXPECT_EQ(actor.counters.weights_version.load(), 0);

  // Report k is about the k-th episode to end, which is the k-th episode in the shipped rows.
  // (Reports the join socket would not queue are dropped and counted: ReachStop ends thousands
  // of episodes a second, more than the fake learner reads.)
  size_t checked = 0;
  uint64_t last_episode = 0;
  for (const ReportCopy& r : learner.reports) {
    EXPECT_GT(r.episode, last_episode) << "reports arrive in order";
    last_episode = r.episode;
    if (r.episode > episodes.size()) {
      break;
    }
    const auto [b, e] = episodes[r.episode - 1];
    EXPECT_EQ(r.actor_id, 5U);
    EXPECT_EQ(r.steps, e - b);
    float sum = 0.0F;
    for (size_t t = b; t < e; ++t) {
      sum += rows.rewards[t];
    }
    EXPECT_NEAR(r.ret, sum, 1e-4);
    EXPECT_NE(r.status, 0);
    EXPECT_EQ(r.policy_version, 0U);
    ++checked;
  }
  EXPECT_GE(checked, 30U);
  EXPECT_EQ(learner.reports.front().episode, 1U);
  EXPECT_LE(static_cast<int64_t>(learner.reports.size()) + actor.counters.reports_dropped.load(),
            actor.counters.episodes.load());

  // Heartbeats carry the counters in the documented order.
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] {
    return learner.last_heartbeat_counters.size() == 7 && learner.last_heartbeat_counters[0] > 0;  // env_steps
  }));
  EXPECT_GT(learner.last_heartbeat_counters[1], 0);  // episodes
  EXPECT_GT(learner.last_heartbeat_counters[2], 0);  // batches_sent
  // transitions_sent: from 1 to 64 rows a batch, none of them from a step not yet played.
  EXPECT_GE(learner.last_heartbeat_counters[3], learner.last_heartbeat_counters[2]);
  EXPECT_LE(learner.last_heartbeat_counters[3], 64 * learner.last_heartbeat_counters[2]);
  EXPECT_LE(learner.last_heartbeat_counters[3], learner.last_heartbeat_counters[0]);
}

// Two ReachStop players in one game (Env::agents() = 2), each on its own observation, rewarded
// on its own; the game ends when player 0's episode ends (player 1's last row is terminal too).
class ReachStopPair final : public Env {
 public:
  [[nodiscard]] std::string_view name() const override { return "reach_stop_pair"; }
  [[nodiscard]] const ActionSpace& action_space() const override { return a_.action_space(); }
  [[nodiscard]] int observation_size() const override { return toy::ReachStopEnv::kObservationSize; }
  [[nodiscard]] int max_episode_steps() const override { return a_.max_episode_steps(); }
  [[nodiscard]] std::string_view status_name(int status) const override { return a_.status_name(status); }
  [[nodiscard]] std::span<const int> outcomes() const override { return a_.outcomes(); }
  [[nodiscard]] int success_status() const override { return a_.success_status(); }
  [[nodiscard]] int agents() const override { return 2; }
  void reset(uint64_t seed, std::span<float> obs) override {
    a_.reset(seed, obs.first(kObs));
    b_.reset(seed + 1, obs.subspan(kObs, kObs));
    b_over_ = false;
  }
  void reset(std::span<float> obs) override {
    a_.reset(obs.first(kObs));
    b_.reset(obs.subspan(kObs, kObs));
    b_over_ = false;
  }
  StepResult step(const ParamAction& /*action*/, std::span<float> /*obs*/) override {
    ADD_FAILURE() << "a team's step is step_team()";
    return {0.0F, toy::ReachStopEnv::kOutOfTime};
  }
  StepResult step_team(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards) override {
    const StepResult ra = a_.step(actions[0], obs.first(kObs));
    StepResult rb{0.0F, 0};
    if (!b_over_) {  // player 1 stands still once its own episode is over
      rb = b_.step(actions[1], obs.subspan(kObs, kObs));
      b_over_ = rb.terminal();
    }
    rewards[0] = ra.reward;
    rewards[1] = rb.reward;
    return {(ra.reward + rb.reward) / 2.0F, ra.status};
  }

 private:
  toy::ReachStopEnv a_, b_;
  bool b_over_ = false;
};

TEST(ActorLoop, ATeamShipsEachPlayersEpisodeAndReportsTheGameOnce) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  const ActorLoopConfig config = test_loop_config();
  ActorRunner actor(ctx, learner.join_endpoint(), config, /*envs=*/1, 2000, nullptr,
                    [] { return std::make_unique<ReachStopPair>(); });
  ASSERT_TRUE(
      serve_until(learner, {&shard}, [&] { return shard.batches.size() >= 20 && learner.reports.size() >= 20; }));
  EXPECT_EQ(shard.invalid, 0);
  // Each game is two episodes of equal length in a row (player 0's, then player 1's), each ending
  // in a terminal row, with its own returns.
  const BatchCopy rows = concat(shard.batches);
  const std::vector<std::pair<size_t, size_t>> episodes = episodes_in(rows);
  ASSERT_GE(episodes.size(), 20U);
  const auto gamma = static_cast<float>(config.gamma);
  for (size_t k = 0; k + 1 < episodes.size(); k += 2) {
    const auto [b0, e0] = episodes[k];
    const auto [b1, e1] = episodes[k + 1];
    ASSERT_EQ(e0 - b0, e1 - b1) << "game " << k / 2 << ": both players keep a row per cycle";
    for (size_t t = b1; t + 1 < e1; ++t) {
      EXPECT_NEAR(rows.returns[t], rows.rewards[t] + gamma * rows.returns[t + 1], 1e-5);
    }
  }
  // One report per game, with the game's steps and the players' mean return.
  size_t checked = 0;
  for (const ReportCopy& r : learner.reports) {
    if (2 * r.episode > episodes.size()) {
      break;
    }
    const auto [b0, e0] = episodes[2 * (r.episode - 1)];
    const auto [b1, e1] = episodes[2 * (r.episode - 1) + 1];
    EXPECT_EQ(r.steps, e0 - b0);
    float sum = 0.0F;
    for (size_t t = b0; t < e0; ++t) {
      sum += rows.rewards[t];
    }
    for (size_t t = b1; t < e1; ++t) {
      sum += rows.rewards[t];
    }
    EXPECT_NEAR(r.ret, sum / 2.0F, 1e-4);
    ++checked;
  }
  EXPECT_GE(checked, 5U);
  // A cycle is a decision of each player: env_steps counts both.
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] {
    return learner.last_heartbeat_counters.size() == 7 && learner.last_heartbeat_counters[0] > 0;
  }));
  EXPECT_EQ(actor.counters.env_steps.load() % 2, 0);
}

// A teacher that always moves at velocity 0.25: its ReachStop episodes run to the time limit.
class SlowMover final : public Policy {
 public:
  void begin_episode() override { ++episodes; }
  ParamAction act(std::span<const float> /*obs*/) override { return {toy::ReachStopEnv::kMove, params_}; }
  int episodes = 0;

 private:
  std::array<float, 1> params_{0.25F};
};

TEST(ActorLoop, PlaysDemonstrationsAndReportsThemAsScripted) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  ActorLoopConfig config = test_loop_config();
  config.exploration.demo_fraction = 0.5;
  config.make_teacher = [] { return std::make_unique<SlowMover>(); };
  ActorRunner actor(ctx, learner.join_endpoint(), config, /*envs=*/1);
  ASSERT_TRUE(
      serve_until(learner, {&shard}, [&] { return shard.batches.size() >= 40 && learner.reports.size() >= 60; }));

  const BatchCopy rows = concat(shard.batches);
  const std::vector<std::pair<size_t, size_t>> episodes = episodes_in(rows);
  // The teacher's rows: MOVE scored 1, STOP -1, its velocity.
  auto teachers_row = [&](size_t t) {
    return rows.actions[t * kWidth] == 1.0F && rows.actions[t * kWidth + 1] == -1.0F &&
           rows.actions[t * kWidth + 2] == 0.25F;
  };
  int scripted = 0;
  int agent = 0;
  for (const ReportCopy& r : learner.reports) {
    if (r.episode > episodes.size()) {
      break;
    }
    const auto [b, e] = episodes[r.episode - 1];
    bool all_teachers = true;
    for (size_t t = b; t < e; ++t) {
      all_teachers = all_teachers && teachers_row(t);
    }
    if (r.scripted) {
      ++scripted;
      EXPECT_TRUE(all_teachers) << "episode " << r.episode;
      EXPECT_EQ(r.steps, 20U);  // moving never ends an episode before the limit
      EXPECT_EQ(r.status, toy::ReachStopEnv::kOutOfTime);
      EXPECT_EQ(r.policy_version, 0U);
    } else {
      ++agent;
      EXPECT_FALSE(all_teachers) << "episode " << r.episode;
    }
  }
  // Half the episodes, drawn: both kinds, in about equal numbers.
  EXPECT_GE(scripted, 10);
  EXPECT_GE(agent, 10);
  // The actor's own episode metrics (on_episode) leave the demonstrations out.
  const int64_t agents = actor.agent_episodes.load();
  const int64_t all = actor.counters.episodes.load();
  EXPECT_GT(agents, all / 4);
  EXPECT_LT(agents, all * 3 / 4);
}

// Cloning: the demonstrations go to the demonstration table too, and with demo_relabel the
// agent's own steps go there with the teacher's action as their label, so every row of that table
// is the teacher's and it gets about as many rows as the replay table.
TEST(ActorLoop, FeedsTheDemonstrationTableWithDemonstrationsAndLabels) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  ActorLoopConfig config = test_loop_config();
  config.exploration.demo_fraction = 0.5;
  config.exploration.demo_relabel = true;
  config.demo_table = true;
  config.make_teacher = [] { return std::make_unique<SlowMover>(); };
  ActorRunner actor(ctx, learner.join_endpoint(), config, /*envs=*/2);
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return shard.batches.size() >= 60; }));

  size_t replay_rows = 0;
  size_t demo_rows = 0;
  size_t teacher_replay_rows = 0;
  for (const BatchCopy& b : shard.batches) {
    for (size_t t = 0; t < b.count; ++t) {
      const bool teachers =
          b.actions[t * kWidth] == 1.0F && b.actions[t * kWidth + 1] == -1.0F && b.actions[t * kWidth + 2] == 0.25F;
      if (b.table == wire::kDemoTable) {
        ++demo_rows;
        EXPECT_TRUE(teachers) << "a row of the demonstration table that is not the teacher's";
      } else {
        ASSERT_EQ(b.table, wire::kReplayTable);
        ++replay_rows;
        teacher_replay_rows += teachers ? 1 : 0;
      }
    }
  }
  EXPECT_GT(teacher_replay_rows, 0U);
  EXPECT_LT(teacher_replay_rows, replay_rows);
  // Every step is labelled or demonstrated once: the tables differ by the rows still unsent.
  EXPECT_NEAR(static_cast<double>(demo_rows), static_cast<double>(replay_rows), 3.0 * 64);
}

TEST(ActorLoop, AppliesPublishedWeightsAndActsWithThem) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  ActorLoopConfig config = test_loop_config();
  config.exploration.epsilon_start = 0.0;  // greedy once weights arrive
  config.exploration.epsilon_end = 0.0;
  ActorRunner actor(ctx, learner.join_endpoint(), config);

  const std::vector<float> out{0.5F, -0.5F, 0.25F};
  ASSERT_TRUE(
      publish_until_applied(learner, {&shard}, actor, weights_message(1, 100, 0, constant_output_params(out)), 1));
  // Rows of episodes that began before the weights may still be in the next two batches.
  const auto first_clean = static_cast<uint64_t>(actor.counters.batches_sent.load()) + 2;
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return shard.batches.size() >= first_clean + 3; }));
  for (size_t i = first_clean; i < shard.batches.size(); ++i) {
    const BatchCopy& b = shard.batches[i];
    for (uint32_t r = 0; r < b.count; ++r) {
      for (uint32_t k = 0; k < kWidth; ++k) {
        ASSERT_EQ(b.actions[r * kWidth + k], out[k]) << "batch " << i << " row " << r;
      }
    }
  }
  ASSERT_TRUE(serve_until(learner, {&shard},
                          [&] { return !learner.reports.empty() && learner.reports.back().policy_version == 1; }));

  // bound = 2 (squashing): the actor squashes as the learner does; every range here is [-1, 1].
  learner.publish(weights_message(2, 200, 2, constant_output_params(out)));
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return actor.counters.weights_version.load() == 2; }));
  const auto squashed_from = static_cast<uint64_t>(actor.counters.batches_sent.load()) + 2;
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return shard.batches.size() >= squashed_from + 2; }));
  const BatchCopy& b = shard.batches.back();
  for (uint32_t k = 0; k < kWidth; ++k) {
    EXPECT_NEAR(b.actions[k], std::tanh(out[k]), 1e-6);
  }

  // A message from a learner before the algorithm seam is played as DDPG's actor, unsquashed.
  const std::vector<float> later{-0.25F, 0.75F, 0.5F};
  learner.publish(older_weights_message(3, 300, constant_output_params(later)));
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return actor.counters.weights_version.load() == 3; }));
  const auto older_from = static_cast<uint64_t>(actor.counters.batches_sent.load()) + 2;
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return shard.batches.size() >= older_from + 2; }));
  for (uint32_t k = 0; k < kWidth; ++k) {
    EXPECT_EQ(shard.batches.back().actions[k], later[k]);
  }
}

// exploration.uniform_random_params = false: random steps play the network's parameters, so the
// actor takes no step before it has weights, and then every random step stores them.
TEST(ActorLoop, RandomStepsKeepThePoliciesParametersAndWaitForThem) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  ActorLoopConfig config = test_loop_config();
  config.exploration.epsilon_start = 1.0;  // every step random
  config.exploration.epsilon_end = 1.0;
  config.exploration.uniform_random_params = false;
  ActorRunner actor(ctx, learner.join_endpoint(), config);
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return !learner.joins.empty(); }));
  const auto waited_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  serve_until(learner, {&shard}, [&] { return std::chrono::steady_clock::now() >= waited_until; });
  EXPECT_EQ(actor.counters.env_steps.load(), 0) << "it stepped before it had the network's parameters";

  const std::vector<float> out{0.5F, -0.5F, 0.25F};
  ASSERT_TRUE(
      publish_until_applied(learner, {&shard}, actor, weights_message(1, 100, 0, constant_output_params(out)), 1));
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return shard.batches.size() >= 3; }));
  bool scores_vary = false;
  for (const BatchCopy& b : shard.batches) {
    for (uint32_t r = 0; r < b.count; ++r) {
      ASSERT_EQ(b.actions[r * kWidth + 2], out[2]) << "a random step drew its parameter";
      scores_vary = scores_vary || b.actions[r * kWidth] != out[0];
    }
  }
  EXPECT_TRUE(scores_vary) << "the scores were not drawn";
}

TEST(ActorLoop, DropsAndCountsMalformedMessagesAndKeepsActing) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  ActorRunner actor(ctx, learner.join_endpoint(), test_loop_config());
  const std::vector<float> good = constant_output_params({0.1F, 0.2F, 0.3F});
  ASSERT_TRUE(publish_until_applied(learner, {&shard}, actor, weights_message(1, 0, 0, good), 1));
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return !shard.identity.empty(); }));
  const int64_t before = actor.counters.malformed_messages.load();
  EXPECT_EQ(before, 0);

  // On the weights socket: seven bad messages, then good weights. One PUB connection is FIFO, so
  // once version 2 is applied all seven have been looked at.
  std::vector<float> nan_params = good;
  nan_params[3] = std::numeric_limits<float>::quiet_NaN();
  const std::array<int, 3> wrong_obs{5, 4, 3};
  const Bytes garbage{'n', 'o', 't', ' ', 'a', ' ', 'f', 'l', 'a', 't', 'b', 'u', 'f', 'f', 'e', 'r'};
  flatbuffers::FlatBufferBuilder fbb;
  wire::build_heartbeat(fbb, wire::Role::Learner, "learner", 1, {});
  const Bytes heartbeat = copy_bytes(wire::bytes_of(fbb));
  learner.publish(garbage);
  learner.publish(heartbeat);  // verified, but not weights
  learner.publish(weights_message(9, 0, 0, std::vector<float>(3 * 4 + 4 + 4 * 3 + 3), wrong_obs));
  learner.publish(weights_message(9, 0, 0, std::vector<float>(7, 0.0F)));  // wrong parameter count
  learner.publish(weights_message(9, 0, 0, nan_params));
  learner.publish(weights_message(9, 0, 0, good, kTestWidths, "no-such-learner"));  // no acting policy for it
  learner.publish(weights_message(9, 0, 0, good, kTestWidths, "ddpg", "critic"));   // not the network DDPG plays
  learner.publish(weights_message(2, 0, 0, good));
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return actor.counters.weights_version.load() == 2; }));
  EXPECT_EQ(actor.counters.malformed_messages.load(), before + 7);

  // On the join socket: garbage and a message type an actor never receives; on the shard's
  // socket: anything at all.
  learner.send_to_actor(garbage);
  wire::build_sample_request(fbb, 1, 32);
  learner.send_to_actor(wire::bytes_of(fbb));
  shard.send_to_actor(garbage);
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return actor.counters.malformed_messages.load() == before + 10; }));

  const int64_t steps = actor.counters.env_steps.load();
  const size_t batches = shard.batches.size();
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] {
    return actor.counters.env_steps.load() > steps + 1000 && shard.batches.size() > batches + 3;
  }));
  EXPECT_EQ(actor.counters.weights_version.load(), 2);
  EXPECT_EQ(shard.invalid, 0);
}

TEST(ActorLoop, StartsRoundRobinAtActorIndexModShards) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard0(ctx);
  FakeShard shard1(ctx);
  learner.shard_endpoints = {shard0.endpoint(), shard1.endpoint()};
  learner.actor_index = 3;
  ActorRunner actor(ctx, learner.join_endpoint(), test_loop_config());
  ASSERT_TRUE(serve_until(learner, {&shard0, &shard1},
                          [&] { return shard0.batches.size() >= 5 && shard1.batches.size() >= 5; }));
  for (const BatchCopy& b : shard1.batches) {
    EXPECT_EQ(b.sequence % 2, 0U) << "3 % 2 = 1: shard 1 gets batches 0, 2, 4, ...";
  }
  for (const BatchCopy& b : shard0.batches) {
    EXPECT_EQ(b.sequence % 2, 1U);
  }
}

TEST(ActorLoop, RejoinsWhenTheLearnersMapIsNewer) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard a(ctx);
  FakeShard b(ctx);
  learner.shard_endpoints = {a.endpoint()};
  ActorRunner actor(ctx, learner.join_endpoint(), test_loop_config());
  ASSERT_TRUE(serve_until(learner, {&a, &b}, [&] { return a.batches.size() >= 2; }));
  EXPECT_TRUE(b.batches.empty());

  // A shard joins: the learner's heartbeat answers now say version 2.
  learner.map_version = 2;
  learner.shard_endpoints = {a.endpoint(), b.endpoint()};
  ASSERT_TRUE(serve_until(learner, {&a, &b}, [&] { return b.batches.size() >= 2; }));
  ASSERT_EQ(learner.joins.size(), 2U);
  EXPECT_EQ(learner.joins[1].identity, learner.joins[0].identity) << "re-joins on the same socket";

  // Shard a is dropped: the actor disconnects it and sends to b only.
  learner.map_version = 3;
  learner.shard_endpoints = {b.endpoint()};
  ASSERT_TRUE(serve_until(learner, {&a, &b}, [&] { return learner.joins.size() == 3; }));
  // Batches already on their way to a may still land; after that, none.
  const size_t at_b = b.batches.size();
  ASSERT_TRUE(serve_until(learner, {&a, &b}, [&] { return b.batches.size() >= at_b + 50; }));
  const size_t at_a = a.batches.size();
  ASSERT_TRUE(serve_until(learner, {&a, &b}, [&] { return b.batches.size() >= at_b + 100; }));
  EXPECT_EQ(a.batches.size(), at_a);
  for (const BatchCopy& batch : b.batches) {
    EXPECT_EQ(batch.actor_id, 0U) << "the actor keeps its first index";
  }
}

TEST(ActorLoop, BackpressureFromAFullShardHoldsTheEnvLoop) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx, /*recv_hwm=*/1);
  shard.reading = false;
  learner.shard_endpoints = {shard.endpoint()};
  ActorLoopConfig config = test_loop_config();
  config.shard_send_hwm = 1;
  ActorRunner actor(ctx, learner.join_endpoint(), config);

  // Once the queues and the kernel buffers are full (blocked for a while), no step may happen.
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return actor.counters.send_blocked_ms.load() >= 500; }));
  const int64_t steps = actor.counters.env_steps.load();
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return actor.counters.send_blocked_ms.load() >= 900; }));
  EXPECT_EQ(actor.counters.env_steps.load(), steps) << "no steps while the only shard takes nothing";
  EXPECT_GT(learner.heartbeats, 5) << "heartbeats go on while blocked";

  shard.reading = true;
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return actor.counters.env_steps.load() > steps + 10000; }));
  EXPECT_EQ(shard.invalid, 0);
}

// Credit-based flow control: at most batches_in_flight batches unacknowledged per shard; an
// acknowledgement frees its batch and every earlier one; a lost connection (the shard restarted
// on the same endpoint) frees the batches that died with it.
TEST(ActorLoop, KeepsAtMostItsWindowUnacknowledgedPerShard) {
  net::Context ctx;
  FakeLearner learner(ctx);
  auto shard = std::make_unique<FakeShard>(ctx);
  shard->acking = false;
  const std::string endpoint = shard->endpoint();
  learner.shard_endpoints = {endpoint};
  ActorLoopConfig config = test_loop_config();
  config.batches_in_flight = 3;
  ActorRunner actor(ctx, learner.join_endpoint(), config);

  ASSERT_TRUE(serve_until(learner, {shard.get()}, [&] { return shard->batches.size() == 3; }));
  ASSERT_TRUE(serve_until(learner, {shard.get()}, [&] { return actor.counters.send_blocked_ms.load() >= 100; }));
  const int64_t steps = actor.counters.env_steps.load();
  ASSERT_TRUE(serve_until(learner, {shard.get()}, [&] { return actor.counters.send_blocked_ms.load() >= 250; }));
  EXPECT_EQ(shard->batches.size(), 3U) << "sent past its window";
  EXPECT_EQ(actor.counters.env_steps.load(), steps) << "stepped with a full window";

  shard->ack(shard->batches[1].sequence);  // frees the first two
  ASSERT_TRUE(serve_until(learner, {shard.get()}, [&] { return shard->batches.size() == 5; }));
  EXPECT_EQ(actor.counters.batches_acknowledged.load(), 2);
  ASSERT_TRUE(serve_until(learner, {shard.get()}, [&] { return actor.counters.send_blocked_ms.load() >= 400; }));
  EXPECT_EQ(shard->batches.size(), 5U) << "sent past its window";

  // The shard restarts on the same endpoint (the learner's map does not change) and acknowledges
  // what it reads: the three batches the old one held are lost, and sending goes on.
  shard.reset();
  for (int attempt = 0; shard == nullptr; ++attempt) {
    try {
      shard = std::make_unique<FakeShard>(ctx, 1000, endpoint);
    } catch (const std::runtime_error&) {  // ZeroMQ frees the port on its I/O thread, soon after
      ASSERT_LT(attempt, 200) << "the old shard's port stayed in use";
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  ASSERT_TRUE(serve_until(learner, {shard.get()}, [&] { return shard->batches.size() >= 50; }));
  EXPECT_EQ(actor.counters.batches_lost.load(), 3);
  EXPECT_GE(actor.counters.batches_acknowledged.load(), 2 + 50 - 3) << "the new shard acknowledged all but a window";
  EXPECT_EQ(shard->invalid, 0);
}

TEST(ActorLoop, SkipsAShardThatIsGone) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard live(ctx);
  std::string dead_endpoint;
  {
    FakeShard dead(ctx);  // bound, then closed: nothing listens there any more
    dead_endpoint = dead.endpoint();
  }
  learner.shard_endpoints = {dead_endpoint, live.endpoint()};  // actor 0 starts with the dead one
  ActorLoopConfig config = test_loop_config();
  config.peer_timeout_ms = 300;
  config.shard_send_hwm = 1;
  ActorRunner actor(ctx, learner.join_endpoint(), config);
  ASSERT_TRUE(serve_until(learner, {&live}, [&] { return live.batches.size() >= 10; }));
  EXPECT_GE(actor.counters.send_blocked_ms.load(), 250);
}

TEST(ActorLoop, JoinRetriesOnAFreshSocketWhenTheLearnerDoesNotAnswer) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  learner.ignore_joins = 1;
  ActorRunner actor(ctx, learner.join_endpoint(), test_loop_config(), 1, /*join_retry_ms=*/200);
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] { return !shard.batches.empty(); }));
  ASSERT_EQ(learner.joins.size(), 2U);
  EXPECT_NE(learner.joins[0].identity, learner.joins[1].identity);
}

TEST(LearnerLink, JoinGivesUpAfterItsTimeout) {
  net::Context ctx;
  // A bound socket that never answers a join. It holds its port for the whole test: a port
  // closed and left free could be taken by a learner of a test running beside this one, which
  // would answer (a fresh clone's ctest -j2 once joined one that way).
  FakeShard silent(ctx);
  LearnerLinkConfig c;
  c.join_endpoint = silent.endpoint();
  c.name = "test";
  c.join_retry_ms = 100;
  c.join_timeout_ms = 300;
  LearnerLink link(ctx, c);
  std::atomic<bool> stop{false};
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(link.join(stop).has_value());
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(s, 0.25);
  EXPECT_LT(s, 1.5);
  stop = true;
  EXPECT_FALSE(link.join(stop).has_value()) << "returns at once when stopped";
}

TEST(ActorLoop, RejectsAnEmptyEnvListAndBadSettings) {
  net::Context ctx;
  ClusterInfo map;
  map.weights_endpoint = "tcp://127.0.0.1:1";
  ActorCounters counters;
  const auto make = [&](ActorLoopConfig config, std::vector<std::unique_ptr<Env>> envs) {
    LearnerLinkConfig lc;
    lc.join_endpoint = "tcp://127.0.0.1:1";
    ActorLoop loop(ctx, LearnerLink(ctx, lc), map, std::move(envs), std::move(config), counters);
  };
  EXPECT_THROW(make(test_loop_config(), {}), std::invalid_argument);
  ActorLoopConfig bad = test_loop_config();
  bad.batch_transitions = 0;
  std::vector<std::unique_ptr<Env>> one;
  one.push_back(std::make_unique<toy::ReachStopEnv>());
  EXPECT_THROW(make(bad, std::move(one)), std::invalid_argument);
  // Demonstrations without a teacher, labels without the demonstration table.
  ActorLoopConfig no_teacher = test_loop_config();
  no_teacher.exploration.demo_fraction = 0.5;
  std::vector<std::unique_ptr<Env>> two;
  two.push_back(std::make_unique<toy::ReachStopEnv>());
  EXPECT_THROW(make(no_teacher, std::move(two)), std::invalid_argument);
  ActorLoopConfig no_table = test_loop_config();
  no_table.exploration.demo_fraction = 0.5;
  no_table.exploration.demo_relabel = true;
  no_table.make_teacher = [] { return std::make_unique<SlowMover>(); };
  std::vector<std::unique_ptr<Env>> three;
  three.push_back(std::make_unique<toy::ReachStopEnv>());
  EXPECT_THROW(make(no_table, std::move(three)), std::invalid_argument);
}

}  // namespace
}  // namespace pamdp::testing
