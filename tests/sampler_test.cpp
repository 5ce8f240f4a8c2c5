// LocalSampler: the in-process side of the run's one sampling seam (learner/sampler.hpp). Its
// draws must be the replay buffer's own, in the order `pamdp train` always drew them, so a seeded
// run keeps its metrics; update_from() updates exactly once per batch it gets.
#include "learner/sampler.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "envs/toy/reach_stop.hpp"
#include "learner/ddpg_algorithm.hpp"

namespace pamdp {
namespace {

constexpr int kObs = 3;
constexpr int kAct = 2;
constexpr int kBatch = 4;

// Transition i holds the value `base + i` in every field, so a column tells which one it is.
void fill(ReplayBuffer& r, int n, float base) {
  std::vector<float> s(kObs);
  std::vector<float> a(kAct);
  for (int i = 0; i < n; ++i) {
    const float v = base + static_cast<float>(i);
    std::fill(s.begin(), s.end(), v);
    std::fill(a.begin(), a.end(), v);
    r.insert({s, a, v, s, i % 2 == 0, v});
  }
}

// The columns' first state entries: which transitions a batch holds.
std::vector<float> picked(const BatchView& b) {
  std::vector<float> out;
  for (Eigen::Index j = 0; j < b.states.cols(); ++j) {
    out.push_back(b.states(0, j));
  }
  return out;
}

TEST(LocalSampler, NothingBelowWarmUpAndNoDrawFromTheStream) {
  ReplayBuffer replay(100, kObs, kAct);
  fill(replay, 9, 0.0F);
  Rng rng(11);
  const auto before = rng.state();
  LocalSampler sampler(replay, nullptr, rng, kBatch, 10);
  EXPECT_EQ(sampler.next(), nullptr);
  EXPECT_EQ(rng.state(), before);
  fill(replay, 1, 9.0F);
  ASSERT_NE(sampler.next(), nullptr);
  EXPECT_NE(rng.state(), before);
}

TEST(LocalSampler, DrawsWhatTheReplayBufferDrawsThenTheDemonstrations) {
  ReplayBuffer replay(100, kObs, kAct);
  ReplayBuffer demos(100, kObs, kAct);
  fill(replay, 20, 0.0F);
  Rng rng(5);
  Rng reference(5);
  BatchBuffers expected(kObs, kAct, kBatch);
  BatchBuffers expected_demos(kObs, kAct, kBatch);
  LocalSampler sampler(replay, &demos, rng, kBatch, 1);

  // No demonstrations yet: the batch alone, and no draw for the empty table.
  const Sample* s = sampler.next();
  ASSERT_NE(s, nullptr);
  replay.sample(reference, kBatch, expected);
  EXPECT_EQ(picked(*s->batch), picked(view_of(expected, kBatch)));
  EXPECT_FALSE(s->demos.has_value());
  EXPECT_EQ(rng.state(), reference.state());

  // With demonstrations (values from 100 on): the batch, then the demonstrations, one stream.
  fill(demos, 6, 100.0F);
  for (int k = 0; k < 3; ++k) {
    s = sampler.next();
    ASSERT_NE(s, nullptr);
    replay.sample(reference, kBatch, expected);
    demos.sample(reference, kBatch, expected_demos);
    EXPECT_EQ(picked(*s->batch), picked(view_of(expected, kBatch)));
    ASSERT_TRUE(s->demos.has_value());
    EXPECT_EQ(picked(*s->demos), picked(view_of(expected_demos, kBatch)));
    for (const float v : picked(*s->demos)) {
      EXPECT_GE(v, 100.0F);
    }
    // Every field of a column is the same transition's.
    for (Eigen::Index j = 0; j < kBatch; ++j) {
      const float v = s->batch->states(0, j);
      EXPECT_EQ(s->batch->actions(1, j), v);
      EXPECT_EQ(s->batch->rewards(j), v);
      EXPECT_EQ(s->batch->next_states(2, j), v);
      EXPECT_EQ(s->batch->mc_returns(j), v);
      EXPECT_EQ(s->batch->terminal(j), static_cast<int>(v) % 2 == 0 ? 1.0F : 0.0F);
    }
  }
  EXPECT_EQ(rng.state(), reference.state());
}

TEST(UpdateFrom, OneUpdatePerBatchAndNoneWithoutOne) {
  toy::ReachStopEnv env;
  DdpgConfig config;
  config.hidden = {8};
  config.batch_size = kBatch;
  DdpgAlgorithm ddpg(env.observation_size(), env.action_space(), config, 3, UpdateDevice::kCpu);
  const int width = env.action_space().output_width();
  ReplayBuffer replay(100, env.observation_size(), width);
  Rng rng(2);
  LocalSampler sampler(replay, nullptr, rng, kBatch, 5);
  EXPECT_FALSE(update_from(sampler, ddpg).has_value());
  EXPECT_EQ(ddpg.updates(), 0);
  std::vector<float> s(static_cast<size_t>(env.observation_size()), 0.5F);
  std::vector<float> a(static_cast<size_t>(width), 0.1F);
  for (int i = 0; i < 5; ++i) {
    replay.insert({s, a, 1.0F, s, true, 1.0F});
  }
  for (int i = 1; i <= 3; ++i) {
    const std::optional<UpdateStats> stats = update_from(sampler, ddpg);
    ASSERT_TRUE(stats.has_value());
    EXPECT_EQ(ddpg.updates(), i);
  }
}

}  // namespace
}  // namespace pamdp
