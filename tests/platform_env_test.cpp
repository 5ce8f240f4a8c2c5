// The Platform env (envs/platform/): steps worked out by hand from gym-platform's rules with the
// noise off, a course run to its end, the terminal outcomes, clipping, and seeded noise.
// The env conformance harness (env_conformance_test) runs it too, through the registry.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "envs/platform/platform_env.hpp"

namespace pamdp::platform {
namespace {

constexpr double kCourse = 1035.0;  // 250 + 225 + 275 + 235 + 50

StepResult step(PlatformEnv& env, int action, float param, std::vector<float>& obs) {
  std::array<float, 3> params{0.0F, 0.0F, 0.0F};
  params[static_cast<size_t>(action)] = param;
  return env.step({action, params}, obs);
}

TEST(PlatformEnv, ResetPutsThePlayerLeftAndTheEnemiesRight) {
  PlatformEnv env({.noise = false});
  std::vector<float> obs(9);
  env.reset(1, obs);
  EXPECT_EQ(env.player().x, 0.0);
  EXPECT_EQ(env.player().y, 40.0);
  EXPECT_EQ(env.enemy(0).x, 230.0);  // 250 wide, less its 20
  EXPECT_EQ(env.enemy(1).x, 730.0);  // 475 + 275 - 20
  EXPECT_EQ(env.enemy(0).dx, -30.0);
  EXPECT_FLOAT_EQ(obs[0], static_cast<float>(2.0 * 20.0 / 1055.0 - 1.0));
  EXPECT_FLOAT_EQ(obs[1], -1.0F);
  EXPECT_FLOAT_EQ(obs[2], static_cast<float>(2.0 * 230.0 / kCourse - 1.0));
  EXPECT_FLOAT_EQ(obs[3], -1.0F);  // dx -30 of [-30, 30]
  EXPECT_FLOAT_EQ(obs[4], static_cast<float>(2.0 * 250.0 / 275.0 - 1.0));
  EXPECT_FLOAT_EQ(obs[6], static_cast<float>(2.0 * 225.0 / 235.0 - 1.0));
  EXPECT_FLOAT_EQ(obs[8], -1.0F);  // no height differences
}

// RUN 30 from the start, by hand: 20 ticks; each adds 30 to dx (600 per second, the cap, for
// dt = 0.05), dx is held to 70 on the ground, moves x by dx * 0.05 and decays by 0.99. So dx
// before each move is 30, 59.7, then 70 for 18 ticks: x = 0.05 (30 + 59.7 + 18 * 70) = 67.485,
// dx = 69.3. The enemy, at its right end, turns twice (230 is not strictly inside (0, 230)),
// then walks left 1.5 a tick for 19 ticks: 201.5.
TEST(PlatformEnv, RunThirtyByHand) {
  PlatformEnv env({.noise = false});
  std::vector<float> obs(9);
  env.reset(1, obs);
  const StepResult r = step(env, PlatformEnv::kRun, 30.0F, obs);
  EXPECT_EQ(r.status, PlatformEnv::kInProgress);
  EXPECT_EQ(env.last_ticks(), 20);
  EXPECT_NEAR(env.player().x, 67.485, 1e-12);
  EXPECT_NEAR(env.player().dx, 69.3, 1e-12);
  EXPECT_EQ(env.player().y, 40.0);
  EXPECT_NEAR(env.enemy(0).x, 201.5, 1e-12);
  EXPECT_FLOAT_EQ(r.reward, static_cast<float>(67.485 / kCourse));
  EXPECT_FLOAT_EQ(obs[0], static_cast<float>(2.0 * (67.485 + 20.0) / 1055.0 - 1.0));
  EXPECT_FLOAT_EQ(obs[1], static_cast<float>(2.0 * 0.693 - 1.0));
  EXPECT_FLOAT_EQ(obs[2], static_cast<float>(2.0 * 201.5 / kCourse - 1.0));
}

// RUN 10: dx before the k-th move is 10 (1 - 0.99^k) / 0.01 until that passes 70 (k = 8), so
// x = 0.05 (sum over k = 1..7 of 1000 (1 - 0.99^k) + 13 * 70).
TEST(PlatformEnv, RunTenByHand) {
  PlatformEnv env({.noise = false});
  std::vector<float> obs(9);
  env.reset(1, obs);
  step(env, PlatformEnv::kRun, 10.0F, obs);
  double sum = 13.0 * 70.0;
  for (int k = 1; k <= 7; ++k) {
    sum += 1000.0 * (1.0 - std::pow(0.99, k));
  }
  EXPECT_NEAR(env.player().x, 0.05 * sum, 1e-9);  // 59.2234721396
}

// HOP 205 from the start, by hand: the jump's time is 2 * 35 / 9.8 + 1 = 8.142857, so dx0 =
// 205 / 8.142857 = 25.175 (under the 30 one tick can add) and dy = 35. In the air dy loses
// 9.8 * 0.05 = 0.49 a tick, so y = 40 + 0.05 (35 n - 0.245 n (n - 1)) falls below 40 first at
// n = 144, where the platform puts it back on top; x = 0.05 * 25.175 * (1 - 0.99^144) / 0.01.
TEST(PlatformEnv, HopByHand) {
  PlatformEnv env({.noise = false});
  std::vector<float> obs(9);
  env.reset(1, obs);
  const StepResult r = step(env, PlatformEnv::kHop, 205.0F, obs);
  EXPECT_EQ(r.status, PlatformEnv::kInProgress);
  EXPECT_EQ(env.last_ticks(), 144);
  const double dx0 = 205.0 / (2.0 * 35.0 / 9.8 + 1.0);
  EXPECT_NEAR(env.player().x, 0.05 * dx0 * (1.0 - std::pow(0.99, 144)) / 0.01, 1e-9);  // 96.2688
  EXPECT_EQ(env.player().y, 40.0);
  EXPECT_EQ(env.player().dx, 0.0);  // landing stops it
  EXPECT_EQ(env.player().dy, 0.0);
}

// A course run to its end, the actions found by a search on gym-platform's own code with the
// noise off; the positions after each step are that code's (printed to 17 digits). The return
// telescopes to exactly 1.
TEST(PlatformEnv, ACourseToTheEndMatchesGymPlatform) {
  struct Step {
    int action;
    float param;
    int ticks;
    double x;
  };
  const Step kCourseSteps[] = {
      {1, 205.0F, 144, 96.26878395087817},  {0, 17.0F, 20, 160.68420810087818},   {0, 7.0F, 20, 230.68420810087818},
      {1, 596.0F, 144, 498.35838786673474}, {1, 698.0F, 144, 613.0758934806732},  {0, 6.0F, 20, 663.6389624775774},
      {0, 11.0F, 20, 733.6389624775774},    {1, 585.0F, 144, 1001.3131422434336}, {2, 168.0F, 28, 1035.0},
  };
  PlatformEnv env({.noise = false});
  std::vector<float> obs(9);
  env.reset(1, obs);
  double ret = 0.0;
  StepResult r;
  for (const Step& s : kCourseSteps) {
    r = step(env, s.action, s.param, obs);
    ret += r.reward;
    EXPECT_EQ(env.last_ticks(), s.ticks);
    EXPECT_NEAR(env.player().x, s.x, 1e-9);
  }
  EXPECT_EQ(r.status, PlatformEnv::kGoal);
  EXPECT_NEAR(ret, 1.0, 1e-6);
}

// HOP 100 from the start lands on the enemy walking left: gym-platform's code ends it on tick
// 125 with the player at x = 43.92 and the enemy at 44.
TEST(PlatformEnv, TouchingAnEnemyEndsTheEpisode) {
  PlatformEnv env({.noise = false});
  std::vector<float> obs(9);
  env.reset(1, obs);
  const StepResult r = step(env, PlatformEnv::kHop, 100.0F, obs);
  EXPECT_EQ(r.status, PlatformEnv::kEnemy);
  EXPECT_EQ(env.last_ticks(), 125);
  EXPECT_NEAR(env.player().x, 43.92145251831252, 1e-9);
  EXPECT_NEAR(env.enemy(0).x, 44.0, 1e-9);
}

// Running off the first platform's end falls into the gap: the first tick in the air puts the
// player below the top, at 40 - 0.49 * 0.05 = 39.9755 (gym-platform's code: tick 7, x 255.149).
TEST(PlatformEnv, RunningIntoTheGapFalls) {
  PlatformEnv env({.noise = false});
  std::vector<float> obs(9);
  env.reset(1, obs);
  step(env, PlatformEnv::kHop, 205.0F, obs);
  step(env, PlatformEnv::kRun, 17.0F, obs);
  step(env, PlatformEnv::kRun, 7.0F, obs);  // x 230.68, 250 is the platform's end
  const StepResult r = step(env, PlatformEnv::kRun, 30.0F, obs);
  EXPECT_EQ(r.status, PlatformEnv::kFell);
  EXPECT_EQ(env.last_ticks(), 7);
  EXPECT_NEAR(env.player().y, 39.9755, 1e-12);
  EXPECT_NEAR(env.player().x, 255.14920810087818, 1e-9);
}

TEST(PlatformEnv, ParametersAreClippedToTheirRanges) {
  PlatformEnv a({.noise = false});
  PlatformEnv b({.noise = false});
  std::vector<float> oa(9);
  std::vector<float> ob(9);
  a.reset(1, oa);
  b.reset(1, ob);
  step(a, PlatformEnv::kRun, 1000.0F, oa);  // clipped to 30
  step(b, PlatformEnv::kRun, 30.0F, ob);
  EXPECT_EQ(a.player().x, b.player().x);
  a.reset(1, oa);
  step(a, PlatformEnv::kRun, -5.0F, oa);  // clipped to 0: no move
  EXPECT_EQ(a.player().x, 0.0);
  a.reset(1, oa);
  step(a, PlatformEnv::kRun, std::nanf(""), oa);  // NaN counts as 0
  EXPECT_EQ(a.player().x, 0.0);
}

TEST(PlatformEnv, OutOfTimeAfterMaxSteps) {
  PlatformEnv env({.noise = false, .max_steps = 2});
  std::vector<float> obs(9);
  env.reset(1, obs);
  EXPECT_EQ(step(env, PlatformEnv::kRun, 1.0F, obs).status, PlatformEnv::kInProgress);
  EXPECT_EQ(step(env, PlatformEnv::kRun, 1.0F, obs).status, PlatformEnv::kOutOfTime);
  EXPECT_THROW(PlatformEnv({.max_steps = 0}), std::invalid_argument);
}

// With noise, a seed gives one episode, and the noise only slows the player (|N| is taken off
// dx): the same run covers less ground than without it.
TEST(PlatformEnv, SeededNoiseIsReproducibleAndSlows) {
  PlatformEnv a;
  PlatformEnv b;
  PlatformEnv quiet({.noise = false});
  std::vector<float> oa(9);
  std::vector<float> ob(9);
  std::vector<float> oq(9);
  a.reset(42, oa);
  b.reset(42, ob);
  quiet.reset(42, oq);
  step(a, PlatformEnv::kRun, 20.0F, oa);
  step(b, PlatformEnv::kRun, 20.0F, ob);
  step(quiet, PlatformEnv::kRun, 20.0F, oq);
  EXPECT_EQ(oa, ob);
  EXPECT_LT(a.player().x, quiet.player().x);
  EXPECT_GT(a.player().x, quiet.player().x - 1.0);
  b.reset(43, ob);
  step(b, PlatformEnv::kRun, 20.0F, ob);
  EXPECT_NE(a.player().x, b.player().x);
}

}  // namespace
}  // namespace pamdp::platform
