// The one episode path (actor/episode_player.hpp) that `pamdp train` and the actors share: what it
// plays, what it keeps, when it asks the policy, and where the teacher plays or labels.
#include "actor/episode_player.hpp"

#include <gtest/gtest.h>

#include <array>
#include <stdexcept>
#include <utility>
#include <vector>

#include "envs/toy/reach_stop.hpp"

namespace pamdp {
namespace {

using toy::ReachStopEnv;

// Output vectors of the toy task: scores of MOVE and STOP, then the velocity.
constexpr size_t kWidth = 3;

// A policy output that always moves at velocity v; counts its calls.
struct Mover {
  float v = 0.5F;
  int calls = 0;
  EpisodePlayer::Act act() {
    return [this](std::span<const float> /*obs*/, std::span<float> out) {
      ++calls;
      out[0] = 1.0F;
      out[1] = -1.0F;
      out[2] = v;
    };
  }
};

// A teacher that stops at once.
class Stopper final : public Policy {
 public:
  void begin_episode() override { ++episodes; }
  ParamAction act(std::span<const float> /*obs*/) override { return {ReachStopEnv::kStop, params_}; }
  int episodes = 0;

 private:
  std::array<float, 1> params_{0.0F};
};

ExplorationConfig greedy_config() {
  ExplorationConfig c;
  c.uniform_random_params = true;
  return c;
}

TEST(EpisodePlayer, KeepsEachStepAsTheEnvPlaysIt) {
  ReachStopEnv env({}, 0);
  ReachStopEnv twin({}, 0);
  EpisodePlayer player(env, nullptr, false);
  EpsilonGreedy explore(env.action_space(), greedy_config(), 1);
  Rng rng(9);
  Mover mover;
  const EpisodePlayer::Act act = mover.act();

  player.begin(42, 0.0, rng);
  int status = 0;
  while (!player.ended()) {
    status = player.step(act, explore, 0.0).status;
  }
  // MOVE never ends an episode: it runs to the time limit, one policy call a step.
  EXPECT_EQ(status, ReachStopEnv::kOutOfTime);
  EXPECT_EQ(player.steps(), 20);
  EXPECT_EQ(mover.calls, 20);
  EXPECT_FALSE(player.demo());
  EXPECT_EQ(player.labels(), nullptr);

  // The same seed and actions through a second env give the kept transitions.
  EpisodeBuffer& ep = player.episode();
  ASSERT_EQ(ep.size(), 20U);
  ep.compute_returns(0.9);
  std::vector<float> obs(3);
  std::vector<float> next(3);
  twin.reset(42, obs);
  const std::array<float, 1> v{0.5F};
  float total = 0.0F;
  for (size_t i = 0; i < ep.size(); ++i) {
    const TransitionView t = ep.transition(i);
    const StepResult sr = twin.step({ReachStopEnv::kMove, v}, next);
    EXPECT_EQ(std::vector<float>(t.state.begin(), t.state.end()), obs) << "step " << i;
    EXPECT_EQ(std::vector<float>(t.next_state.begin(), t.next_state.end()), next) << "step " << i;
    EXPECT_EQ(std::vector<float>(t.action.begin(), t.action.end()), (std::vector<float>{1.0F, -1.0F, 0.5F}));
    EXPECT_EQ(t.reward, sr.reward);
    EXPECT_EQ(t.terminal, i + 1 == ep.size());
    total += sr.reward;
    std::swap(obs, next);
  }
  EXPECT_EQ(player.episode_return(), total);

  // The next episode starts empty.
  player.begin(43, 0.0, rng);
  EXPECT_FALSE(player.ended());
  EXPECT_EQ(player.steps(), 0);
  EXPECT_EQ(player.episode().size(), 0U);
  EXPECT_EQ(player.episode_return(), 0.0F);
}

TEST(EpisodePlayer, AsksThePolicyOnlyWhereItsOutputIsUsed) {
  ReachStopEnv env({}, 0);
  EpisodePlayer player(env, nullptr, false);
  Rng rng(9);
  Mover mover;
  const EpisodePlayer::Act act = mover.act();

  // ε = 1 with uniform random parameters: every step is a random draw, the output is never read.
  EpsilonGreedy uniform(env.action_space(), greedy_config(), 1);
  for (int e = 0; e < 5; ++e) {
    player.begin(static_cast<uint64_t>(e), 0.0, rng);
    while (!player.ended()) {
      player.step(act, uniform, 1.0);
    }
  }
  EXPECT_EQ(mover.calls, 0);

  // Random steps that keep the network's parameters read it at ε = 1 too.
  ExplorationConfig keep = greedy_config();
  keep.uniform_random_params = false;
  EpsilonGreedy keeping(env.action_space(), keep, 1);
  player.begin(7, 0.0, rng);
  player.step(act, keeping, 1.0);
  EXPECT_EQ(mover.calls, 1);
  EXPECT_EQ(player.episode().transition(0).action[2], 0.5F);  // the network's velocity, kept

  // No policy yet (an actor before its first weights): random steps still play.
  player.begin(8, 0.0, rng);
  player.step(EpisodePlayer::Act{}, uniform, 1.0);
  EXPECT_EQ(player.steps(), 1);
}

TEST(EpisodePlayer, TheTeacherPlaysDemonstrationsAndLabelsTheAgentsSteps) {
  ReachStopEnv env({}, 0);
  Stopper teacher;
  EpisodePlayer player(env, &teacher, /*labels=*/true);
  EpsilonGreedy explore(env.action_space(), greedy_config(), 1);
  Rng rng(9);
  Mover mover;
  const EpisodePlayer::Act act = mover.act();

  // A demonstration: the teacher's STOP, stored as score 1 for it and -1 for MOVE, MOVE's
  // velocity from the network; nothing to label.
  player.begin(1, 1.0, rng);
  ASSERT_TRUE(player.demo());
  EXPECT_EQ(teacher.episodes, 1);
  player.step(act, explore, 0.0);
  ASSERT_TRUE(player.ended());  // STOP ends the episode
  EXPECT_EQ(player.labels(), nullptr);
  const TransitionView d = player.episode().transition(0);
  EXPECT_EQ(std::vector<float>(d.action.begin(), d.action.end()), (std::vector<float>{-1.0F, 1.0F, 0.5F}));

  // The agent's episode: it moves, the teacher's STOP is its label for the same states.
  player.begin(2, 0.0, rng);
  ASSERT_FALSE(player.demo());
  EXPECT_EQ(teacher.episodes, 2);
  for (int i = 0; i < 3; ++i) {
    player.step(act, explore, 0.0);
  }
  ASSERT_NE(player.labels(), nullptr);
  ASSERT_EQ(player.labels()->size(), 3U);
  for (size_t i = 0; i < 3; ++i) {
    const TransitionView a = player.episode().transition(i);
    const TransitionView l = player.labels()->transition(i);
    EXPECT_EQ(std::vector<float>(a.state.begin(), a.state.end()), std::vector<float>(l.state.begin(), l.state.end()));
    EXPECT_EQ(a.reward, l.reward);
    EXPECT_EQ(a.action[0], 1.0F);  // the agent moved
    EXPECT_EQ(l.action[1], 1.0F);  // the teacher would have stopped
  }
}

TEST(EpisodePlayer, DrawsFromTheStreamOnlyWithDemonstrations) {
  ReachStopEnv env({}, 0);
  Stopper teacher;
  EpisodePlayer player(env, &teacher, false);
  Rng rng(9);
  const auto before = rng.state();
  player.begin(1, 0.0, rng);
  EXPECT_EQ(rng.state(), before);
  EXPECT_EQ(teacher.episodes, 0);
  player.begin(1, 0.5, rng);
  EXPECT_NE(rng.state(), before);
}

TEST(EpisodePlayer, RefusesDemonstrationsAndLabelsWithoutATeacher) {
  ReachStopEnv env({}, 0);
  EXPECT_THROW(EpisodePlayer(env, nullptr, true), std::invalid_argument);
  EpisodePlayer player(env, nullptr, false);
  Rng rng(9);
  EXPECT_THROW(player.begin(1, 1.0, rng), std::logic_error);
}

}  // namespace
}  // namespace pamdp
