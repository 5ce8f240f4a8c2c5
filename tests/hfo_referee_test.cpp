// Episode rules (server referee, shared/hfo-reference.md §5.2), the shaped reward of dqn-hfo
// (§6.2) and the start distributions (§5.1), against hand-computed values.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <utility>

#include "envs/hfo/features.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {
namespace {

constexpr double kTol = 1e-9;
// 2 / R with R = sqrt(52.5^2 + 34^2) = 62.5479816: 0.0319755 reward per metre.
const double kPerMetre = 2.0 / std::sqrt(52.5 * 52.5 + 34.0 * 34.0);
// Rewards come from float32 features: allow a few float ulps of the proximities.
constexpr double kRewardTol = 2e-6;

SoccerSimConfig quiet_config() {
  SoccerSimConfig c;
  c.noise = false;
  return c;
}

PlayerState make_agent(Vec2 pos, double body_deg = 0.0, Vec2 vel = {}) {
  PlayerState p;
  p.pos = pos;
  p.body_deg = body_deg;
  p.vel = vel;
  return p;
}

SoccerSim sim_with(Vec2 agent_pos, Vec2 ball_pos, Vec2 ball_vel = {}) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent(agent_pos), BallState{ball_pos, ball_vel});
  return sim;
}

// ---------------------------------------------------------------------------------------
// §5.2 GOAL: |prev.x| <= 52.585, ball.x > 52.585 and the line prev -> ball meets x = 52.585 at
// |y| <= 7.07.

// Ball (52, 0) moving (1, 0): ends at 53 > 52.585, crossing at y = 0 -> GOAL.
TEST(HfoReferee, GoalStraightIn) {
  SoccerSim sim = sim_with({40.0, 10.0}, {52.0, 0.0}, {1.0, 0.0});
  EXPECT_EQ(sim.step(), kGoal);
}

// Ball (52, 6) moving (1, 1.2): crossing at t = 0.585 -> y = 6 + 0.585 * 1.2 = 6.702 <= 7.07 ->
// GOAL, although the ball ends at y = 7.2 (outside the mouth). The path passes the post
// (52.44, 7.07) at |0.44 * 1.2 - 1.07 * 1| / sqrt(1 + 1.44) = 0.542 / 1.562 = 0.347 > 0.145: no bounce.
TEST(HfoReferee, GoalDecidedByCrossingPoint) {
  SoccerSim sim = sim_with({40.0, -10.0}, {52.0, 6.0}, {1.0, 1.2});
  EXPECT_EQ(sim.step(), kGoal);
  EXPECT_NEAR(sim.state().ball.pos.x, 53.0, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 7.2, kTol);
}

// Ball (52, 9) moving (1, -2.1): crossing at y = 9 - 0.585 * 2.1 = 7.7715 > 7.07 -> no goal, even
// though the ball ends at y = 6.9 inside the mouth (post distance |0.44 * -2.1 + 1.93| / 2.326 =
// 0.4325 > 0.145: no bounce). The ball is now outside the HFO area, so the next check (prev
// = (53, 6.9), x > 52.5) is OUT_OF_BOUNDS.
TEST(HfoReferee, NoGoalWhenCrossingOutsidePostMargin) {
  SoccerSim sim = sim_with({40.0, -10.0}, {52.0, 9.0}, {1.0, -2.1});
  EXPECT_EQ(sim.step(), kInGame);
  EXPECT_NEAR(sim.state().ball.pos.x, 53.0, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 6.9, kTol);
  EXPECT_EQ(sim.step(), kOutOfBounds);
}

// Ball (52, 7.5) moving (1, 0): crossing at y = 7.5 > 7.07 (0.43 from the post, no bounce) ->
// IN_GAME, then OUT_OF_BOUNDS one cycle later.
TEST(HfoReferee, NoGoalWideOfThePost) {
  SoccerSim sim = sim_with({40.0, -10.0}, {52.0, 7.5}, {1.0, 0.0});
  EXPECT_EQ(sim.step(), kInGame);
  EXPECT_NEAR(sim.state().ball.pos.y, 7.5, kTol);
  EXPECT_EQ(sim.step(), kOutOfBounds);
}

// The goal line is x = 52.5 + 0.085 = 52.585. Ball (52, 0) moving (0.55, 0): ends at 52.55 (past
// 52.5 but not 52.585) -> IN_GAME (and prev 52.0 is inside, so no OOB). Next cycle: 52.55 + 0.517
// = 53.067 > 52.585 with prev 52.55 (<= 52.585) -> GOAL, checked before the OOB rule (prev 52.55
// lies outside x <= 52.5).
TEST(HfoReferee, GoalLineIncludesBallRadius) {
  SoccerSim sim = sim_with({40.0, 10.0}, {52.0, 0.0}, {0.55, 0.0});
  EXPECT_EQ(sim.step(), kInGame);
  EXPECT_NEAR(sim.state().ball.pos.x, 52.55, kTol);
  EXPECT_EQ(sim.step(), kGoal);
}

// A ball that starts behind the goal line (prev.x = 53 > 52.585) cannot score.
TEST(HfoReferee, NoGoalFromBehindTheLine) {
  SoccerSim sim = sim_with({40.0, 10.0}, {53.0, 0.0}, {0.5, 0.0});
  EXPECT_EQ(sim.step(), kOutOfBounds);
}

// §5.2 OUT_OF_BOUNDS is tested on the previous position, so it is declared one cycle after the
// ball leaves x in [0, 52.5], |y| <= 34.
//   left:   (1, 0) moving (-2, 0) -> -1 (IN_GAME), then OOB.
//   top:    (20, -33.5) moving (0, -1) -> -34.5 (IN_GAME), then OOB.
//   bottom: (20, 33.5) moving (0, 1) -> 34.5 (IN_GAME), then OOB.
//   right, outside the goal: (52, 20) moving (1, 0) -> 53 (IN_GAME), then OOB.
TEST(HfoReferee, OutOfBoundsOneCycleLate) {
  struct Case {
    Vec2 pos;
    Vec2 vel;
  };
  const Case cases[] = {
      {{1.0, 0.0}, {-2.0, 0.0}}, {{20.0, -33.5}, {0.0, -1.0}}, {{20.0, 33.5}, {0.0, 1.0}}, {{52.0, 20.0}, {1.0, 0.0}}};
  for (const Case& c : cases) {
    SoccerSim sim = sim_with({30.0, 5.0}, c.pos, c.vel);
    EXPECT_EQ(sim.step(), kInGame) << c.pos.x << "," << c.pos.y;
    EXPECT_EQ(sim.step(), kOutOfBounds) << c.pos.x << "," << c.pos.y;
  }
}

// The line itself is inside: ball (0.5, 0) moving (-0.5, 0) stops exactly on x = 0 (IN_GAME), then
// rolls to 0 - 0.47 = -0.47 (prev 0.0 still inside: IN_GAME), then OOB.
TEST(HfoReferee, BallOnTheHalfwayLineIsIn) {
  SoccerSim sim = sim_with({30.0, 5.0}, {0.5, 0.0}, {-0.5, 0.0});
  EXPECT_EQ(sim.step(), kInGame);
  EXPECT_NEAR(sim.state().ball.pos.x, 0.0, kTol);
  EXPECT_EQ(sim.step(), kInGame);
  EXPECT_EQ(sim.step(), kOutOfBounds);
}

// §5.2 OUT_OF_TIME from the untouched counter: step k checks counter (k - 1) > 100 before
// incrementing it, so steps 1..101 are IN_GAME and step 102 ends the episode. The agent stays
// 1.09 m from the ball (> 1.085: not a touch).
TEST(HfoReferee, UntouchedLimitFiresAtStep102) {
  SoccerSim sim = sim_with({20.0, 0.0}, {21.09, 0.0});
  for (int k = 1; k <= 101; ++k) {
    ASSERT_EQ(sim.step(), kInGame) << "step " << k;
  }
  EXPECT_EQ(sim.step(), kOutOfTime);
}

// §5.2 time limit: with the ball within 1.085 (here 1.08 m: a touch for the referee though not
// kickable for the client) the untouched counter stays 0, and the check cycle > 500 fires at
// step 501.
TEST(HfoReferee, TimeLimitFiresAtStep501) {
  SoccerSim sim = sim_with({20.0, 0.0}, {21.08, 0.0});
  EXPECT_FALSE(sim.agent_kickable());
  for (int k = 1; k <= 500; ++k) {
    ASSERT_EQ(sim.step(), kInGame) << "step " << k;
  }
  EXPECT_EQ(sim.step(), kOutOfTime);
}

// A touch resets the untouched counter. Agent far for steps 1..90 (counter 90), next to the ball
// for step 91 (counter -> 0), far again: step k >= 92 checks (k - 92) > 100 -> OOT at step 193.
TEST(HfoReferee, TouchResetsUntouchedCounter) {
  SoccerSim sim = sim_with({20.0, 0.0}, {30.0, 0.0});
  for (int k = 1; k <= 90; ++k) {
    ASSERT_EQ(sim.step(), kInGame) << "step " << k;
  }
  sim.mutable_state().players[0].pos = {29.0, 0.0};  // 1 m from the ball
  ASSERT_EQ(sim.step(), kInGame);                    // step 91
  sim.mutable_state().players[0].pos = {20.0, 0.0};
  for (int k = 92; k <= 192; ++k) {
    ASSERT_EQ(sim.step(), kInGame) << "step " << k;
  }
  EXPECT_EQ(sim.step(), kOutOfTime);  // step 193
}

// ---------------------------------------------------------------------------------------
// §6.2 shaped reward through HfoEnv.

class HfoReward : public ::testing::Test {
 protected:
  explicit HfoReward(int out_of_bounds_penalty = 0) : env_(quiet_config(), false, out_of_bounds_penalty) {}

  void start(const PlayerState& agent, const BallState& ball) { env_.set_state(agent, ball, obs_); }

  StepResult act(int id, std::initializer_list<std::pair<int, float>> values) {
    params_.fill(0.0F);
    for (const auto& [i, v] : values) {
      params_[static_cast<size_t>(i)] = v;
    }
    return env_.step(ParamAction{id, params_}, obs_);
  }
  StepResult dash(float power, float dir) { return act(kDash, {{param::kDashPower, power}, {param::kDashDir, dir}}); }
  StepResult idle() { return act(kTurn, {{param::kTurnDir, 0.0F}}); }

  HfoEnv env_;
  std::array<float, 58> obs_{};
  std::array<float, param::kCount> params_{};
};

// Agent at (0, 0) moving (0.4, 0) (dash steady state), ball at rest at (30, 0), straight ahead
// with the goal: each Dash(100, 0) moves the agent 0.4 + 0.6 = 1.0 m closer. The ball-goal
// distance does not change (0 shaping from it).
//   transition 1: first of the episode -> 0 exactly.
//   transitions 2, 3: dP = 2 * 1.0 / R = 0.0319755 each.
TEST_F(HfoReward, OneMetreCloserIsWorth0_031975) {
  start(make_agent({0.0, 0.0}, 0.0, {0.4, 0.0}), BallState{{30.0, 0.0}, {}});
  StepResult r = dash(100.0F, 0.0F);
  EXPECT_EQ(r.status, kInGame);
  EXPECT_EQ(r.reward, 0.0F);
  EXPECT_NEAR(env_.sim().agent().pos.x, 1.0, kTol);
  r = dash(100.0F, 0.0F);
  EXPECT_NEAR(env_.sim().agent().pos.x, 2.0, kTol);
  EXPECT_NEAR(r.reward, 0.0319755, kRewardTol);
  EXPECT_NEAR(r.reward, kPerMetre, kRewardTol);
  r = dash(100.0F, 0.0F);
  EXPECT_NEAR(r.reward, kPerMetre, kRewardTol);
}

// Moving 1 m away costs the same: agent moving (-0.4, 0) with Dash(-100, 0) (back dash, full
// rate): -0.4 - 0.6 = -1.0 m per cycle -> -0.0319755 from the second transition on.
TEST_F(HfoReward, OneMetreFartherCosts0_031975) {
  start(make_agent({10.0, 0.0}, 0.0, {-0.4, 0.0}), BallState{{30.0, 0.0}, {}});
  EXPECT_EQ(dash(-100.0F, 0.0F).reward, 0.0F);
  const StepResult r = dash(-100.0F, 0.0F);
  EXPECT_NEAR(env_.sim().agent().pos.x, 8.0, kTol);
  EXPECT_NEAR(r.reward, -kPerMetre, kRewardTol);
}

// Ball (30, 0) rolling (1, 0) toward the goal, agent idle at (0, 0) (Turn(0)).
//   transition 1: 0 (first).
//   transition 2: the ball moves 0.94 m: agent-ball +0.94 -> dP = -0.94 * 2/R; ball-goal -0.94 ->
//   -3 dD = +3 * 0.94 * 2/R. r = (3 - 1) * 0.94 * 0.0319755 = 1.88 * 0.0319755 = 0.0601138.
TEST_F(HfoReward, BallTowardGoalTermIsTripled) {
  start(make_agent({0.0, 0.0}), BallState{{30.0, 0.0}, {1.0, 0.0}});
  EXPECT_EQ(idle().reward, 0.0F);
  const StepResult r = idle();
  EXPECT_NEAR(env_.sim().state().ball.pos.x, 31.94, kTol);
  EXPECT_NEAR(r.reward, 1.88 * kPerMetre, 3 * kRewardTol);
  EXPECT_NEAR(r.reward, 0.0601138, 3 * kRewardTol);
}

// The ball-goal distance comes from the law of cosines on the egocentric bearings and
// proximities (§6.2), which reproduces the true distance in units of 2/R. Ball off the
// agent-goal line: agent (0, 0) body 0 idle, ball (30, 10) rolling (1, 0).
//   t1: ball -> (31, 10) (first transition, 0).
//   t2: ball -> (31.94, 10):
//     agent-ball sqrt(31^2 + 10^2) = sqrt(1061) = 32.5729949 -> sqrt(31.94^2 + 100) =
//       sqrt(1120.1636) = 33.4688452: change -0.8958503 (farther)
//     ball-goal sqrt(21.5^2 + 100) = sqrt(562.25) = 23.7118114 -> sqrt(20.56^2 + 100) =
//       sqrt(522.7136) = 22.8629307: change +0.8488807 (closer)
//     r = 0.0319755 * (-0.8958503 + 3 * 0.8488807) = 0.0319755 * 1.6507918 = 0.0527848.
TEST_F(HfoReward, KickToGoalTermUsesLawOfCosines) {
  start(make_agent({0.0, 0.0}), BallState{{30.0, 10.0}, {1.0, 0.0}});
  EXPECT_EQ(idle().reward, 0.0F);
  const StepResult r = idle();
  EXPECT_NEAR(env_.sim().state().ball.pos.x, 31.94, kTol);
  EXPECT_NEAR(r.reward, 0.0527848, 1e-5);
}

// Kickable bonus, paid once. Agent (0, 0) body 0 at rest, ball at rest at (1.5, 0).
//   t1 Turn(0):      0 (first transition); not kickable (1.5 m).
//   t2 Dash(100, 0): agent 0 -> 0.6, ball 0.9 m away: kickable -1 -> +1 (dK = 2 >= 1): bonus 1;
//                    dP = 0.6 * 2/R = 0.0191853 -> r = 1.0191853.
//   t3 Turn(0):      drift 0.24 -> x 0.84 (0.66 m): r = 0.24 * 2/R = 0.0076741.
//   t4 Dash(-100,0): v = 0.096 - 0.6 = -0.504 -> x 0.336, 1.164 m: not kickable;
//                    r = -0.504 * 2/R = -0.0161157.
//   t5 Dash(100, 0): v = -0.2016 + 0.6 = 0.3984 -> x 0.7344, 0.7656 m: kickable again but the bonus
//                    was paid: r = 0.3984 * 2/R = 0.0127390.
TEST_F(HfoReward, KickableBonusPaidOnce) {
  start(make_agent({0.0, 0.0}), BallState{{1.5, 0.0}, {}});
  StepResult r = idle();
  EXPECT_EQ(r.reward, 0.0F);
  EXPECT_EQ(obs_[feat::kKickable], -1.0F);
  r = dash(100.0F, 0.0F);
  EXPECT_EQ(obs_[feat::kKickable], 1.0F);
  EXPECT_NEAR(r.reward, 1.0 + 0.6 * kPerMetre, kRewardTol);
  EXPECT_NEAR(r.reward, 1.0191853, kRewardTol);
  r = idle();
  EXPECT_NEAR(env_.sim().agent().pos.x, 0.84, kTol);
  EXPECT_NEAR(r.reward, 0.24 * kPerMetre, kRewardTol);
  r = dash(-100.0F, 0.0F);
  EXPECT_NEAR(env_.sim().agent().pos.x, 0.336, kTol);
  EXPECT_EQ(obs_[feat::kKickable], -1.0F);
  EXPECT_NEAR(r.reward, -0.504 * kPerMetre, kRewardTol);
  r = dash(100.0F, 0.0F);
  EXPECT_NEAR(env_.sim().agent().pos.x, 0.7344, kTol);
  EXPECT_EQ(obs_[feat::kKickable], 1.0F);
  EXPECT_NEAR(r.reward, 0.3984 * kPerMetre, kRewardTol);
}

// The first transition has no shaping at all, so becoming kickable in it earns no bonus, and a
// later step in which the agent stays kickable earns none either (§6.2: dK is taken between two
// non-first steps). Agent (0, 0), ball (1.5, 0): t1 Dash(100, 0) -> 0.9 m (kickable): r = 0;
// t2 Turn(0): drift 0.24 m, still kickable: r = 0.24 * 2/R = 0.0076741, no bonus.
TEST_F(HfoReward, NoBonusOnFirstTransition) {
  start(make_agent({0.0, 0.0}), BallState{{1.5, 0.0}, {}});
  StepResult r = dash(100.0F, 0.0F);
  EXPECT_EQ(obs_[feat::kKickable], 1.0F);
  EXPECT_EQ(r.reward, 0.0F);
  r = idle();
  EXPECT_NEAR(r.reward, 0.24 * kPerMetre, kRewardTol);
}

// Goal: ball (51, 0) rolling (1, 0), agent idle at (40, 10).
//   t1: ball -> 52.0, IN_GAME, r = 0 (first).
//   t2: ball -> 52.94 > 52.585: GOAL; shaping zeroed on the terminal step, r = 5 exactly
//       (the ball did move 0.94 m toward the goal, which would otherwise pay about
//        3 * 0.94 * 0.032 = 0.09).
TEST_F(HfoReward, GoalPaysExactlyFive) {
  start(make_agent({40.0, 10.0}), BallState{{51.0, 0.0}, {1.0, 0.0}});
  StepResult r = idle();
  EXPECT_EQ(r.status, kInGame);
  EXPECT_EQ(r.reward, 0.0F);
  r = idle();
  EXPECT_EQ(r.status, kGoal);
  EXPECT_EQ(r.reward, 5.0F);
}

// Goal in the very first transition: 5 as well.
TEST_F(HfoReward, GoalOnFirstTransition) {
  start(make_agent({40.0, 10.0}), BallState{{52.0, 0.0}, {1.0, 0.0}});
  const StepResult r = idle();
  EXPECT_EQ(r.status, kGoal);
  EXPECT_EQ(r.reward, 5.0F);
}

// Any other terminal step pays exactly 0: ball (1, 0) rolling (-2, 0) out of the left side
// (IN_GAME, then OUT_OF_BOUNDS with the ball another 1.88 m farther from the goal).
TEST_F(HfoReward, OutOfBoundsPaysZero) {
  start(make_agent({30.0, 5.0}), BallState{{1.0, 0.0}, {-2.0, 0.0}});
  StepResult r = idle();
  EXPECT_EQ(r.status, kInGame);
  EXPECT_EQ(r.reward, 0.0F);
  r = idle();
  EXPECT_EQ(r.status, kOutOfBounds);
  EXPECT_EQ(r.reward, 0.0F);
}

// env.out_of_bounds_penalty = 4: the same out-of-bounds episode pays -4 on its terminal step and
// nothing else changes; a goal still pays exactly 5.
class HfoRewardPenalty : public HfoReward {
 protected:
  HfoRewardPenalty() : HfoReward(4) {}
};

TEST_F(HfoRewardPenalty, OutOfBoundsPaysMinusThePenalty) {
  start(make_agent({30.0, 5.0}), BallState{{1.0, 0.0}, {-2.0, 0.0}});
  StepResult r = idle();
  EXPECT_EQ(r.status, kInGame);
  EXPECT_EQ(r.reward, 0.0F);
  r = idle();
  EXPECT_EQ(r.status, kOutOfBounds);
  EXPECT_EQ(r.reward, -4.0F);
  start(make_agent({40.0, 10.0}), BallState{{52.0, 0.0}, {1.0, 0.0}});
  r = idle();
  EXPECT_EQ(r.status, kGoal);
  EXPECT_EQ(r.reward, 5.0F);
}

// A new episode restarts the reward: after a goal, set_state again and the first transition is
// again unshaped even though the agent moves 1 m.
TEST_F(HfoReward, ResetRestartsShaping) {
  start(make_agent({40.0, 10.0}), BallState{{52.0, 0.0}, {1.0, 0.0}});
  ASSERT_EQ(idle().status, kGoal);
  start(make_agent({0.0, 0.0}, 0.0, {0.4, 0.0}), BallState{{30.0, 0.0}, {}});
  EXPECT_EQ(dash(100.0F, 0.0F).reward, 0.0F);
  EXPECT_NEAR(dash(100.0F, 0.0F).reward, kPerMetre, kRewardTol);
}

// ---------------------------------------------------------------------------------------
// §5.1 start distributions.

// kPaper (E1): ball x = 0.2 * U[-0.1, 52.5] + 5.25 in [5.23, 15.75], y = 34 * U[-0.8, 0.8] in
// [-27.2, 27.2]; agent clamped to x in [-0.1, 52.5], |y| <= 34; velocities 0.
TEST(HfoStart, PaperDistributionRanges) {
  SoccerSimConfig cfg;
  cfg.start = StartDistribution::kPaper;
  SoccerSim sim(cfg, 2024);
  double bx_min = 1e9;
  double bx_max = -1e9;
  double by_min = 1e9;
  double by_max = -1e9;
  int agent_at_left = 0;
  for (int i = 0; i < 2000; ++i) {
    sim.reset_episode();
    const SoccerState& s = sim.state();
    const Vec2 b = s.ball.pos;
    const Vec2 a = s.players[0].pos;
    ASSERT_GE(b.x, 5.23);
    ASSERT_LE(b.x, 15.75);
    ASSERT_LE(std::fabs(b.y), 27.2);
    ASSERT_GE(a.x, -0.1);
    ASSERT_LE(a.x, 52.5);
    ASSERT_LE(std::fabs(a.y), 34.0);
    EXPECT_EQ(s.ball.vel.r(), 0.0);
    EXPECT_EQ(s.players[0].vel.r(), 0.0);
    bx_min = std::min(bx_min, b.x);
    bx_max = std::max(bx_max, b.x);
    by_min = std::min(by_min, b.y);
    by_max = std::max(by_max, b.y);
    agent_at_left += a.x == -0.1 ? 1 : 0;
  }
  // The whole ranges are used (2000 uniform draws leave gaps of ~0.005 of the range at the ends).
  EXPECT_LT(bx_min, 5.23 + 0.1);
  EXPECT_GT(bx_max, 15.75 - 0.1);
  EXPECT_LT(by_min, -27.2 + 0.5);
  EXPECT_GT(by_max, 27.2 - 0.5);
  EXPECT_GT(agent_at_left, 0);
}

// The start curriculum (issue 80): with the same draws, ball and players start at
// start_curriculum_from of their distance to the goal's centre at update 0, the fraction rising
// linearly to 1 at start_curriculum_updates; never told the updates, or past the end, the start is
// the distribution's own, bit for bit.
TEST(HfoStart, TheCurriculumMovesStartsTowardTheGoalAndEndsOnTheDistribution) {
  SoccerSimConfig plain;
  plain.start = StartDistribution::kPaper;
  SoccerSimConfig taught = plain;
  taught.start_curriculum_updates = 1000;
  taught.start_curriculum_from = 0.25;
  const Vec2 goal{52.5, 0.0};
  for (const auto& [updates, scale] :
       std::initializer_list<std::pair<int64_t, double>>{{-1, 1.0}, {0, 0.25}, {400, 0.55}, {1000, 1.0}, {5000, 1.0}}) {
    SoccerSim reference(plain, 31);
    SoccerSim sim(taught, 31);
    if (updates >= 0) {
      sim.set_training_updates(updates);
    }
    EXPECT_DOUBLE_EQ(sim.start_scale(), scale) << updates;
    for (int episode = 0; episode < 50; ++episode) {
      reference.reset_episode();
      sim.reset_episode();
      const Vec2 b = reference.state().ball.pos;
      const Vec2 a = reference.state().players[0].pos;
      if (scale == 1.0) {
        ASSERT_EQ(sim.state().ball.pos.x, b.x);
        ASSERT_EQ(sim.state().ball.pos.y, b.y);
        ASSERT_EQ(sim.state().players[0].pos.x, a.x);
        ASSERT_EQ(sim.state().players[0].pos.y, a.y);
        continue;
      }
      ASSERT_NEAR(sim.state().ball.pos.x, goal.x + scale * (b.x - goal.x), 1e-12) << updates;
      ASSERT_NEAR(sim.state().ball.pos.y, scale * b.y, 1e-12);
      ASSERT_NEAR(sim.state().players[0].pos.x, goal.x + scale * (a.x - goal.x), 1e-12);
      ASSERT_NEAR(sim.state().players[0].pos.y, scale * a.y, 1e-12);
      if (scale == 0.25) {
        // The paper's ball, up to 54.5 m from the goal's centre (x 5.23, |y| 27.2), starts within 13.7 m.
        ASSERT_LE((sim.state().ball.pos - goal).r(), 13.7);
      }
    }
  }
}

// kDec2015: ball x = 52.5 * U[0, 0.2] in [0, 10.5]; agent x clamped to [-0.1, 21], |y| <= 27.2.
// With a = bx/10.5 ~ U[0, 1] and the ten offsets (ox = -2, -1, 0, 1, 2 each with probability 0.2):
//   P(x clamped to -0.1) = 0.2 * [P(ox = -2): ~1] + 0.2 * [P(a + U < 0.99048) = 0.99048^2 / 2 =
//                          0.49052] = 0.2 * 1.49052 = 0.298
//   P(x clamped to 21)   = 0.2 * [ox = 2: 1] + 0.2 * [ox = 1: P(a + U > 1) = 0.5] = 0.3
// (binomial std with 2000 draws: sqrt(0.3 * 0.7 / 2000) = 0.010; we allow 0.05).
TEST(HfoStart, Dec2015DistributionRangesAndClamps) {
  SoccerSimConfig cfg;
  cfg.start = StartDistribution::kDec2015;
  SoccerSim sim(cfg, 77);
  int at_left = 0;
  int at_right = 0;
  double bx_max = -1e9;
  constexpr int kN = 2000;
  for (int i = 0; i < kN; ++i) {
    sim.reset_episode();
    const Vec2 b = sim.state().ball.pos;
    const Vec2 a = sim.state().players[0].pos;
    ASSERT_GE(b.x, 0.0);
    ASSERT_LE(b.x, 10.5);
    ASSERT_LE(std::fabs(b.y), 27.2);
    ASSERT_GE(a.x, -0.1);
    ASSERT_LE(a.x, 21.0);
    ASSERT_LE(std::fabs(a.y), 27.2);
    at_left += a.x == -0.1 ? 1 : 0;
    at_right += a.x == 21.0 ? 1 : 0;
    bx_max = std::max(bx_max, b.x);
  }
  EXPECT_GT(bx_max, 10.4);
  EXPECT_NEAR(static_cast<double>(at_left) / kN, 0.298, 0.05);
  EXPECT_NEAR(static_cast<double>(at_right) / kN, 0.3, 0.05);
}

// §5.1 / §2.5: a reset restores stamina, effort, recovery and capacity, zeroes the velocity and
// (BodyAtReset::kCarry, the real HFO behaviour) keeps the body angle of the previous episode;
// the very first episode starts at body 0.
TEST(HfoStart, ResetRestoresStaminaAndCarriesBody) {
  SoccerSimConfig cfg;
  cfg.body_at_reset = BodyAtReset::kCarry;
  SoccerSim sim(cfg, 5);
  sim.mutable_state().players[0].body_deg = 77.0;
  sim.reset_episode();
  EXPECT_EQ(sim.agent().body_deg, 0.0);  // first episode
  PlayerState& p = sim.mutable_state().players[0];
  p.body_deg = 45.0;
  p.stamina = 1234.0;
  p.effort = 0.7;
  p.recovery = 0.6;
  p.capacity = 10.0;
  p.vel = {0.3, 0.1};
  p.tackle_cycles = 4;
  sim.reset_episode();
  EXPECT_EQ(sim.agent().body_deg, 45.0);
  EXPECT_EQ(sim.agent().stamina, 8000.0);
  EXPECT_EQ(sim.agent().effort, 1.0);
  EXPECT_EQ(sim.agent().recovery, 1.0);
  EXPECT_EQ(sim.agent().capacity, 130600.0);
  EXPECT_EQ(sim.agent().vel.r(), 0.0);
  EXPECT_EQ(sim.state().cycle, 0);
  EXPECT_EQ(sim.state().untouched, 0);
}

}  // namespace
}  // namespace pamdp::hfo
