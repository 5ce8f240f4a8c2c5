// VectorEnv (python/vector_env.hpp) without Python: results do not depend on the thread count,
// next-step and same-step autoreset agree with plain envs, and a step allocates nothing.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "core/rng.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "python/vector_env.hpp"
#include "tests/counting_new.hpp"

namespace pamdp::python {
namespace {

constexpr int kTimeout = hfo::kOutOfTime;

std::vector<std::unique_ptr<Env>> hfo_envs(int n) {
  std::vector<std::unique_ptr<Env>> envs;
  for (int i = 0; i < n; ++i) {
    envs.push_back(std::make_unique<hfo::HfoEnv>(hfo::SoccerSimConfig{.goalie = true}));
  }
  return envs;
}

// n 2v1 games (two learned players against agent2d's goalie).
std::vector<std::unique_ptr<Env>> team_envs(int n) {
  std::vector<std::unique_ptr<Env>> envs;
  for (int i = 0; i < n; ++i) {
    envs.push_back(std::make_unique<hfo::HfoTeamEnv>(hfo::SoccerSimConfig{.goalie = true, .offense_agents = 2}));
  }
  return envs;
}

// Everything a vector env writes, owned here as the NumPy arrays are in the module.
struct Batch {
  Batch(int n, int obs_size, bool same_step, int agents = 1)
      : obs(static_cast<size_t>(n * agents * obs_size)),
        reward(static_cast<size_t>(n * agents)),
        terminated(static_cast<size_t>(n)),
        truncated(static_cast<size_t>(n)),
        status(static_cast<size_t>(n)),
        final_obs(same_step ? obs.size() : 0),
        has_final(same_step ? static_cast<size_t>(n) : 0) {}
  VectorBuffers buffers() { return {obs, reward, terminated, truncated, status, final_obs, has_final}; }

  std::vector<float> obs, reward;
  std::vector<uint8_t> terminated, truncated;
  std::vector<int32_t> status;
  std::vector<float> final_obs;
  std::vector<uint8_t> has_final;
};

// Random ids and parameters for n envs (HFO's six parameters, out of bounds too).
void draw(Rng& rng, std::vector<int>& ids, std::vector<float>& params) {
  for (int& id : ids) {
    id = static_cast<int>(rng.next_u64() % 4);
  }
  for (float& p : params) {
    p = static_cast<float>(rng.uniform(-200.0, 200.0));
  }
}

TEST(VectorEnv, ThreadCountChangesNothing) {
  for (const AutoReset mode : {AutoReset::kNextStep, AutoReset::kSameStep}) {
    constexpr int kN = 11;
    VectorEnv one(hfo_envs(kN), 1, mode, kTimeout);
    VectorEnv four(hfo_envs(kN), 4, mode, kTimeout);
    ASSERT_EQ(four.num_threads(), 4);
    const bool same = mode == AutoReset::kSameStep;
    Batch a(kN, one.observation_size(), same);
    Batch b(kN, one.observation_size(), same);
    std::vector<uint64_t> seeds;
    for (int i = 0; i < kN; ++i) {
      seeds.push_back(100 + static_cast<uint64_t>(i));
    }
    one.reset(seeds, a.buffers());
    four.reset(seeds, b.buffers());
    Rng rng(3);
    std::vector<int> ids(kN);
    std::vector<float> params(kN * 6);
    int episodes = 0;
    for (int step = 0; step < 600; ++step) {
      draw(rng, ids, params);
      one.step(ids, params, a.buffers());
      four.step(ids, params, b.buffers());
      ASSERT_EQ(a.obs, b.obs) << "step " << step;
      ASSERT_EQ(a.reward, b.reward);
      ASSERT_EQ(a.status, b.status);
      ASSERT_EQ(a.terminated, b.terminated);
      ASSERT_EQ(a.truncated, b.truncated);
      ASSERT_EQ(a.final_obs, b.final_obs);
      for (int i = 0; i < kN; ++i) {
        episodes += a.status[static_cast<size_t>(i)] != 0 ? 1 : 0;
        EXPECT_EQ(a.truncated[static_cast<size_t>(i)] != 0, a.status[static_cast<size_t>(i)] == kTimeout);
      }
    }
    EXPECT_GT(episodes, kN);
  }
}

TEST(VectorEnv, MatchesPlainEnvs) {
  constexpr int kN = 5;
  VectorEnv vec(hfo_envs(kN), 2, AutoReset::kNextStep, kTimeout);
  auto plain = hfo_envs(kN);
  Batch batch(kN, vec.observation_size(), false);
  const std::vector<uint64_t> seeds{7, 8, 9, 10, 11};
  vec.reset(seeds, batch.buffers());
  const auto width = static_cast<size_t>(vec.observation_size());
  std::vector<float> obs(width);
  std::vector<bool> pending(kN, false);
  for (int i = 0; i < kN; ++i) {
    plain[static_cast<size_t>(i)]->reset(seeds[static_cast<size_t>(i)], obs);
  }
  Rng rng(5);
  std::vector<int> ids(kN);
  std::vector<float> params(kN * 6);
  for (int step = 0; step < 400; ++step) {
    draw(rng, ids, params);
    vec.step(ids, params, batch.buffers());
    for (size_t i = 0; i < kN; ++i) {
      Env& env = *plain[i];
      if (pending[i]) {  // next-step autoreset: this step started the next episode
        env.reset(obs);
        pending[i] = false;
        EXPECT_EQ(batch.reward[i], 0.0F);
        EXPECT_EQ(batch.status[i], 0);
      } else {
        const StepResult r = env.step({ids[i], std::span<const float>(params).subspan(i * 6, 6)}, obs);
        EXPECT_EQ(batch.reward[i], r.reward);
        EXPECT_EQ(batch.status[i], r.status);
        pending[i] = r.terminal();
      }
      ASSERT_TRUE(std::equal(obs.begin(), obs.end(), batch.obs.begin() + static_cast<std::ptrdiff_t>(i * width)))
          << "env " << i << " step " << step;
    }
  }
}

// Allocations in 300 steps of a warmed-up vector env over `envs` (agents() players each).
int64_t step_allocations(std::vector<std::unique_ptr<Env>> envs, int threads, AutoReset mode) {
  const int n = static_cast<int>(envs.size());
  VectorEnv vec(std::move(envs), threads, mode, kTimeout);
  const int rows = n * vec.agents();
  Batch batch(n, vec.observation_size(), mode == AutoReset::kSameStep, vec.agents());
  vec.reset({}, batch.buffers());
  Rng rng(1);
  std::vector<int> ids(static_cast<size_t>(rows));
  std::vector<float> params(static_cast<size_t>(rows) * 6);
  draw(rng, ids, params);
  vec.step(ids, params, batch.buffers());  // warm up
  testing::alloc::CountAllocations counter;
  for (int step = 0; step < 300; ++step) {
    draw(rng, ids, params);
    vec.step(ids, params, batch.buffers());
  }
  return counter.count();
}

TEST(VectorEnv, StepAllocatesNothing) {
  for (const int threads : {1, 3}) {
    for (const AutoReset mode : {AutoReset::kNextStep, AutoReset::kSameStep}) {
      EXPECT_EQ(step_allocations(hfo_envs(8), threads, mode), 0) << threads << " threads";
    }
  }
}

// A team vector env: game i's players take rows i * A .. i * A + A - 1 of the actions, and every
// game plays as a plain team env stepped with step_team, obs and rewards player-major.
TEST(VectorEnv, ATeamMatchesPlainTeamGames) {
  constexpr int kN = 3;
  constexpr int kA = 2;
  VectorEnv vec(team_envs(kN), 2, AutoReset::kNextStep, kTimeout);
  ASSERT_EQ(vec.agents(), kA);
  auto plain = team_envs(kN);
  Batch batch(kN, vec.observation_size(), false, kA);
  const std::vector<uint64_t> seeds{3, 4, 5};
  vec.reset(seeds, batch.buffers());
  const auto width = static_cast<size_t>(vec.observation_size()) * kA;
  std::vector<float> obs(width);
  std::vector<float> rewards(kA);
  std::vector<bool> pending(kN, false);
  for (size_t i = 0; i < kN; ++i) {
    plain[i]->reset(seeds[i], obs);
    ASSERT_TRUE(std::equal(obs.begin(), obs.end(), batch.obs.begin() + static_cast<std::ptrdiff_t>(i * width)));
  }
  Rng rng(11);
  std::vector<int> ids(kN * kA);
  std::vector<float> params(kN * kA * 6);
  std::vector<ParamAction> actions(kA);
  int ends = 0;
  for (int step = 0; step < 600; ++step) {
    draw(rng, ids, params);
    vec.step(ids, params, batch.buffers());
    for (size_t i = 0; i < kN; ++i) {
      Env& env = *plain[i];
      if (pending[i]) {
        env.reset(obs);
        pending[i] = false;
        EXPECT_EQ(batch.reward[i * kA], 0.0F);
        EXPECT_EQ(batch.reward[i * kA + 1], 0.0F);
        EXPECT_EQ(batch.status[i], 0);
      } else {
        for (size_t a = 0; a < kA; ++a) {
          actions[a] = {ids[i * kA + a], std::span<const float>(params).subspan((i * kA + a) * 6, 6)};
        }
        const StepResult r = env.step_team(actions, obs, rewards);
        EXPECT_EQ(batch.reward[i * kA], rewards[0]);
        EXPECT_EQ(batch.reward[i * kA + 1], rewards[1]);
        EXPECT_EQ(batch.status[i], r.status);
        EXPECT_EQ(batch.truncated[i], r.status == kTimeout ? 1 : 0);
        EXPECT_EQ(batch.terminated[i], r.terminal() && r.status != kTimeout ? 1 : 0);
        pending[i] = r.terminal();
        ends += r.terminal() ? 1 : 0;
      }
      ASSERT_TRUE(std::equal(obs.begin(), obs.end(), batch.obs.begin() + static_cast<std::ptrdiff_t>(i * width)))
          << "game " << i << " step " << step;
    }
  }
  EXPECT_GT(ends, 3) << "the games must end and restart for the test to check autoreset";
}

TEST(VectorEnv, ATeamStepAllocatesNothing) {
  for (const AutoReset mode : {AutoReset::kNextStep, AutoReset::kSameStep}) {
    EXPECT_EQ(step_allocations(team_envs(4), 2, mode), 0);
  }
}

TEST(VectorEnv, RefusesEnvsOfDifferentTeamSizes) {
  std::vector<std::unique_ptr<Env>> envs = team_envs(1);
  envs.push_back(std::make_unique<hfo::HfoEnv>(hfo::SoccerSimConfig{.goalie = true}));
  EXPECT_THROW(VectorEnv(std::move(envs), 1, AutoReset::kNextStep, kTimeout), std::invalid_argument);
}

}  // namespace
}  // namespace pamdp::python
