// A team game through the paths that train and judge policies (issue 79): the registry's hfo env
// with env.offense_agents = N, the episode player that `pamdp train` and the actors share, and the
// evaluation. Each is checked against the team env played by hand, step by step.
#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <vector>

#include "actor/episode_player.hpp"
#include "actor/exploration.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/scripted_team.hpp"
#include "envs/registry.hpp"
#include "learner/evaluation.hpp"

namespace pamdp {
namespace {

using hfo::HfoTeamEnv;
using hfo::ScriptedTeamPlayer;

EnvParams team_params(int agents, bool goalie) {
  EnvParams p = env_registry().defaults();
  p.set("offense_agents", int64_t{agents});
  p.set("goalie", goalie);
  return p;
}

TEST(TeamGame, TheHfoEnvWithSeveralAgentsIsATeam) {
  const EnvRegistration& r = env_registry().find("hfo");
  const auto one = r.make(team_params(1, true));
  EXPECT_EQ(one->agents(), 1);
  EXPECT_EQ(one->observation_size(), 66);
  const auto two = r.make(team_params(2, true));
  EXPECT_EQ(two->agents(), 2);
  EXPECT_EQ(two->observation_size(), 74);  // 58 + 8 for the teammate + 8 for the goalie
  EXPECT_EQ(r.observation_size(team_params(2, true)), 74);
  const auto four = r.make(team_params(4, false));
  EXPECT_EQ(four->agents(), 4);
  EXPECT_EQ(four->observation_size(), 58 + 3 * 8);
  EXPECT_EQ(r.observation_size(team_params(4, false)), 58 + 3 * 8);
  EXPECT_TRUE(env_registry().reads("hfo-server", "offense_agents"));
}

// Scores and parameters that make every player dash at full power straight ahead.
void dash_output(std::span<const float> /*obs*/, std::span<float> out) {
  std::fill(out.begin(), out.end(), 0.0F);
  out[hfo::kDash] = 1.0F;
  out[hfo::hfo_action_space().num_actions() + hfo::param::kDashPower] = 100.0F;
}

TEST(TeamGame, TheEpisodePlayerKeepsEachPlayersOwnTransitions) {
  hfo::SoccerSimConfig c;
  c.offense_agents = 2;
  HfoTeamEnv env(c);
  HfoTeamEnv twin(c);
  const auto obs_dim = static_cast<size_t>(env.observation_size());
  EpisodePlayer player(env, nullptr, false);
  ASSERT_EQ(player.players(), 2);
  ExplorationConfig x;
  EpsilonGreedy explore(env.action_space(), x, 1);
  Rng rng(3);
  player.begin(11, 0.0, rng);
  std::vector<float> obs(2 * obs_dim);
  twin.reset(11, obs);
  std::array<float, 6> dash{100.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
  const std::array<ParamAction, 2> actions{ParamAction{hfo::kDash, dash}, ParamAction{hfo::kDash, dash}};
  std::vector<float> next(obs.size());
  std::array<float, 2> rewards{};
  float team_return = 0.0F;
  for (int t = 0; t < 12; ++t) {
    const StepResult sr = player.step(dash_output, explore, /*epsilon=*/0.0);
    const int status = twin.step(actions, next, rewards);
    ASSERT_EQ(sr.status, status);
    team_return += (rewards[0] + rewards[1]) / 2.0F;
    for (int i = 0; i < 2; ++i) {
      const TransitionView v = player.episode(i).transition(static_cast<size_t>(t));
      for (size_t k = 0; k < obs_dim; ++k) {
        ASSERT_EQ(v.state[k], obs[i * obs_dim + k]) << "player " << i << ", step " << t << ", feature " << k;
        ASSERT_EQ(v.next_state[k], next[i * obs_dim + k]) << "player " << i << ", step " << t;
      }
      EXPECT_EQ(v.reward, rewards[static_cast<size_t>(i)]);
      EXPECT_EQ(v.action[hfo::kDash], 1.0F);
    }
    obs = next;
    if (status != hfo::kInGame) {
      break;
    }
  }
  EXPECT_EQ(player.episode(0).size(), player.episode(1).size());
  EXPECT_FLOAT_EQ(player.episode_return(), team_return);
}

TEST(TeamGame, DemonstrationsTakeOneTeacherPerPlayer) {
  hfo::SoccerSimConfig c;
  c.offense_agents = 2;
  HfoTeamEnv env(c);
  ScriptedTeamPlayer a(1, 0);
  ScriptedTeamPlayer b(1, 0);
  std::array<Policy*, 1> one{&a};
  EXPECT_THROW(EpisodePlayer(env, one, false), std::invalid_argument);
  std::array<Policy*, 2> two{&a, &b};
  EpisodePlayer player(env, two, true);
  ExplorationConfig x;
  EpsilonGreedy explore(env.action_space(), x, 1);
  Rng rng(3);
  player.begin(5, /*demo_share=*/1.0, rng);
  ASSERT_TRUE(player.demo());
  while (!player.ended()) {
    player.step({}, explore, 1.0);
  }
  EXPECT_EQ(player.episode(0).size(), player.episode(1).size());
  EXPECT_EQ(player.labels(0), nullptr);  // a demonstration is not labelled
}

// The team's evaluation against the same game played by hand: the same outcomes, steps and
// returns, whether one policy plays every slot or each player has its own.
TEST(TeamGame, EvaluationPlaysEveryPlayer) {
  hfo::SoccerSimConfig c;
  c.offense_agents = 2;
  c.goalie = true;
  c.start = hfo::StartDistribution::kHfo;
  constexpr int kEpisodes = 40;
  HfoTeamEnv by_hand(c);
  const auto obs_dim = static_cast<size_t>(by_hand.observation_size());
  ScriptedTeamPlayer p0(1, 1);
  ScriptedTeamPlayer p1(1, 1);
  std::vector<float> obs(2 * obs_dim);
  std::array<float, 2> rewards{};
  std::array<ParamAction, 2> actions{};
  std::array<std::array<float, 6>, 2> params{};
  int goals = 0;
  double steps = 0.0;
  double ret = 0.0;
  for (int e = 0; e < kEpisodes; ++e) {
    if (e == 0) {
      by_hand.reset(9, obs);
    } else {
      by_hand.reset(obs);
    }
    int status = hfo::kInGame;
    while (status == hfo::kInGame) {
      for (size_t i = 0; i < 2; ++i) {
        const ParamAction a = (i == 0 ? p0 : p1).act(std::span<const float>(obs).subspan(i * obs_dim, obs_dim));
        std::copy(a.params.begin(), a.params.end(), params[i].begin());
        actions[i] = {a.id, std::span<const float>(params[i]).first(a.params.size())};
      }
      status = by_hand.step(actions, obs, rewards);
      ret += (rewards[0] + rewards[1]) / 2.0;
      steps += 1.0;
    }
    goals += status == hfo::kGoal ? 1 : 0;
  }

  HfoTeamEnv env(c);
  ScriptedTeamPlayer shared(1, 1);
  const EvalResult one = evaluate(env, shared, kEpisodes, 9);
  EXPECT_DOUBLE_EQ(one.goal_rate, static_cast<double>(goals) / kEpisodes);
  EXPECT_DOUBLE_EQ(one.avg_steps, steps / kEpisodes);
  EXPECT_NEAR(one.avg_return, ret / kEpisodes, 1e-4);
  EXPECT_EQ(one.outcomes.at("GOAL"), goals);

  HfoTeamEnv env2(c);
  ScriptedTeamPlayer q0(1, 1);
  ScriptedTeamPlayer q1(1, 1);
  std::array<Policy*, 2> each{&q0, &q1};
  int calls = 0;
  const EvalResult two = evaluate(env2, each, kEpisodes, 9, {}, [&](const EvalStep& s) {
    EXPECT_EQ(s.player, calls % 2);
    ++calls;
  });
  EXPECT_DOUBLE_EQ(two.goal_rate, one.goal_rate);
  EXPECT_DOUBLE_EQ(two.avg_steps, one.avg_steps);
  EXPECT_EQ(calls, static_cast<int>(steps) * 2);

  std::array<Policy*, 3> three{&q0, &q1, &shared};
  EXPECT_THROW((void)evaluate(env2, three, 1, 9), std::invalid_argument);
}

TEST(TeamGame, ATeamRewardGivesEveryPlayerTheMean) {
  hfo::SoccerSimConfig c;
  c.offense_agents = 2;
  c.noise = false;
  HfoTeamEnv own(c);
  HfoTeamEnv team(c, false, 0, /*team_reward=*/true);
  const auto n = static_cast<size_t>(own.observation_size());
  std::vector<float> a(2 * n);
  std::vector<float> b(2 * n);
  own.reset(4, a);
  team.reset(4, b);
  std::array<float, 6> dash{100.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
  std::array<float, 6> turn{};
  const std::array<ParamAction, 2> actions{ParamAction{hfo::kDash, dash}, ParamAction{hfo::kTurn, turn}};
  std::array<float, 2> ro{};
  std::array<float, 2> rt{};
  bool differed = false;
  for (int t = 0; t < 20; ++t) {
    const StepResult so = own.step_team(actions, a, ro);
    const StepResult st = team.step_team(actions, b, rt);
    ASSERT_EQ(so.status, st.status);
    EXPECT_FLOAT_EQ(rt[0], (ro[0] + ro[1]) / 2.0F);
    EXPECT_FLOAT_EQ(rt[1], rt[0]);
    EXPECT_FLOAT_EQ(so.reward, st.reward);
    differed = differed || ro[0] != ro[1];
    if (so.terminal()) {
      break;
    }
  }
  EXPECT_TRUE(differed) << "the test needs players whose own rewards differ";
}

}  // namespace
}  // namespace pamdp
