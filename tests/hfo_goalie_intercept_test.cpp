// librcsc's intercept table and Body_Intercept2009 as ported for agent2d's goalie
// (envs/hfo/goalie_intercept.cpp), on situations worked out by hand in the goalie's frame
// (its goal at x = -52.5). Noise parameters are 0 unless a test says otherwise, as in the
// recorded real games. Operator new is counted here, so this is a binary of its own.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "counting_new.hpp"
#include "envs/hfo/goalie_world.hpp"

namespace pamdp::hfo::agent2d {
namespace {

using pamdp::testing::alloc::CountAllocations;

GoalieWorld world(Vec2 self_pos, double body_deg, Vec2 ball_pos, Vec2 ball_vel) {
  GoalieWorld w;
  w.self.pos = self_pos;
  w.self.body_deg = body_deg;
  w.ball_pos = ball_pos;
  w.ball_vel = ball_vel;
  w.ball_rand = 0.0;
  w.player_rand = 0.0;
  w.finish();
  return w;
}

void add_opponent(GoalieWorld* w, Vec2 pos, double body_deg) {
  PlayerView& o = w->opponents[static_cast<size_t>(w->num_opponents++)];
  o.pos = pos;
  o.body_deg = body_deg;
  w->finish();
}

// Distance covered by n full dashes from rest, speed 0.6 (1 - 0.4^k) after k dashes.
double dash_distance(int n) {
  double d = 0.0;
  for (int k = 1; k <= n; ++k) {
    d += 1.0 - std::pow(0.4, k);
  }
  return d;
}

TEST(GoalieIntercept, BallWithinReachIsReachedNow) {
  const GoalieWorld w = world({-50.0, 0.0}, 0.0, {-49.2, 0.5}, {-1.0, 0.0});
  ASSERT_TRUE(w.self_kickable);  // 0.94 m <= 1.085 - 0.055
  InterceptTable t;
  predict_intercepts(w, &t);
  EXPECT_EQ(t.self_reach_cycle, 0);
  EXPECT_EQ(t.ball_cache_size, 1);  // createBallCache stops at the current position
  EXPECT_EQ(t.self_cache_size, 0);
}

// A ball rolling straight at the goalie, who faces it: ball at -40 with speed 1.5 toward the
// goal; after n cycles it is at -40 - 25 (1 - 0.94^n): 4.519 m away after 4, 3.348 after 5.
// Four full dashes cover 3.350 m, leaving 1.169 m, just outside the 1.3 - 0.15 = 1.15 m
// that predictDashCycleShort asks for; five dashes (the last ones eased) end on the ball.
TEST(GoalieIntercept, BallRollingAtTheGoalieIsReachedOnTheFifthCycle) {
  const GoalieWorld w = world({-50.0, 0.0}, 0.0, {-40.0, 0.0}, {-1.5, 0.0});
  const double ball4 = -40.0 - 25.0 * (1.0 - std::pow(0.94, 4));
  ASSERT_GT(ball4 - (-50.0) - dash_distance(4), kCatchableArea - 0.15);
  InterceptTable t;
  predict_intercepts(w, &t);
  EXPECT_EQ(t.self_reach_cycle, 5);
  const InterceptInfo& first = t.self_cache[0];
  EXPECT_EQ(first.turn_cycle, 0);
  EXPECT_EQ(first.dash_cycle, 5);
  EXPECT_DOUBLE_EQ(first.dash_power, 100.0);
  EXPECT_LT(first.ball_dist, 0.01);
  EXPECT_EQ(t.opponent_reach_cycle, 1000);  // no opponents
  EXPECT_EQ(t.teammate_reach_cycle, 1000);

  // Body_Intercept2009: the goalie branch picks that catch (turn 0, ball within 0.65 m, the
  // one farthest from the goal); the target is 3.35 m ahead, too far for doInertiaDash's
  // eased power (1.085 + 0.48), so it dashes at full power straight ahead.
  Command c;
  ASSERT_TRUE(body_intercept(w, t, false, &c));
  EXPECT_EQ(c.kind, Command::Kind::kDash);
  EXPECT_DOUBLE_EQ(c.p1, 100.0);
  EXPECT_DOUBLE_EQ(c.p2, 0.0);
}

// The ball comes within catching reach next cycle with no dash (predictNoDash, goalie mode:
// 1.1 m < 1.3 - 0.15): one turn and no dash. Body_Intercept2009 then turns to the face point
// (50.5, 0): from a body of 90 degrees, a turn of -90 at rest.
TEST(GoalieIntercept, BallArrivingIntoCatchReachTurnsToTheFacePoint) {
  const GoalieWorld w = world({-50.0, 0.0}, 90.0, {-48.0, 0.0}, {-0.9, 0.0});
  ASSERT_FALSE(w.self_kickable);
  InterceptTable t;
  predict_intercepts(w, &t);
  EXPECT_EQ(t.self_reach_cycle, 1);
  EXPECT_EQ(t.self_cache[0].turn_cycle, 1);
  EXPECT_EQ(t.self_cache[0].dash_cycle, 0);
  Command c;
  ASSERT_TRUE(body_intercept(w, t, false, &c));
  EXPECT_EQ(c.kind, Command::Kind::kTurn);
  EXPECT_NEAR(c.p1, -90.0, 1e-9);
}

// A ball 1.12 m away next cycle is within 1.3 - 0.15 with noise off, but not with the
// server's ball_rand 0.05 (1.15 - 0.9 x 0.05 = 1.105): the no-dash way is then refused.
TEST(GoalieIntercept, BallNoiseNarrowsTheNoDashReach) {
  GoalieWorld w = world({-50.0, 0.0}, 90.0, {-47.98, 0.0}, {-0.9, 0.0});
  auto no_dash_first = [&] {
    InterceptTable t;
    predict_intercepts(w, &t);
    return t.self_cache_size > 0 && t.self_cache[0].turn_cycle == 1 && t.self_cache[0].dash_cycle == 0;
  };
  EXPECT_TRUE(no_dash_first());
  w.ball_rand = kBallRand;
  EXPECT_FALSE(no_dash_first());
}

// A ball passing far up the field, (0, 20) at 2 m/cycle along +x: no way within the 30
// cycles, so predictFinal aims at where it stops, (33.3, 20), 85.7 m away: 13.5 degrees off
// the body, more than the 12.5 degree margin, so one turn; 84.6 m less the kick reach take
// 50 table dashes (49.33 m) and 36 more at 1 m: 86 dashes.
TEST(GoalieIntercept, BallPassingFarGivesTheFinalPointEstimate) {
  const GoalieWorld w = world({-50.0, 0.0}, 0.0, {0.0, 20.0}, {2.0, 0.0});
  InterceptTable t;
  predict_intercepts(w, &t);
  EXPECT_EQ(t.ball_cache_size, InterceptTable::kMaxCycle + 1);
  ASSERT_EQ(t.self_cache_size, 1);
  EXPECT_EQ(t.self_cache[0].turn_cycle, 1);
  EXPECT_EQ(t.self_cache[0].dash_cycle, 86);
  EXPECT_EQ(t.self_reach_cycle, 87);

  // Body_Intercept2009 takes it (the goalie's aggressive branch: outside its area, ball
  // distance 0) and turns first: toward the ball's position after 87 cycles.
  Command c;
  ASSERT_TRUE(body_intercept(w, t, false, &c));
  EXPECT_EQ(c.kind, Command::Kind::kTurn);
  const double k = (1.0 - std::pow(kBallDecay, 87)) / (1.0 - kBallDecay);
  const double want = std::atan2(20.0, 2.0 * k + 50.0) * kRadToDeg;
  EXPECT_NEAR(c.p1, want, 1e-3);
}

// An attacker 5 m beside a ball at rest, facing it: no turn, and 5 - 1.085 = 3.915 m take
// five dashes (3.350 after four, 4.340 after five).
TEST(GoalieIntercept, OpponentFacingTheBallReachesItInFiveCycles) {
  GoalieWorld w = world({-50.0, 0.0}, 0.0, {-30.0, 0.0}, {0.0, 0.0});
  add_opponent(&w, {-30.0, 5.0}, -90.0);
  InterceptTable t;
  predict_intercepts(w, &t);
  EXPECT_EQ(t.ball_cache_size, 6);  // a ball at rest: cached for five cycles
  EXPECT_EQ(t.opponent_reach_cycle, 5);
}

// Facing away by 90 degrees it needs a turn, and then only four dashes remain by cycle 5:
// predictFinal counts one turn and dashes over 3.915 m less 3 % of its 20.6 m from the
// goalie (four), and at least the six cached cycles: 6.
TEST(GoalieIntercept, OpponentThatMustTurnFallsBackToTheFinalEstimate) {
  GoalieWorld w = world({-50.0, 0.0}, 0.0, {-30.0, 0.0}, {0.0, 0.0});
  add_opponent(&w, {-30.0, 5.0}, 0.0);
  InterceptTable t;
  predict_intercepts(w, &t);
  EXPECT_EQ(t.opponent_reach_cycle, 6);
}

TEST(GoalieIntercept, KickableOpponentReachesNow) {
  GoalieWorld w = world({-50.0, 0.0}, 0.0, {-30.0, 0.0}, {0.0, 0.0});
  add_opponent(&w, {-30.5, 0.0}, 0.0);
  ASSERT_TRUE(w.exist_kickable_opponent);
  InterceptTable t;
  predict_intercepts(w, &t);
  EXPECT_EQ(t.opponent_reach_cycle, 0);
}

// A ball 0.8 m beside the goalie's path with an attacker on it, within 2 m of the goalie and
// farther from the goal: doKickableOpponentCheck sends it at the attacker's next position.
TEST(GoalieIntercept, KickableOpponentCloseByIsAttacked) {
  GoalieWorld w = world({-48.0, 0.0}, 0.0, {-46.5, 0.0}, {0.0, 0.0});
  add_opponent(&w, {-45.8, 0.0}, 180.0);
  ASSERT_TRUE(w.exist_kickable_opponent);
  InterceptTable t;
  predict_intercepts(w, &t);
  Command c;
  ASSERT_TRUE(body_intercept(w, t, false, &c));
  // Straight ahead, 2.2 m: Body_GoToPoint dashes forward.
  EXPECT_EQ(c.kind, Command::Kind::kDash);
  EXPECT_GT(c.p1, 0.0);
  EXPECT_DOUBLE_EQ(c.p2, 0.0);
}

// getOneStepDashPower divides by dashDirRate of the global dash angle (librcsc passes it for
// a relative one), and ServerParam::dashDirRate discretizes first: 12.5 degrees becomes 0 and
// the rate 1, so the one dash straight ahead is the wanted acceleration / 0.006. Without the
// discretization the rate would be 0.4 + 0.6 (1 - 12.5 / 90) = 0.917 and the power 98.64.
// (A state where two independent ports first disagreed.)
TEST(GoalieIntercept, OneStepDashRateDiscretizesTheGlobalAngle) {
  GoalieWorld w = world({-42.605221884983081, -8.3356815769333288}, 12.51567821915782,
                        {-42.019554580501833, -6.383216969855571}, {-0.2716937026711323, -0.86361212902227169});
  w.ball_rand = kBallRand;
  w.player_rand = kPlayerRand;
  add_opponent(&w, {-41.997249388391197, -10.274543660642859}, -113.20959439084903);
  InterceptTable t;
  predict_intercepts(w, &t);
  ASSERT_EQ(t.self_reach_cycle, 1);
  EXPECT_EQ(t.self_cache[0].turn_cycle, 0);
  EXPECT_EQ(t.self_cache[0].dash_cycle, 1);
  EXPECT_NEAR(t.self_cache[0].dash_power, 90.412, 1e-3);
  Command c;
  ASSERT_TRUE(body_intercept(w, t, false, &c));
  EXPECT_EQ(c.kind, Command::Kind::kDash);
  EXPECT_DOUBLE_EQ(c.p1, 90.412);
}

// 22 ways to the ball, with pairs of equal reach and turn count (a wait and a dash each
// cycle): librcsc sorts them with std::sort, whose introsort reorders equal entries past 16,
// and Body_Intercept2009 keeps the first of equal scores. Here that is a full dash at cycle 12
// (goalie branch, ball 0.2 m away), not the wait that a stable sort would leave first (which
// would turn instead).
TEST(GoalieIntercept, SelfCacheOrderFollowsStdSort) {
  GoalieWorld w = world({-49.33550910745609, -9.1216689793570431}, -7.0122837070174739,
                        {-52.392900175414731, -6.4156341049677685}, {0.77424116943124233, -0.3848604957370888});
  w.self.stamina = 2360.8042519081896;
  add_opponent(&w, {-56.910325001261057, -1.6198358102319599}, -135.70499943892764);
  w.opponents[0].vel = {0.030303765206168176, -0.011217222109090874};
  w.finish();
  InterceptTable t;
  predict_intercepts(w, &t);
  ASSERT_EQ(t.self_cache_size, 22);
  EXPECT_EQ(t.opponent_reach_cycle, 16);
  Command c;
  ASSERT_TRUE(body_intercept(w, t, false, &c));
  EXPECT_EQ(c.kind, Command::Kind::kDash);
  EXPECT_DOUBLE_EQ(c.p1, 100.0);
  EXPECT_DOUBLE_EQ(c.p2, 0.0);
}

TEST(GoalieIntercept, CountingAllocatorSeesAllocations) {
  long n = 0;
  {
    CountAllocations scope;
    auto p = std::make_unique<int>(1);
    n = scope.count();
  }
  EXPECT_GE(n, 1);
}

TEST(GoalieIntercept, AllocatesNothing) {
  const GoalieWorld worlds[] = {
      world({-50.0, 0.0}, 0.0, {-40.0, 0.0}, {-1.5, 0.0}),    world({-50.0, 0.0}, 90.0, {-48.0, 0.0}, {-0.9, 0.0}),
      world({-50.0, 0.0}, 0.0, {0.0, 20.0}, {2.0, 0.0}),      world({-45.0, 3.0}, -120.0, {-35.0, -5.0}, {-2.0, 0.8}),
      world({-50.0, 2.0}, 180.0, {-44.0, 6.0}, {-0.3, -1.2}),
  };
  InterceptTable t;
  Command c;
  predict_intercepts(worlds[0], &t);  // one-time set-up (the dash distance table) outside
  long n = 0;
  {
    CountAllocations scope;
    for (const GoalieWorld& w : worlds) {
      predict_intercepts(w, &t);
      body_intercept(w, t, true, &c);
      body_intercept(w, t, false, &c);
    }
    n = scope.count();
  }
  EXPECT_EQ(n, 0);
}

}  // namespace
}  // namespace pamdp::hfo::agent2d
