// ReachStopEnv's own rules (envs/toy/reach_stop.hpp); the generic Env contract is checked by
// env_conformance_test.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "envs/toy/reach_stop.hpp"

namespace pamdp::toy {
namespace {

class ReachStopTest : public ::testing::Test {
 protected:
  StepResult move(float velocity) {
    params_[ReachStopEnv::kVelocityParam] = velocity;
    return env_.step({ReachStopEnv::kMove, params_}, obs_);
  }
  StepResult stop() { return env_.step({ReachStopEnv::kStop, params_}, obs_); }

  ReachStopEnv env_;
  std::array<float, ReachStopEnv::kObservationSize> obs_{};
  std::array<float, 1> params_{};
};

TEST_F(ReachStopTest, ObservationIsPositionTargetAndGap) {
  env_.set_state(-0.5F, 0.25F, obs_);
  EXPECT_EQ(obs_[0], -0.5F);
  EXPECT_EQ(obs_[1], 0.25F);
  EXPECT_EQ(obs_[2], 0.75F);
}

TEST_F(ReachStopTest, MoveScalesVelocityAndRewardsTheDistanceRemoved) {
  env_.set_state(0.0F, 0.5F, obs_);
  StepResult r = move(1.0F);
  EXPECT_EQ(r.status, ReachStopEnv::kInProgress);
  EXPECT_FLOAT_EQ(env_.pos(), env_.config().max_step);
  EXPECT_FLOAT_EQ(r.reward, env_.config().max_step);
  EXPECT_FLOAT_EQ(obs_[0], env_.pos());

  r = move(-0.5F);  // away from the target: negative reward
  EXPECT_FLOAT_EQ(env_.pos(), 0.5F * env_.config().max_step);
  EXPECT_FLOAT_EQ(r.reward, -0.5F * env_.config().max_step);
}

TEST_F(ReachStopTest, VelocityAndPositionAreClamped) {
  env_.set_state(0.9F, -1.0F, obs_);
  move(5.0F);  // clamped to velocity 1, then to the edge
  EXPECT_EQ(env_.pos(), 1.0F);
  move(1.0F);
  EXPECT_EQ(env_.pos(), 1.0F);
  move(-100.0F);
  EXPECT_FLOAT_EQ(env_.pos(), 1.0F - env_.config().max_step);
  move(std::nanf(""));  // a NaN velocity must not poison the state
  EXPECT_TRUE(std::isfinite(env_.pos()));
}

TEST_F(ReachStopTest, StopWithinToleranceSucceedsWithBonus) {
  const float tol = env_.config().tolerance;
  env_.set_state(0.3F, 0.3F + 0.9F * tol, obs_);
  const StepResult r = stop();
  EXPECT_EQ(r.status, ReachStopEnv::kSuccess);
  EXPECT_EQ(r.status, env_.success_status());
  EXPECT_EQ(r.reward, env_.config().success_bonus);
}

TEST_F(ReachStopTest, StopElsewhereFailsWithoutReward) {
  const float tol = env_.config().tolerance;
  env_.set_state(0.3F, 0.3F - 1.5F * tol, obs_);
  const StepResult r = stop();
  EXPECT_EQ(r.status, ReachStopEnv::kWrongStop);
  EXPECT_EQ(r.reward, 0.0F);
}

TEST_F(ReachStopTest, TimesOutAfterMaxSteps) {
  env_.set_state(-1.0F, 1.0F, obs_);
  const int max_steps = env_.max_episode_steps();
  ASSERT_EQ(max_steps, 20);
  for (int i = 1; i < max_steps; ++i) {
    ASSERT_EQ(move(0.0F).status, ReachStopEnv::kInProgress) << "step " << i;
  }
  EXPECT_EQ(move(0.0F).status, ReachStopEnv::kOutOfTime);
}

TEST_F(ReachStopTest, StopOnTheLastStepStillCountsAsSuccess) {
  env_.set_state(0.0F, 0.0F, obs_);
  for (int i = 1; i < env_.max_episode_steps(); ++i) {
    move(0.0F);
  }
  EXPECT_EQ(stop().status, ReachStopEnv::kSuccess);
}

TEST_F(ReachStopTest, ReturnIsDistanceClosedPlusBonus) {
  env_.set_state(-0.8F, 0.6F, obs_);
  float ret = 0.0F;
  StepResult r;
  int steps = 0;
  while (std::fabs(obs_[2]) > 0.01F && steps < 10) {
    r = move(std::clamp(obs_[2] / env_.config().max_step, -1.0F, 1.0F));
    ret += r.reward;
    ++steps;
  }
  r = stop();
  ret += r.reward;
  EXPECT_EQ(r.status, ReachStopEnv::kSuccess);
  EXPECT_NEAR(ret, 1.4F + env_.config().success_bonus, 1e-5F);
  EXPECT_EQ(steps, 6);  // ceil(1.4 / 0.25)
}

TEST_F(ReachStopTest, ResetDrawsPositionsOverTheWholeRange) {
  env_.reset(1, obs_);
  float lo = 1.0F;
  float hi = -1.0F;
  for (int i = 0; i < 2000; ++i) {
    env_.reset(obs_);
    ASSERT_LE(std::fabs(obs_[0]), 1.0F);
    ASSERT_LE(std::fabs(obs_[1]), 1.0F);
    lo = std::min({lo, obs_[0], obs_[1]});
    hi = std::max({hi, obs_[0], obs_[1]});
  }
  EXPECT_LT(lo, -0.99F);
  EXPECT_GT(hi, 0.99F);
}

TEST(ReachStopConfig, RejectsValuesOutOfRange) {
  EXPECT_THROW(ReachStopEnv(ReachStopConfig{.max_steps = 0}), std::invalid_argument);
  EXPECT_THROW(ReachStopEnv(ReachStopConfig{.max_step = 0.0F}), std::invalid_argument);
  EXPECT_THROW(ReachStopEnv(ReachStopConfig{.tolerance = -0.1F}), std::invalid_argument);
  EXPECT_THROW(ReachStopEnv(ReachStopConfig{.success_bonus = INFINITY}), std::invalid_argument);
  EXPECT_NO_THROW(ReachStopEnv(ReachStopConfig{.max_steps = 1, .max_step = 2.0F, .tolerance = 0.0F}));
}

using ReachStopDeathTest = ReachStopTest;

TEST_F(ReachStopDeathTest, StepAfterTerminalStops) {
  env_.set_state(0.0F, 0.0F, obs_);
  stop();
  EXPECT_DEATH(stop(), "after a terminal status");
}

TEST_F(ReachStopDeathTest, UnknownActionStops) {
  env_.set_state(0.0F, 0.0F, obs_);
  EXPECT_DEATH(env_.step({7, params_}, obs_), "action id out of range");
}

}  // namespace
}  // namespace pamdp::toy
