// The 58 low-level features (shared/hfo-reference.md §3) against hand-computed values.
// R = sqrt(52.5^2 + 34^2) = sqrt(2756.25 + 1156) = sqrt(3912.25) = 62.5479816; 2/R = 0.0319755.
// Proximity: 1 - 2 clamp(d/M, 0, 1); magnitude: 2 clamp(x/max, 0, 1) - 1; flags +1 / -1.
// Features are float32, so comparisons use 1e-6.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <span>

#include "core/rng.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {
namespace {

constexpr double kFTol = 1e-6;
const double kR = std::sqrt(52.5 * 52.5 + 34.0 * 34.0);  // 62.5479815821

using Features = std::array<float, 58>;

SoccerState make_state(Vec2 agent_pos, double body_deg, Vec2 agent_vel, Vec2 ball_pos, Vec2 ball_vel = {}) {
  SoccerState s;
  s.num_players = 1;
  s.players[0].pos = agent_pos;
  s.players[0].body_deg = body_deg;
  s.players[0].vel = agent_vel;
  s.ball.pos = ball_pos;
  s.ball.vel = ball_vel;
  s.prev_ball = ball_pos;
  return s;
}

Features features_of(const SoccerState& s) {
  Features f{};
  f.fill(-7.0F);  // sentinel: every slot must be written
  write_features(s, f);
  return f;
}

SoccerSimConfig quiet_config() {
  SoccerSimConfig c;
  c.noise = false;
  return c;
}

TEST(HfoFeatures, CountIs58For1v0) {
  EXPECT_EQ(kNumAgentFeatures, 58);
  EXPECT_EQ(feature_count(1), 58);
}

// §3.2 worked example: agent at (0, 0), body 0, at rest, ball at (10, 0).
//   ball: bearing 0 - body 0 = 0 -> (sin, cos) = (0, 1); prox 1 - 2 * 10/62.548 = 1 - 0.3197545
//         = 0.6802455.
//   goal centre (52.5, 0): (0, 1), prox 1 - 2 * 52.5/62.548 = 1 - 1.6787112 = -0.6787112.
//   goal post top (52.5, -7.01): d = sqrt(2756.25 + 49.1401) = 52.9659334; sin = -7.01/52.9659334
//         = -0.1323492, cos = 52.5/52.9659334 = 0.9912031; prox 1 - 2 * 52.9659334/62.548 = -0.6936097.
//   goal post bottom (52.5, 7.01): (+0.1323492, 0.9912031, -0.6936097).
//   penalty centre (36, 0): (0, 1, 1 - 72/62.548 = -0.1511163).
//   penalty top (36, -20.16): d = sqrt(1296 + 406.4256) = 41.2604605; sin = -20.16/41.2604605 =
//         -0.4886034, cos = 36/41.2604605 = 0.8725060; prox 1 - 82.520921/62.548 = -0.3193219.
//   corner top-left (0, -34): bearing -90 -> (-1, 0); prox 1 - 68/62.548 = -0.0871654.
//   corner bottom-left (0, 34): (+1, 0, -0.0871654).
//   corner top-right (52.5, -34): d = R -> prox -1; sin = -34/R = -0.5435827, cos = 52.5/R = 0.8393556.
//   corner bottom-right (52.5, 34): (0.5435827, 0.8393556, -1).
//   OOB left d = x = 0 -> +1; right d = 52.5 -> -1; top d = 34 + 0 over 68 -> 1 - 1 = 0; bottom 0.
//   self velocity zero -> vdir = 0 -> wrap(0 - 0) = 0 -> (0, 1); speed 2 * 0 - 1 = -1.
//   body 0 -> (0, 1); stamina 8000 -> 2 * 1 - 1 = +1; frozen/collisions/kickable -1.
//   ball speed 2 * 0/5 - 1 = -1; ball velocity angle atan2(0, 0) = 0 -> (0, 1).
TEST(HfoFeatures, WorkedExample) {
  const Features f = features_of(make_state({0.0, 0.0}, 0.0, {}, {10.0, 0.0}));
  EXPECT_NEAR(f[51], 0.0, kFTol);
  EXPECT_NEAR(f[52], 1.0, kFTol);
  EXPECT_NEAR(f[53], 0.6802455, kFTol);
  EXPECT_NEAR(f[53], 1.0 - 2.0 * 10.0 / kR, kFTol);
  EXPECT_NEAR(f[13], 0.0, kFTol);
  EXPECT_NEAR(f[14], 1.0, kFTol);
  EXPECT_NEAR(f[15], -0.6787112, kFTol);
  EXPECT_NEAR(f[46], 1.0, kFTol);
  EXPECT_NEAR(f[47], -1.0, kFTol);
  EXPECT_NEAR(f[48], 0.0, kFTol);
  EXPECT_NEAR(f[49], 0.0, kFTol);
  EXPECT_NEAR(f[2], 0.0, kFTol);
  EXPECT_NEAR(f[3], 1.0, kFTol);
  EXPECT_NEAR(f[5], 0.0, kFTol);
  EXPECT_NEAR(f[6], 1.0, kFTol);

  // The other landmarks.
  EXPECT_NEAR(f[16], -0.1323492, kFTol);
  EXPECT_NEAR(f[17], 0.9912031, kFTol);
  EXPECT_NEAR(f[18], -0.6936097, kFTol);
  EXPECT_NEAR(f[19], 0.1323492, kFTol);
  EXPECT_NEAR(f[20], 0.9912031, kFTol);
  EXPECT_NEAR(f[21], -0.6936097, kFTol);
  EXPECT_NEAR(f[22], 0.0, kFTol);
  EXPECT_NEAR(f[23], 1.0, kFTol);
  EXPECT_NEAR(f[24], -0.1511163, kFTol);
  EXPECT_NEAR(f[25], -0.4886034, kFTol);
  EXPECT_NEAR(f[26], 0.8725060, kFTol);
  EXPECT_NEAR(f[27], -0.3193219, kFTol);
  EXPECT_NEAR(f[28], 0.4886034, kFTol);
  EXPECT_NEAR(f[29], 0.8725060, kFTol);
  EXPECT_NEAR(f[30], -0.3193219, kFTol);
  EXPECT_NEAR(f[34], -1.0, kFTol);
  EXPECT_NEAR(f[35], 0.0, kFTol);
  EXPECT_NEAR(f[36], -0.0871654, kFTol);
  EXPECT_NEAR(f[37], -0.5435827, kFTol);
  EXPECT_NEAR(f[38], 0.8393556, kFTol);
  EXPECT_NEAR(f[39], -1.0, kFTol);
  EXPECT_NEAR(f[40], 0.5435827, kFTol);
  EXPECT_NEAR(f[41], 0.8393556, kFTol);
  EXPECT_NEAR(f[42], -1.0, kFTol);
  EXPECT_NEAR(f[43], 1.0, kFTol);
  EXPECT_NEAR(f[44], 0.0, kFTol);
  EXPECT_NEAR(f[45], -0.0871654, kFTol);

  // Self block and ball block.
  EXPECT_EQ(f[0], 1.0F);
  EXPECT_EQ(f[1], 1.0F);
  EXPECT_NEAR(f[4], -1.0, kFTol);
  EXPECT_NEAR(f[7], 1.0, kFTol);
  for (int i = 8; i <= 12; ++i) {
    EXPECT_EQ(f[i], -1.0F) << "feature " << i;
  }
  EXPECT_EQ(f[50], 1.0F);
  EXPECT_EQ(f[54], 1.0F);
  EXPECT_NEAR(f[55], -1.0, kFTol);
  EXPECT_NEAR(f[56], 0.0, kFTol);
  EXPECT_NEAR(f[57], 1.0, kFTol);
}

// Every feature of many random states lies in [-1, 1] (and is a number); the valid flags 0, 1,
// 50 and 54 are always +1 under full state.
TEST(HfoFeatures, AllInRangeAndValidFlagsConstant) {
  Rng rng(12345);
  for (int trial = 0; trial < 2000; ++trial) {
    SoccerState s = make_state({rng.uniform(-60.0, 60.0), rng.uniform(-40.0, 40.0)}, rng.uniform(-180.0, 180.0),
                               {rng.uniform(-1.2, 1.2), rng.uniform(-1.2, 1.2)},
                               {rng.uniform(-60.0, 60.0), rng.uniform(-40.0, 40.0)},
                               {rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0)});
    s.players[0].stamina = rng.uniform(0.0, 8000.0);
    s.players[0].tackle_cycles = static_cast<int>(rng.below(11));
    if (trial % 10 == 0) {
      s.ball.pos = s.players[0].pos + Vec2{rng.uniform(-1.1, 1.1), rng.uniform(-1.1, 1.1)};
    }
    if (trial % 97 == 0) {
      s.players[0].vel = {};
      s.ball.vel = {};
    }
    const Features f = features_of(s);
    for (int i = 0; i < 58; ++i) {
      ASSERT_TRUE(std::isfinite(f[i])) << "feature " << i << " trial " << trial;
      ASSERT_GE(f[i], -1.0F) << "feature " << i << " trial " << trial;
      ASSERT_LE(f[i], 1.0F) << "feature " << i << " trial " << trial;
    }
    EXPECT_EQ(f[0], 1.0F);
    EXPECT_EQ(f[1], 1.0F);
    EXPECT_EQ(f[50], 1.0F);
    EXPECT_EQ(f[54], 1.0F);
    // sin^2 + cos^2 = 1 for each angle pair.
    for (int i : {2, 5, 13, 16, 19, 22, 25, 28, 34, 37, 40, 43, 51, 56}) {
      EXPECT_NEAR(f[i] * f[i] + f[i + 1] * f[i + 1], 1.0, 1e-5) << "pair " << i;
    }
  }
}

// §1.1 / §3.1: relative angle = bearing - body, positive to the agent's right (+y when body 0).
// Agent (10, 0), ball (10, 5): bearing 90.
//   body 0:   ball (sin, cos) = (sin 90, cos 90) = (1, 0); prox 1 - 2 * 5/R = 1 - 0.1598773 = 0.8401227.
//   body 90:  ball straight ahead (0, 1); body (f5, f6) = (1, 0); goal centre (52.5, 0) at bearing 0
//             -> 0 - 90 = -90 -> (-1, 0) (to the left).
//   body -90: f5 = -1, ball bearing 90 - (-90) = 180 -> (0, -1).
//   body 180: (f5, f6) = (0, -1); goal centre 0 - 180 = -180 -> wrap 180 -> (0, -1).
TEST(HfoFeatures, RelativeAngleSignConventions) {
  Features f = features_of(make_state({10.0, 0.0}, 0.0, {}, {10.0, 5.0}));
  EXPECT_NEAR(f[51], 1.0, kFTol);
  EXPECT_NEAR(f[52], 0.0, kFTol);
  EXPECT_NEAR(f[53], 0.8401227, kFTol);

  f = features_of(make_state({10.0, 0.0}, 90.0, {}, {10.0, 5.0}));
  EXPECT_NEAR(f[5], 1.0, kFTol);
  EXPECT_NEAR(f[6], 0.0, kFTol);
  EXPECT_NEAR(f[51], 0.0, kFTol);
  EXPECT_NEAR(f[52], 1.0, kFTol);
  EXPECT_NEAR(f[13], -1.0, kFTol);
  EXPECT_NEAR(f[14], 0.0, kFTol);

  f = features_of(make_state({10.0, 0.0}, -90.0, {}, {10.0, 5.0}));
  EXPECT_NEAR(f[5], -1.0, kFTol);
  EXPECT_NEAR(f[6], 0.0, kFTol);
  EXPECT_NEAR(f[51], 0.0, kFTol);
  EXPECT_NEAR(f[52], -1.0, kFTol);
  EXPECT_NEAR(f[13], 1.0, kFTol);

  f = features_of(make_state({10.0, 0.0}, 180.0, {}, {10.0, 5.0}));
  EXPECT_NEAR(f[5], 0.0, kFTol);
  EXPECT_NEAR(f[6], -1.0, kFTol);
  EXPECT_NEAR(f[13], 0.0, kFTol);
  EXPECT_NEAR(f[14], -1.0, kFTol);

  // Body 30, ball at 60 deg global, 4 m away: relative 30 -> (0.5, cos 30 = 0.8660254).
  const double th = 60.0 * kDegToRad;
  f = features_of(make_state({10.0, 0.0}, 30.0, {}, {10.0 + 4.0 * std::cos(th), 4.0 * std::sin(th)}));
  EXPECT_NEAR(f[5], 0.5, kFTol);
  EXPECT_NEAR(f[6], 0.8660254, kFTol);
  EXPECT_NEAR(f[51], 0.5, kFTol);
  EXPECT_NEAR(f[52], 0.8660254, kFTol);
  EXPECT_NEAR(f[53], 1.0 - 8.0 / kR, kFTol);  // 1 - 0.1279018 = 0.8720982
}

// §3.2 self velocity angle is wrap(body - vdir) (the opposite order to landmarks).
//   body 0,  v = (0, 0.2):  vdir 90, 0 - 90 = -90 -> (-1, 0); speed 2 * 0.2/0.46 - 1 = -0.1304348.
//   body 90, v = (0.2, 0):  90 - 0 = 90 -> (1, 0).
//   body 30, v = 0.46 at 30 deg: 0 -> (0, 1); speed 2 * 1 - 1 = +1.
//   body 0,  v = (-0.3, 0): 0 - 180 -> wrap 180 -> (0, -1); speed 2 * 0.3/0.46 - 1 = 0.3043478.
//   body 0,  v = (0.6, 0): speed clamped: 2 * clamp(1.304, 0, 1) - 1 = +1.
TEST(HfoFeatures, SelfVelocityAngleIsBodyMinusVelocity) {
  Features f = features_of(make_state({10.0, 0.0}, 0.0, {0.0, 0.2}, {20.0, 0.0}));
  EXPECT_NEAR(f[2], -1.0, kFTol);
  EXPECT_NEAR(f[3], 0.0, kFTol);
  EXPECT_NEAR(f[4], -0.1304348, kFTol);

  f = features_of(make_state({10.0, 0.0}, 90.0, {0.2, 0.0}, {20.0, 0.0}));
  EXPECT_NEAR(f[2], 1.0, kFTol);
  EXPECT_NEAR(f[3], 0.0, kFTol);

  const double th = 30.0 * kDegToRad;
  f = features_of(make_state({10.0, 0.0}, 30.0, {0.46 * std::cos(th), 0.46 * std::sin(th)}, {20.0, 0.0}));
  EXPECT_NEAR(f[2], 0.0, kFTol);
  EXPECT_NEAR(f[3], 1.0, kFTol);
  EXPECT_NEAR(f[4], 1.0, kFTol);

  f = features_of(make_state({10.0, 0.0}, 0.0, {-0.3, 0.0}, {20.0, 0.0}));
  EXPECT_NEAR(f[2], 0.0, kFTol);
  EXPECT_NEAR(f[3], -1.0, kFTol);
  EXPECT_NEAR(f[4], 0.3043478, kFTol);

  f = features_of(make_state({10.0, 0.0}, 0.0, {0.6, 0.0}, {20.0, 0.0}));
  EXPECT_NEAR(f[4], 1.0, kFTol);
}

// §3.2 ball velocity angle is global (independent of the body).
//   v = (0, -1): atan2 = -90 -> (-1, 0) for any body; speed 2 * 1/5 - 1 = -0.6.
//   v = (1.5, 2): |v| = 2.5 -> speed 2 * 0.5 - 1 = 0; (sin, cos) = (2/2.5, 1.5/2.5) = (0.8, 0.6).
TEST(HfoFeatures, BallVelocityAngleIsGlobal) {
  for (double body : {0.0, 90.0, -135.0}) {
    Features f = features_of(make_state({10.0, 0.0}, body, {}, {20.0, 0.0}, {0.0, -1.0}));
    EXPECT_NEAR(f[55], -0.6, kFTol) << "body " << body;
    EXPECT_NEAR(f[56], -1.0, kFTol) << "body " << body;
    EXPECT_NEAR(f[57], 0.0, kFTol) << "body " << body;

    f = features_of(make_state({10.0, 0.0}, body, {}, {20.0, 0.0}, {1.5, 2.0}));
    EXPECT_NEAR(f[55], 0.0, kFTol) << "body " << body;
    EXPECT_NEAR(f[56], 0.8, kFTol) << "body " << body;
    EXPECT_NEAR(f[57], 0.6, kFTol) << "body " << body;
  }
}

// §3.5 kickable bit uses the client rule d <= 1.03 (not the server's 1.085).
TEST(HfoFeatures, KickableBit) {
  EXPECT_EQ(features_of(make_state({10.0, 0.0}, 0.0, {}, {11.02, 0.0}))[12], 1.0F);
  EXPECT_EQ(features_of(make_state({10.0, 0.0}, 0.0, {}, {11.04, 0.0}))[12], -1.0F);
  EXPECT_EQ(features_of(make_state({10.0, 0.0}, 0.0, {}, {11.08, 0.0}))[12], -1.0F);  // server-kickable only
  // 1.02 m along a diagonal: (0.612, 0.816) = 1.02 * (0.6, 0.8).
  EXPECT_EQ(features_of(make_state({5.0, 5.0}, 45.0, {}, {5.612, 5.816}))[12], 1.0F);
  // 1.04 m behind the agent: (-0.624, -0.832) = 1.04 * (-0.6, -0.8).
  EXPECT_EQ(features_of(make_state({5.0, 5.0}, 45.0, {}, {4.376, 4.168}))[12], -1.0F);
}

// §3.2 stamina: 2 * S/8000 - 1.  8000 -> 1, 6000 -> 0.5, 4000 -> 0, 2000 -> -0.5, 0 -> -1.
TEST(HfoFeatures, StaminaNormalisation) {
  const double cases[][2] = {{8000, 1.0}, {6000, 0.5}, {4000, 0.0}, {2000, -0.5}, {0, -1.0}, {1000, -0.75}};
  for (const auto& c : cases) {
    SoccerState s = make_state({10.0, 0.0}, 0.0, {}, {20.0, 0.0});
    s.players[0].stamina = c[0];
    EXPECT_NEAR(features_of(s)[7], c[1], kFTol) << "stamina " << c[0];
  }
}

// §3.2 OOB proximities. Agent (10.5, 17):
//   left:   d = 10.5, 1 - 2 * 10.5/52.5 = 1 - 0.4 = 0.6
//   right:  d = 42,   1 - 2 * 0.8 = -0.6
//   top:    d = 34 + 17 = 51 over 68 -> 1 - 2 * 0.75 = -0.5
//   bottom: d = 34 - 17 = 17 over 68 -> 1 - 0.5 = 0.5
// Agent (-0.1, -34): left d = -0.1 -> clamp 0 -> +1; right d = 52.6 -> -1; top d = 0 -> +1;
// bottom d = 68 -> -1.
TEST(HfoFeatures, OutOfBoundsProximities) {
  Features f = features_of(make_state({10.5, 17.0}, 0.0, {}, {20.0, 0.0}));
  EXPECT_NEAR(f[46], 0.6, kFTol);
  EXPECT_NEAR(f[47], -0.6, kFTol);
  EXPECT_NEAR(f[48], -0.5, kFTol);
  EXPECT_NEAR(f[49], 0.5, kFTol);

  f = features_of(make_state({-0.1, -34.0}, 0.0, {}, {20.0, 0.0}));
  EXPECT_NEAR(f[46], 1.0, kFTol);
  EXPECT_NEAR(f[47], -1.0, kFTol);
  EXPECT_NEAR(f[48], 1.0, kFTol);
  EXPECT_NEAR(f[49], -1.0, kFTol);
}

// §3.1 proximity saturates at d >= R: agent (0, -34), ball (52.5, 34): d = sqrt(52.5^2 + 68^2)
// = 85.9 > 62.548 -> -1. Landmark distance: goal centre from (52.5 - 31.274, 0) = 31.274 m
// = R/2 -> 1 - 2 * 0.5 = 0.
TEST(HfoFeatures, ProximitySaturatesAndScales) {
  EXPECT_NEAR(features_of(make_state({0.0, -34.0}, 0.0, {}, {52.5, 34.0}))[53], -1.0, kFTol);
  EXPECT_NEAR(features_of(make_state({52.5 - kR / 2.0, 0.0}, 0.0, {}, {10.0, 0.0}))[15], 0.0, kFTol);
}

// §3.2 frozen bit: +1 in the 9 observed states after a tackle, -1 before and after.
TEST(HfoFeatures, FrozenBitAfterTackle) {
  SoccerSim sim(quiet_config(), 1);
  PlayerState agent;
  agent.pos = {10.0, 0.0};
  sim.set_state(agent, BallState{{9.5, 0.0}, {}});  // ball behind: the tackle fails
  Features f{};
  write_features(sim.state(), f);
  EXPECT_EQ(f[8], -1.0F);
  ASSERT_TRUE(sim.tackle(0.0));
  int frozen = 0;
  for (int i = 0; i < 12; ++i) {
    sim.step();
    write_features(sim.state(), f);
    if (i < 9) {
      EXPECT_EQ(f[8], 1.0F) << "observation " << i + 1;
    } else {
      EXPECT_EQ(f[8], -1.0F) << "observation " << i + 1;
    }
    frozen += f[8] > 0.0F ? 1 : 0;
  }
  EXPECT_EQ(frozen, 9);
}

// §3.2 collided-with-ball bit: +1 only in the observation right after the collision.
// Agent (10, 0) moving (0.1, 0), ball (11, 0) moving (-0.8, 0): after movement 0.1 apart -> collision.
TEST(HfoFeatures, CollidedWithBallBitForOneCycle) {
  SoccerSim sim(quiet_config(), 1);
  PlayerState agent;
  agent.pos = {10.0, 0.0};
  agent.vel = {0.1, 0.0};
  sim.set_state(agent, BallState{{11.0, 0.0}, {-0.8, 0.0}});
  Features f{};
  sim.step();
  write_features(sim.state(), f);
  EXPECT_EQ(f[9], 1.0F);
  EXPECT_EQ(f[10], -1.0F);
  EXPECT_EQ(f[11], -1.0F);
  EXPECT_EQ(f[12], 1.0F);  // 0.385 m apart: kickable
  sim.step();
  write_features(sim.state(), f);
  EXPECT_EQ(f[9], -1.0F);
}

// §2.3: a player touching a post gets the collided-with-post bit (feature 11) for one cycle.
// Agent at (51.44, -7.07) running (1, 0) into the post (52.44, -7.07): contact at 0.36 m.
TEST(HfoFeatures, CollidedWithPostBit) {
  SoccerSim sim(quiet_config(), 1);
  PlayerState agent;
  agent.pos = {51.44, -7.07};
  agent.vel = {1.0, 0.0};
  sim.set_state(agent, BallState{{30.0, 10.0}, {}});
  Features f{};
  sim.step();
  write_features(sim.state(), f);
  EXPECT_EQ(f[11], 1.0F);
  sim.step();
  write_features(sim.state(), f);
  EXPECT_EQ(f[11], -1.0F);
}

}  // namespace
}  // namespace pamdp::hfo
