// envs/scaled_parameters.hpp: parameters over [-1, 1] mapped onto an env's own ranges, as MP-DQN's
// ScaledParameterisedActionWrapper maps them, and the hand-made parameter policies of Goal and
// Platform (cycraig/MP-DQN run_goal_pdqn.py, run_platform_pdqn.py) in either unit. The generic
// Env contract of the scaled envs is checked by env_conformance_test.
#include "envs/scaled_parameters.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>

#include "envs/goal/goal_env.hpp"
#include "envs/platform/platform_env.hpp"
#include "envs/registry.hpp"

namespace pamdp {
namespace {

// A scaled step is the inner env's step at lo + (p + 1)(hi - lo) / 2: Goal's kick_to_x over
// [0, 40] and shoot_left_y over [-7.01, 7.01], by hand.
TEST(ScaledParameters, AStepIsTheInnerStepAtTheMappedParameters) {
  struct Case {
    int action;
    std::array<float, 4> scaled;
    std::array<float, 4> raw;
  };
  const Case cases[] = {
      {goal::GoalEnv::kKickTo, {-0.5F, 1.0F, 0, 0}, {10.0F, 15.0F, -0.0F, 0}},
      {goal::GoalEnv::kKickTo, {1.0F, -1.0F, 0, 0}, {40.0F, -15.0F, 0, 0}},
      {goal::GoalEnv::kShootGoalLeft, {0, 0, 0.5F, 0}, {20.0F, 0, 3.505F, 0}},
      {goal::GoalEnv::kShootGoalRight, {0, 0, 0, -1.0F}, {20.0F, 0, 0, -7.01F}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.action);
    ScaledParametersEnv scaled(std::make_unique<goal::GoalEnv>());
    goal::GoalEnv raw;
    std::array<float, goal::GoalEnv::kObservationSize> obs_s{};
    std::array<float, goal::GoalEnv::kObservationSize> obs_r{};
    scaled.reset(7, obs_s);
    raw.reset(7, obs_r);
    StepResult rs;
    StepResult rr;
    int steps = 0;
    do {
      rs = scaled.step({c.action, c.scaled}, obs_s);
      rr = raw.step({c.action, c.raw}, obs_r);
      ASSERT_EQ(rs.status, rr.status);
      ASSERT_FLOAT_EQ(rs.reward, rr.reward);
      for (size_t i = 0; i < obs_s.size(); ++i) {
        ASSERT_NEAR(obs_s[i], obs_r[i], 1e-5) << "feature " << i;
      }
    } while (!rs.terminal() && ++steps < 100);
  }
  // The shown space: every parameter over [-1, 1], the actions and names unchanged.
  const ScaledParametersEnv env(std::make_unique<goal::GoalEnv>());
  const ActionSpace& inner = goal::GoalEnv().action_space();
  ASSERT_EQ(env.action_space().num_params(), inner.num_params());
  for (int i = 0; i < inner.num_params(); ++i) {
    EXPECT_EQ(env.action_space().params[static_cast<size_t>(i)].name, inner.params[static_cast<size_t>(i)].name);
    EXPECT_EQ(env.action_space().params[static_cast<size_t>(i)].lo, -1.0F);
    EXPECT_EQ(env.action_space().params[static_cast<size_t>(i)].hi, 1.0F);
  }
  EXPECT_EQ(env.action_space().num_actions(), inner.num_actions());
}

ParameterPrior prior_of(const std::string& env, bool scaled) {
  EnvParams p = env_registry().defaults();
  p.set("scaled_parameters", scaled);
  const auto& of = env_registry().find(env).parameter_prior;
  EXPECT_TRUE(of);
  const std::optional<ParameterPrior> prior = of(p);
  EXPECT_TRUE(prior.has_value());
  return *prior;
}

// Goal's shots aim one inside each post (GOAL_WIDTH / 2 - 1 = 6.01, run_goal_pdqn.py's unscaled
// shoot_goal_left_weights), which its scaled weights encode as ±0.857346647646219686; and the
// two units describe one policy.
TEST(ParameterPrior, GoalShootsOneInsideEachPostInEitherUnit) {
  const ParameterPrior raw = prior_of("goal", false);
  const ParameterPrior scaled = prior_of("goal", true);
  ASSERT_EQ(raw.obs_dim, goal::GoalEnv::kObservationSize);
  ASSERT_EQ(raw.bias.size(), 4U);
  EXPECT_NEAR(raw.bias[2], 6.01F, 1e-5);
  EXPECT_NEAR(raw.bias[3], -6.01F, 1e-5);
  EXPECT_NEAR(scaled.bias[2], 0.857346647646219686F, 1e-7);
  // kick_to_x in raw units at an observation: 20 + 20 (-0.375 + 0.5 o10 + 0.0625 o14).
  std::array<float, goal::GoalEnv::kObservationSize> o{};
  o[10] = 0.4F;
  o[14] = -0.8F;
  float x = raw.bias[0];
  for (int j = 0; j < raw.obs_dim; ++j) {
    x += raw.weights[static_cast<size_t>(j)] * o[static_cast<size_t>(j)];
  }
  EXPECT_NEAR(x, 20.0F + 20.0F * (-0.375F + 0.5F * 0.4F + 0.0625F * -0.8F), 1e-4);
  const ParameterPrior back = prior_in_scaled_units(raw, goal::GoalEnv().action_space());
  for (size_t i = 0; i < back.weights.size(); ++i) {
    EXPECT_NEAR(back.weights[i], scaled.weights[i], 1e-6) << i;
  }
  for (size_t i = 0; i < back.bias.size(); ++i) {
    EXPECT_NEAR(back.bias[i], scaled.bias[i], 1e-6) << i;
  }
}

// Platform's run, hop and leap start at 3, 10 and 400 whatever the state (run_platform_pdqn.py's
// initial_params_), 2 (v - lo) / (hi - lo) - 1 in scaled units over [0, 30], [0, 720], [0, 430].
TEST(ParameterPrior, PlatformStartsAtFixedRunHopAndLeap) {
  const ParameterPrior raw = prior_of("platform", false);
  const ParameterPrior scaled = prior_of("platform", true);
  EXPECT_EQ(raw.bias, (std::vector<float>{3.0F, 10.0F, 400.0F}));
  EXPECT_NEAR(scaled.bias[0], 2.0F * 3.0F / 30.0F - 1.0F, 1e-6);
  EXPECT_NEAR(scaled.bias[1], 2.0F * 10.0F / 720.0F - 1.0F, 1e-6);
  EXPECT_NEAR(scaled.bias[2], 2.0F * 400.0F / 430.0F - 1.0F, 1e-6);
  for (const float w : scaled.weights) {
    EXPECT_EQ(w, 0.0F);
  }
}

// env.scaled_parameters through the registry: the made env shows [-1, 1]; other envs have no
// such key and no policy.
TEST(ScaledParameters, TheRegistryMakesTheScaledEnv) {
  for (const std::string name : {"goal", "platform"}) {
    EnvParams p = env_registry().defaults();
    p.set("scaled_parameters", true);
    const std::unique_ptr<Env> env = env_registry().find(name).make(p);
    for (const ParamSpec& s : env->action_space().params) {
      EXPECT_EQ(s.lo, -1.0F) << name;
      EXPECT_EQ(s.hi, 1.0F) << name;
    }
  }
  EXPECT_FALSE(env_registry().reads("hfo", "scaled_parameters"));
  EXPECT_FALSE(env_registry().find("hfo").parameter_prior);
}

}  // namespace
}  // namespace pamdp
