// GoalEnv's own rules (envs/goal/goal_env.hpp): hand-computed traces of gym-goal's dynamics with
// the noise off, every terminal outcome, parameter clamping, the start state and the
// observation's scaling. The generic Env contract is checked by env_conformance_test.
//
// Constants used in the arithmetic (gym-goal config.py): striker and keeper decay 0.4, power
// rate 0.006, size 0.9; ball decay 0.94, power rate 0.027, size 0.4; kickable 1.6; catchable 2;
// goal line x = 20, goal mouth |y| <= 7.01.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>

#include "core/rng.hpp"
#include "envs/goal/goal_env.hpp"

namespace pamdp::goal {
namespace {

constexpr double kTol = 1e-9;
constexpr double kPi = std::numbers::pi;

// The observation value MP-DQN's ScaledStateWrapper gives `v` in [lo, hi].
float scaled(double v, double lo, double hi) {
  return static_cast<float>(2 * (v - lo) / (hi - lo) - 1);
}

Body at(double x, double y, double orientation_rad = 0.0) {
  return {.position = {x, y}, .velocity = {}, .orientation_rad = orientation_rad};
}

class GoalEnvTest : public ::testing::Test {
 protected:
  StepResult kick_to(float x, float y) {
    params_ = {x, y, 0.0F, 0.0F};
    return env_.step({GoalEnv::kKickTo, params_}, obs_);
  }
  StepResult shoot_left(float y) {
    params_ = {0.0F, 0.0F, y, 0.0F};
    return env_.step({GoalEnv::kShootGoalLeft, params_}, obs_);
  }
  const GoalState& s() const { return env_.state(); }

  GoalEnv env_{GoalConfig{.noise = false}};
  std::array<float, GoalEnv::kObservationSize> obs_{};
  std::array<float, 4> params_{};
};

// Striker (18, 0) facing the ball at (19.5, 0), keeper out of reach at (21.9, 8). SHOOT_GOAL(0)
// aims at (20.4, 0).
//  sim 1: kick. accel = 0.06 * ((20.4, 0) - (18, 0)) - 0 = (0.144, 0); kick power weight
//         1 - 0 - 0.25 * 1.5 / 1.6 = 0.765625 cancels out, so the ball gets v = (0.144, 0).
//         Ball at rest point 19.5 + 0.144 / 0.06 = 21.9, straight ahead (gradient 0): the keeper
//         chases (21.9, 0), straight down: v = (0, -0.048) -> y 7.952, v -0.0192.
//         Ball x 19.644, v 0.13536. Striker still.
//  sim 2: ball 1.644 away (> 1.6): the striker faces it and dashes, v 0.06 -> x 18.06, v 0.024.
//         Keeper v -0.0672 -> y 7.8848. Ball x 19.77936, v 0.1272384.
//  sim 3: striker v 0.084 -> x 18.144, v 0.0336. Keeper v -0.07488 -> y 7.80992.
//         Ball x 19.9065984, v 0.119604096.
//  sim 4: striker v 0.0936 -> x 18.2376, v 0.03744. Keeper v -0.077952 -> y 7.731968,
//         v -0.0311808. Ball x 20.026202496 (in the goal), v 0.11242785024: GOAL, +50.
TEST_F(GoalEnvTest, StraightShotScoresOnTheFourthSimStep) {
  env_.set_state({.striker = at(18, 0), .keeper = at(21.9, 8), .ball = at(19.5, 0)}, obs_);
  const StepResult r = shoot_left(0.0F);
  EXPECT_EQ(r.status, GoalEnv::kGoal);
  EXPECT_EQ(r.reward, 50.0F);
  EXPECT_EQ(env_.last_sim_steps(), 4);
  EXPECT_NEAR(s().ball.position.x, 20.026202496, kTol);
  EXPECT_NEAR(s().ball.position.y, 0.0, kTol);
  EXPECT_NEAR(s().ball.velocity.x, 0.11242785024, kTol);
  EXPECT_NEAR(s().striker.position.x, 18.2376, kTol);
  EXPECT_NEAR(s().striker.velocity.x, 0.03744, kTol);
  EXPECT_NEAR(s().striker.orientation_rad, 0.0, kTol);
  EXPECT_NEAR(s().keeper.position.x, 21.9, kTol);
  EXPECT_NEAR(s().keeper.position.y, 7.731968, kTol);
  EXPECT_NEAR(s().keeper.velocity.y, -0.0311808, kTol);
  EXPECT_NEAR(s().keeper.orientation_rad, -kPi / 2, kTol);

  // The observation of that state, feature by feature (MP-DQN's scaling).
  EXPECT_NEAR(obs_[0], scaled(18.2376, 0, 20), 1e-6);         // 0.82376
  EXPECT_NEAR(obs_[2], scaled(0.03744, -1, 1), 1e-6);         // 0.03744
  EXPECT_NEAR(obs_[6], scaled(7.731968, -15, 15), 1e-6);      // 0.5154645
  EXPECT_NEAR(obs_[9], scaled(-kPi / 2, -kPi, kPi), 1e-6);    // -0.5
  EXPECT_NEAR(obs_[10], scaled(20.026202496, 0, 20), 1e-6);   // 1.0026202: past the goal line
  EXPECT_NEAR(obs_[12], scaled(0.11242785024, -3, 3), 1e-6);  // 0.0374760
  const double dx = 20.026202496 - 21.9;
  const double dy = 0.0 - 7.731968;
  EXPECT_NEAR(obs_[14], dx / std::hypot(dx, dy), 1e-6);
  EXPECT_NEAR(obs_[15], dy / std::hypot(dx, dy), 1e-6);
  // Keeper-ball line at x = 20: y = 0 + (dy / dx) * (20 - 20.026202496) = -0.10812..., then
  // scaled from [-7.01, 14.02].
  EXPECT_NEAR(obs_[16], scaled((dy / dx) * (20 - 20.026202496), -7.01, 14.02), 1e-6);
}

// Striker (18, 0) facing the ball at (19.5, 0), keeper at (20, -4). SHOOT_GOAL(6) aims at
// (20.4, 6): accel = 0.06 * (2.4, 6) = (0.144, 0.36), which the ball takes whole.
// Its rest point (21.9, 6) lies past the goal line on the line y = 2.5 x - 48.75, which meets
// x = 20 at y = 1.25, inside 7.01 + 2: the keeper intercepts. The foot of the perpendicular from
// (20, -4) is x = (4 + 48.75) / (2.5 + 0.4) = 18.1896..., so the keeper accelerates with power 20
// (0.12) along the unit normal n = (-2.5, 1) / sqrt(7.25). The line stays put, so n does too:
// keeper speeds 0.12, 0.168, 0.1872, 0.19488, distance covered 0.67008, final speed 0.077952.
// Ball after k sim steps: (19.5, 0) + (0.144, 0.36) * (1 + 0.94 + ... + 0.94^(k-1)); the sums
// are 1, 1.94, 2.8236, 3.654184, so after 4 it is at (20.026202496, 1.31550624): GOAL.
// The striker dashes in sims 2 and 3 (ball at bearings atan2(0.36, 1.644) = 0.215 and
// atan2(0.6984, 1.71936) = 0.386, both within pi/8 = 0.3927), reaching x 18.144, v 0.0336. In sim
// 4 the ball is at bearing atan2(1.016496, 19.9065984 - 18.144) = 0.523 > pi/8: the striker turns
// by that over 1 + 5 * 0.0336, and drifts to x 18.1776.
TEST_F(GoalEnvTest, AngledShotMakesTheKeeperInterceptAlongTheNormal) {
  env_.set_state({.striker = at(18, 0), .keeper = at(20, -4), .ball = at(19.5, 0)}, obs_);
  const StepResult r = shoot_left(6.0F);
  EXPECT_EQ(r.status, GoalEnv::kGoal);
  EXPECT_EQ(r.reward, 50.0F);
  EXPECT_EQ(env_.last_sim_steps(), 4);
  EXPECT_NEAR(s().ball.position.x, 20.026202496, kTol);
  EXPECT_NEAR(s().ball.position.y, 1.31550624, kTol);
  const double nx = -2.5 / std::sqrt(7.25);
  const double ny = 1.0 / std::sqrt(7.25);
  EXPECT_NEAR(s().keeper.position.x, 20 + 0.67008 * nx, kTol);
  EXPECT_NEAR(s().keeper.position.y, -4 + 0.67008 * ny, kTol);
  EXPECT_NEAR(s().keeper.velocity.x, 0.077952 * nx, kTol);
  EXPECT_NEAR(s().keeper.velocity.y, 0.077952 * ny, kTol);
  EXPECT_NEAR(s().keeper.orientation_rad, std::atan2(ny, nx), kTol);
  EXPECT_NEAR(s().striker.position.x, 18.1776, kTol);
  EXPECT_NEAR(s().striker.velocity.x, 0.01344, kTol);
  EXPECT_NEAR(s().striker.orientation_rad, std::atan2(1.016496, 19.9065984 - 18.144) / (1 + 5 * 0.0336), kTol);
}

// KICK_TO(x, y) aims at (x, x) (gym-goal GoalEnv._perform_action hands kick_to x alone).
// Striker (10, 10), ball (11.5, 10), keeper (17, 10). KICK_TO(10, -7) aims at (10, 10), the
// striker's own spot: accel 0.06 * (0, 0) - 0 = 0, so the ball stays, kickable and still, and the
// decision takes one sim step. The keeper chases the ball (rest point (11.5, 10), bearing pi):
// v -0.048 -> x 16.952, v -0.0192; a second decision: v -0.0672 -> x 16.8848, v -0.02688.
TEST_F(GoalEnvTest, KickToASettledBallEndsTheDecisionAfterOneSimStep) {
  env_.set_state({.striker = at(10, 10), .keeper = at(17, 10), .ball = at(11.5, 10)}, obs_);
  StepResult r = kick_to(10.0F, -7.0F);
  EXPECT_EQ(r.status, GoalEnv::kInProgress);
  EXPECT_EQ(r.reward, 0.0F);
  EXPECT_EQ(env_.last_sim_steps(), 1);
  EXPECT_NEAR(s().ball.position.x, 11.5, kTol);
  EXPECT_NEAR(s().ball.position.y, 10.0, kTol);
  EXPECT_NEAR(s().keeper.position.x, 16.952, kTol);
  EXPECT_NEAR(s().keeper.velocity.x, -0.0192, kTol);
  EXPECT_NEAR(s().keeper.orientation_rad, kPi, kTol);
  r = kick_to(10.0F, 3.0F);
  EXPECT_EQ(r.status, GoalEnv::kInProgress);
  EXPECT_NEAR(s().keeper.position.x, 16.8848, kTol);
  EXPECT_NEAR(s().keeper.velocity.x, -0.02688, kTol);
}

// Striker (4.5, 10), ball (6, 10), keeper (8.5, 10). KICK_TO(10, 0) aims at (10, 10):
// accel 0.06 * (5.5, 0) = (0.33, 0).
//  sim 1: ball v 0.33; its rest point 6 + 0.33 / 0.06 = 11.5 is straight ahead (gradient 0), the
//         keeper chases it: v 0.048 -> x 8.548, v 0.0192. Ball x 6.33, v 0.3102, 2.218 from the
//         keeper and 1.83 from the striker: not kickable, go on.
//  sim 2: striker dashes -> x 4.56. Keeper v 0.0672 -> x 8.6152. Ball x 6.6402, v 0.291588,
//         1.975 from the keeper (< 2): CAUGHT. The ball is short of the goal line and wide of the
//         post (10 > 7.01): reward -|(6.6402, 10) - (20, 7.01)| = -13.6903...
TEST_F(GoalEnvTest, KeeperCatchesABallWithinTwo) {
  env_.set_state({.striker = at(4.5, 10), .keeper = at(8.5, 10, kPi), .ball = at(6, 10)}, obs_);
  const StepResult r = kick_to(10.0F, 0.0F);
  EXPECT_EQ(r.status, GoalEnv::kCaught);
  EXPECT_EQ(env_.last_sim_steps(), 2);
  EXPECT_NEAR(r.reward, -std::hypot(20 - 6.6402, 10 - 7.01), 1e-5);
  EXPECT_NEAR(s().ball.position.x, 6.6402, kTol);
  EXPECT_NEAR(s().ball.position.y, 10.0, kTol);
  EXPECT_NEAR(s().keeper.position.x, 8.6152, kTol);
  EXPECT_NEAR(s().striker.position.x, 4.56, kTol);
  EXPECT_EQ(env_.status_name(r.status), "CAUGHT_BY_KEEPER");
}

// KICK_TO's y has no effect (gym-goal passes kick_to the x alone), noise on or off.
TEST(GoalEnvKickTo, TheYParameterIsNeverRead) {
  for (bool noise : {true, false}) {
    GoalEnv a(GoalConfig{.noise = noise});
    GoalEnv b(GoalConfig{.noise = noise});
    std::array<float, GoalEnv::kObservationSize> obs_a{};
    std::array<float, GoalEnv::kObservationSize> obs_b{};
    a.reset(8, obs_a);
    b.reset(8, obs_b);
    StepResult ra;
    int steps = 0;
    do {
      const float x = 3.0F + 2.0F * static_cast<float>(steps);
      ra = a.step({GoalEnv::kKickTo, std::array<float, 4>{x, -12.0F, 0, 0}}, obs_a);
      const StepResult rb = b.step({GoalEnv::kKickTo, std::array<float, 4>{x, 9.0F, 0, 0}}, obs_b);
      ASSERT_EQ(ra.status, rb.status);
      ASSERT_EQ(ra.reward, rb.reward);
      ASSERT_EQ(obs_a, obs_b);
      ++steps;
    } while (!ra.terminal());
  }
}

// Striker (18, 10), ball (19.5, 10), keeper far off at (10, -10). SHOOT_GOAL(7.01) aims at
// (20.4, 7.01): accel = 0.06 * (2.4, -2.99) = (0.144, -0.1794). After 4 sim steps the ball is at
// (19.5 + 0.144 * 3.654184, 10 - 0.1794 * 3.654184) = (20.026202496, 9.3444393904): past the goal
// line but wide of the post, so out of the field. Reward -(9.3444393904 - 7.01).
TEST_F(GoalEnvTest, ShotWideOfThePostIsOutOfBounds) {
  env_.set_state({.striker = at(18, 10), .keeper = at(10, -10), .ball = at(19.5, 10)}, obs_);
  const StepResult r = shoot_left(7.01F);
  EXPECT_EQ(r.status, GoalEnv::kOutOfBounds);
  EXPECT_EQ(env_.last_sim_steps(), 4);
  EXPECT_NEAR(s().ball.position.x, 20.026202496, 1e-6);
  EXPECT_NEAR(s().ball.position.y, 9.3444393904, 1e-6);
  EXPECT_NEAR(r.reward, -2.3344393904, 1e-5);
}

// Nothing but the keeper moves when the striker keeps "kicking" to its own spot; from (20, 15)
// the keeper (terminal speed 0.048 / 0.6 = 0.08) cannot come within 2 of the ball at (1.5, 0) in
// 99 steps. Decisions 1-99 go on; the 100th simulates nothing and ends the episode with
// -(20 - 1.5) = -18.5 (gym-goal GoalEnv.step, time == max_time).
TEST_F(GoalEnvTest, TheHundredthDecisionEndsTheEpisodeUnsimulated) {
  env_.set_state({.striker = at(0, 0), .keeper = at(20, 15), .ball = at(1.5, 0)}, obs_);
  for (int t = 1; t < GoalEnv::kMaxSteps; ++t) {
    ASSERT_EQ(kick_to(0.0F, 0.0F).status, GoalEnv::kInProgress) << "decision " << t;
    ASSERT_EQ(env_.last_sim_steps(), 1);
  }
  const GoalState before = s();
  const StepResult r = kick_to(0.0F, 0.0F);
  EXPECT_EQ(r.status, GoalEnv::kOutOfTime);
  EXPECT_EQ(r.reward, -18.5F);
  EXPECT_EQ(env_.last_sim_steps(), 0);
  EXPECT_EQ(s().keeper.position.x, before.keeper.position.x);
  EXPECT_EQ(s().keeper.position.y, before.keeper.position.y);
  EXPECT_EQ(GoalEnv::kMaxSteps, env_.max_episode_steps());
}

// Out-of-range parameters act as the range's edge (gym-goal GoalEnv.step clips to
// PARAMETERS_MIN / PARAMETERS_MAX), with the noise on: same seed, same start, same trajectory.
TEST(GoalEnvClamp, ParametersOutsideTheirRangesActAsTheEdge) {
  struct Case {
    int action;
    std::array<float, 4> wild;
    std::array<float, 4> edge;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Case cases[] = {
      {GoalEnv::kKickTo, {-5.0F, 100.0F, 0, 0}, {0.0F, 15.0F, 0, 0}},
      {GoalEnv::kKickTo, {90.0F, -40.0F, 0, 0}, {40.0F, -15.0F, 0, 0}},
      {GoalEnv::kKickTo, {nan, nan, 0, 0}, {20.0F, 0.0F, 0, 0}},  // NaN: the midpoint
      {GoalEnv::kShootGoalLeft, {0, 0, 50.0F, 0}, {0, 0, 7.01F, 0}},
      {GoalEnv::kShootGoalRight, {0, 0, 0, -50.0F}, {0, 0, 0, -7.01F}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.action);
    GoalEnv a;
    GoalEnv b;
    std::array<float, GoalEnv::kObservationSize> obs_a{};
    std::array<float, GoalEnv::kObservationSize> obs_b{};
    a.reset(21, obs_a);
    b.reset(21, obs_b);
    StepResult ra;
    StepResult rb;
    do {
      ra = a.step({c.action, c.wild}, obs_a);
      rb = b.step({c.action, c.edge}, obs_b);
      ASSERT_EQ(ra.status, rb.status);
      ASSERT_EQ(ra.reward, rb.reward);
      ASSERT_EQ(obs_a, obs_b);
    } while (!ra.terminal());
  }
  // And a parameter inside its range is not clamped: a different aim gives a different result.
  GoalEnv a;
  GoalEnv b;
  std::array<float, GoalEnv::kObservationSize> obs_a{};
  std::array<float, GoalEnv::kObservationSize> obs_b{};
  a.reset(21, obs_a);
  b.reset(21, obs_b);
  a.step({GoalEnv::kShootGoalLeft, std::array<float, 4>{0, 0, 7.0F, 0}}, obs_a);
  b.step({GoalEnv::kShootGoalLeft, std::array<float, 4>{0, 0, 6.0F, 0}}, obs_b);
  EXPECT_NE(obs_a, obs_b);
}

// gym-goal GoalEnv.reset with the known draw y0 = U(-15, 15), the first of the seed's stream:
// striker (0, y0) facing (20, 0); ball 1.6 - 1e-12 ahead of it; keeper on _keeper_target's line
// through the ball and (20, 0), at x = 14.5 (the ball is short of the goal area), y within 9.16.
TEST(GoalEnvReset, StartsFromGymGoalsStartStateForTheSeedsFirstDraw) {
  for (uint64_t seed : {0, 1, 2, 3, 4}) {
    SCOPED_TRACE(seed);
    GoalEnv env;
    std::array<float, GoalEnv::kObservationSize> obs{};
    env.reset(seed, obs);
    Rng rng(seed);
    const double y0 = rng.uniform(-15.0, 15.0);
    const GoalState& s = env.state();
    EXPECT_EQ(s.striker.position.x, 0.0);
    EXPECT_EQ(s.striker.position.y, y0);
    const double facing = std::atan2(-y0, 20.0);
    EXPECT_EQ(s.striker.orientation_rad, facing);
    const double bx = (1.6 - 1e-12) * std::cos(facing);
    const double by = y0 + (1.6 - 1e-12) * std::sin(facing);
    EXPECT_NEAR(s.ball.position.x, bx, kTol);
    EXPECT_NEAR(s.ball.position.y, by, kTol);
    EXPECT_NEAR(std::hypot(s.ball.position.x, s.ball.position.y - y0), 1.6, 1e-9);
    const double grad = -by / (20 - bx);
    EXPECT_NEAR(s.keeper.position.x, 14.5, kTol);
    EXPECT_NEAR(s.keeper.position.y, std::clamp(by + grad * (14.5 - bx), -9.16, 9.16), kTol);
    EXPECT_NEAR(s.keeper.orientation_rad,
                std::atan2(s.ball.position.y - s.keeper.position.y, s.ball.position.x - s.keeper.position.x), kTol);
    EXPECT_EQ(s.ball.velocity.x, 0.0);
    EXPECT_EQ(obs[0], -1.0F);  // x = 0 is the low end of [0, 20]
    EXPECT_NEAR(obs[1], y0 / 15, 1e-6);
    EXPECT_NEAR(obs[4], facing / kPi, 1e-6);
  }
}

// With the noise on, the same start and the same action give different trajectories for
// different seeds; with it off they agree.
TEST(GoalEnvNoise, NoiseComesFromTheEnvsStreamAndCanBeSwitchedOff) {
  const GoalState start{.striker = at(10, 0), .keeper = at(17, 5), .ball = at(11.5, 0)};
  for (bool noise : {true, false}) {
    GoalEnv a(GoalConfig{.noise = noise}, 1);
    GoalEnv b(GoalConfig{.noise = noise}, 2);
    std::array<float, GoalEnv::kObservationSize> obs_a{};
    std::array<float, GoalEnv::kObservationSize> obs_b{};
    a.set_state(start, obs_a);
    b.set_state(start, obs_b);
    const std::array<float, 4> params{15.0F, 3.0F, 0, 0};
    a.step({GoalEnv::kKickTo, params}, obs_a);
    b.step({GoalEnv::kKickTo, params}, obs_b);
    EXPECT_EQ(obs_a == obs_b, !noise);
  }
}

TEST(GoalEnvDeathTest, MisuseStopsTheProcess) {
  GoalEnv env;
  std::array<float, GoalEnv::kObservationSize> obs{};
  env.reset(1, obs);
  const std::array<float, 4> params{};
  EXPECT_DEATH(env.step({3, params}, obs), "action id out of range");
  EXPECT_DEATH(env.step({0, std::span<const float>(params.data(), 2)}, obs), "4 Goal parameters");
}

TEST(GoalEnvSpace, ActionsOwnTheirParametersWithGymGoalsRanges) {
  const GoalEnv env;
  const ActionSpace& space = env.action_space();
  ASSERT_EQ(space.num_actions(), 3);
  ASSERT_EQ(space.num_params(), 4);
  EXPECT_EQ(space.actions[0].param_indices, (std::vector<int>{0, 1}));
  EXPECT_EQ(space.actions[1].param_indices, (std::vector<int>{2}));
  EXPECT_EQ(space.actions[2].param_indices, (std::vector<int>{3}));
  EXPECT_EQ(space.params[0].lo, 0.0F);
  EXPECT_EQ(space.params[0].hi, 40.0F);
  EXPECT_EQ(space.params[1].lo, -15.0F);
  EXPECT_EQ(space.params[1].hi, 15.0F);
  for (int p : {2, 3}) {
    EXPECT_EQ(space.params[static_cast<size_t>(p)].lo, -7.01F);
    EXPECT_EQ(space.params[static_cast<size_t>(p)].hi, 7.01F);
  }
  EXPECT_EQ(env.success_status(), GoalEnv::kGoal);
  EXPECT_EQ(env.status_name(GoalEnv::kGoal), "GOAL");
}

}  // namespace
}  // namespace pamdp::goal
