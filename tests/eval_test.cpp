// evaluate() and to_json() (learner/evaluation.hpp): the scripted HFO baseline scores as the
// paper's Helios stand-in must, and the counts and the JSON are consistent by construction.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/policy.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/toy/reach_stop.hpp"
#include "learner/evaluation.hpp"

namespace pamdp {
namespace {

// Invariants of any EvalResult, whatever the policy.
void expect_consistent(const EvalResult& r, const Env& env, int episodes) {
  EXPECT_EQ(r.episodes, episodes);
  int total = 0;
  for (const auto& [name, count] : r.outcomes) {
    EXPECT_GE(count, 0) << name;
    total += count;
  }
  EXPECT_EQ(total, episodes) << "outcome counts must sum to the episode count";

  // Every terminal outcome is listed (with 0 if it never happened), and nothing else.
  int terminal_outcomes = 0;
  for (int s : env.outcomes()) {
    if (s != 0) {
      ++terminal_outcomes;
      EXPECT_TRUE(r.outcomes.contains(std::string(env.status_name(s)))) << env.status_name(s);
    }
  }
  EXPECT_EQ(static_cast<int>(r.outcomes.size()), terminal_outcomes);

  const int goals = r.outcomes.at(std::string(env.status_name(env.success_status())));
  EXPECT_DOUBLE_EQ(r.goal_rate, static_cast<double>(goals) / episodes);
  EXPECT_GE(r.avg_steps, 1.0);
  EXPECT_LE(r.avg_steps, env.max_episode_steps());
  if (goals == 0) {
    EXPECT_EQ(r.avg_steps_to_goal, 0.0);
  } else {
    EXPECT_GE(r.avg_steps_to_goal, 1.0);
    EXPECT_LE(r.avg_steps_to_goal, env.max_episode_steps());
  }
  if (goals == episodes) {
    EXPECT_DOUBLE_EQ(r.avg_steps_to_goal, r.avg_steps);
  }
  EXPECT_TRUE(std::isfinite(r.avg_return));
}

TEST(Evaluate, ScriptedOffenseScoresAtLeast95PercentWithNoise) {
  hfo::SoccerSimConfig config;  // paper start distribution, server referee
  config.noise = true;
  ASSERT_EQ(config.start, hfo::StartDistribution::kPaper);
  hfo::HfoEnv env(config);
  hfo::ScriptedOffense policy;
  constexpr int kEpisodes = 300;
  const EvalResult r = evaluate(env, policy, kEpisodes, 20160101);
  expect_consistent(r, env, kEpisodes);
  EXPECT_GE(r.goal_rate, 0.95) << to_json(r);
  // The shaped reward pays 5 for a goal; a scorer's mean return must be clearly positive.
  EXPECT_GT(r.avg_return, 0.0) << to_json(r);
}

TEST(Evaluate, RandomPolicyCountsAreConsistent) {
  hfo::HfoEnv env;
  RandomPolicy policy(env.action_space(), 5, {hfo::kDash, hfo::kTurn, hfo::kKick});
  policy.set_param_range(hfo::param::kDashPower, -100.0F, 100.0F);
  constexpr int kEpisodes = 50;
  const EvalResult r = evaluate(env, policy, kEpisodes, 7);
  expect_consistent(r, env, kEpisodes);
}

TEST(Evaluate, SameSeedGivesSameResult) {
  hfo::HfoEnv env_a;
  hfo::HfoEnv env_b;
  hfo::ScriptedOffense policy_a;
  hfo::ScriptedOffense policy_b;
  const EvalResult a = evaluate(env_a, policy_a, 30, 42);
  const EvalResult b = evaluate(env_b, policy_b, 30, 42);
  EXPECT_EQ(to_json(a), to_json(b));
}

// on_step sees every step exactly once, in order, and adds up to the result it does not change.
TEST(Evaluate, OnStepSeesEveryStepAndChangesNothing) {
  hfo::HfoEnv env_a;
  hfo::HfoEnv env_b;
  hfo::ScriptedOffense policy_a;
  hfo::ScriptedOffense policy_b;
  constexpr int kEpisodes = 12;
  const EvalResult plain = evaluate(env_a, policy_a, kEpisodes, 42);

  int64_t steps = 0;
  double reward = 0.0;
  int terminals = 0;
  int expected_episode = 0;
  int expected_step = 1;
  std::map<std::string, int> outcomes;
  const EvalResult watched = evaluate(env_b, policy_b, kEpisodes, 42, {}, [&](const EvalStep& s) {
    EXPECT_EQ(s.episode, expected_episode);
    EXPECT_EQ(s.step, expected_step);
    EXPECT_EQ(static_cast<int>(s.obs.size()), env_b.observation_size());
    EXPECT_GE(s.action.id, 0);
    EXPECT_LT(s.action.id, env_b.action_space().num_actions());
    ++steps;
    reward += s.result.reward;
    if (s.result.terminal()) {
      ++terminals;
      ++outcomes[std::string(env_b.status_name(s.result.status))];
      ++expected_episode;
      expected_step = 1;
    } else {
      ++expected_step;
    }
  });
  EXPECT_EQ(to_json(watched), to_json(plain));
  EXPECT_EQ(terminals, kEpisodes);
  EXPECT_DOUBLE_EQ(static_cast<double>(steps), plain.avg_steps * kEpisodes);
  EXPECT_NEAR(reward, plain.avg_return * kEpisodes, 1e-6 * kEpisodes);
  for (const auto& [name, count] : outcomes) {
    EXPECT_EQ(plain.outcomes.at(name), count) << name;
  }
}

// The first observation an episode's policy reads is the reset's, not the previous episode's
// last one: check it against a fresh env reset with the same seed.
TEST(Evaluate, OnStepObservationIsTheOneThePolicyRead) {
  hfo::HfoEnv env;
  hfo::HfoEnv reference;
  hfo::ScriptedOffense policy;
  std::vector<float> first(static_cast<size_t>(env.observation_size()));
  reference.reset(7, first);
  bool checked = false;
  evaluate(env, policy, 1, 7, {}, [&](const EvalStep& s) {
    if (s.step == 1) {
      ASSERT_EQ(s.obs.size(), first.size());
      for (size_t i = 0; i < first.size(); ++i) {
        EXPECT_EQ(s.obs[i], first[i]) << "feature " << i;
      }
      checked = true;
    }
  });
  EXPECT_TRUE(checked);
}

// An oracle for ReachStop: move straight at the target, stop once within tolerance.
class ReachStopOracle final : public Policy {
 public:
  explicit ReachStopOracle(const toy::ReachStopConfig& c) : config_(c) {}
  ParamAction act(std::span<const float> obs) override {
    const float gap = obs[2];
    if (std::fabs(gap) <= 0.5F * config_.tolerance) {
      return {toy::ReachStopEnv::kStop, params_};
    }
    params_[0] = std::clamp(gap / config_.max_step, -1.0F, 1.0F);
    return {toy::ReachStopEnv::kMove, params_};
  }

 private:
  toy::ReachStopConfig config_;
  std::array<float, 1> params_{};
};

TEST(Evaluate, ReachStopOracleAlwaysSucceeds) {
  const toy::ReachStopConfig config;
  toy::ReachStopEnv env(config);
  ReachStopOracle oracle(config);
  constexpr int kEpisodes = 500;
  const EvalResult r = evaluate(env, oracle, kEpisodes, 3);
  expect_consistent(r, env, kEpisodes);
  EXPECT_EQ(r.goal_rate, 1.0) << to_json(r);
  // At most ceil(2 / max_step) moves plus the stop.
  EXPECT_LE(r.avg_steps_to_goal, 2.0F / config.max_step + 1.0F);
  // Return = initial distance - final distance + bonus; with E|pos - target| = 2/3 the mean is
  // about 1.67 (tolerance covers sampling error of 500 episodes, sd ~0.5 / sqrt(500)).
  EXPECT_NEAR(r.avg_return, config.success_bonus + 2.0 / 3.0, 0.1) << to_json(r);
}

TEST(ToJson, ParsesBackWithEveryKeyAndValue) {
  hfo::HfoEnv env;
  hfo::ScriptedOffense policy;
  const EvalResult r = evaluate(env, policy, 20, 9);
  const std::string text = to_json(r);
  EXPECT_EQ(text.find('\n'), std::string::npos) << "to_json must be one line";

  const nlohmann::json j = nlohmann::json::parse(text);
  ASSERT_TRUE(j.is_object());
  for (const char* key : {"episodes", "goal_rate", "avg_steps_to_goal", "avg_return", "avg_steps", "outcomes"}) {
    EXPECT_TRUE(j.contains(key)) << key << " missing from " << text;
  }
  EXPECT_EQ(j.at("episodes").get<int>(), r.episodes);
  EXPECT_DOUBLE_EQ(j.at("goal_rate").get<double>(), r.goal_rate);
  EXPECT_DOUBLE_EQ(j.at("avg_steps_to_goal").get<double>(), r.avg_steps_to_goal);
  EXPECT_DOUBLE_EQ(j.at("avg_return").get<double>(), r.avg_return);
  EXPECT_DOUBLE_EQ(j.at("avg_steps").get<double>(), r.avg_steps);
  ASSERT_TRUE(j.at("outcomes").is_object());
  const auto outcomes = j.at("outcomes").get<std::map<std::string, int>>();
  EXPECT_EQ(outcomes, r.outcomes);
}

// PolicyAgreement on four steps worked by hand: a power in [0, 100] and an angle in [-180, 180].
TEST(PolicyAgreement, CountsActionsAndMeasuresClampedAndWrappedDifferences) {
  ActionSpace space;
  space.params = {{"power", 0.0F, 100.0F}, {"angle", -180.0F, 180.0F}};
  space.actions = {{"PUSH", {0}}, {"AIM", {1}}};
  PolicyAgreement a(space);
  const auto step = [&](int teacher_id, std::array<float, 2> teacher, int student_id, std::array<float, 2> student) {
    a.add(ParamAction{teacher_id, teacher}, ParamAction{student_id, student});
  };
  step(0, {50.0F, 0.0F}, 0, {60.0F, 99.0F});    // PUSH, power off by 10 (the angle is not PUSH's)
  step(0, {50.0F, 0.0F}, 1, {120.0F, 0.0F});    // AIM instead; power 120 is played as 100: off by 50
  step(1, {0.0F, 170.0F}, 1, {0.0F, -170.0F});  // AIM, 340 degrees apart one way, 20 the other
  step(1, {0.0F, 0.0F}, 0, {0.0F, 90.0F});      // PUSH instead, angle off by 90
  EXPECT_EQ(a.steps(), 4);
  const std::vector<PolicyAgreement::ActionRow> rows = a.rows();
  ASSERT_EQ(rows.size(), 2U);
  EXPECT_EQ(rows[0].name, "PUSH");
  EXPECT_EQ(rows[0].steps, 2);
  EXPECT_EQ(rows[0].same, 1);
  ASSERT_EQ(rows[0].params.size(), 1U);
  EXPECT_EQ(rows[0].params[0].name, "power");
  EXPECT_DOUBLE_EQ(rows[0].params[0].median, 10.0);  // nearest rank: the first of two
  EXPECT_DOUBLE_EQ(rows[0].params[0].p90, 50.0);
  EXPECT_EQ(rows[1].name, "AIM");
  EXPECT_EQ(rows[1].same, 1);
  ASSERT_EQ(rows[1].params.size(), 1U);
  EXPECT_DOUBLE_EQ(rows[1].params[0].median, 20.0);
  EXPECT_DOUBLE_EQ(rows[1].params[0].p90, 90.0);

  const nlohmann::json j = nlohmann::json::parse(a.to_json());
  EXPECT_EQ(j.at("steps").get<int>(), 4);
  EXPECT_DOUBLE_EQ(j.at("actions").at("PUSH").at("same_action").get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j.at("actions").at("AIM").at("params").at("angle").at("p90").get<double>(), 90.0);
  EXPECT_THROW(a.add(ParamAction{2, std::array<float, 2>{}}, ParamAction{0, std::array<float, 2>{}}), std::logic_error);
}

// The scripted offense asked beside itself agrees everywhere, with no parameter difference; an
// action the teacher never took gets no row.
TEST(PolicyAgreement, APolicyAgreesWithItself) {
  hfo::SoccerSimConfig config;
  config.goalie = true;
  hfo::HfoEnv env(config);
  hfo::ScriptedOffense teacher;
  hfo::ScriptedOffense student;
  PolicyAgreement a(env.action_space());
  evaluate(env, teacher, 20, 4, {}, [&](const EvalStep& s) { a.add(s.action, student.act(s.obs)); });
  ASSERT_GT(a.steps(), 100);
  for (const PolicyAgreement::ActionRow& r : a.rows()) {
    EXPECT_NE(r.name, "TACKLE");
    EXPECT_EQ(r.same, r.steps) << r.name;
    for (const PolicyAgreement::ParamError& p : r.params) {
      EXPECT_EQ(p.p90, 0.0) << r.name << " " << p.name;
    }
  }
}

// A run's screens and confirmations play starts no other evaluation of the run plays: the
// confirmation is an independent second opinion only if its starts are not the screen's.
TEST(EvaluationSeeds, ScreensAndConfirmationsOfARunNeverShareStarts) {
  std::vector<uint64_t> seeds;
  for (const uint64_t run : {1U, 2U}) {
    for (int64_t updates = 0; updates <= 200000; updates += 10000) {
      seeds.push_back(screening_seed(run, updates));
      seeds.push_back(confirmation_seed(run, updates));
    }
  }
  std::sort(seeds.begin(), seeds.end());
  EXPECT_EQ(std::adjacent_find(seeds.begin(), seeds.end()), seeds.end());
  EXPECT_EQ(screening_seed(7, 30000), screening_seed(7, 30000));  // a function of its arguments only
}

}  // namespace
}  // namespace pamdp
