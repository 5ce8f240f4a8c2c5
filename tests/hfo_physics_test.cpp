// Physics of the embedded HFO simulator (SoccerSim, noise off) against hand-computed values
// from shared/hfo-reference.md §2. Every expected number below is worked out in the comments
// from the reference's equations; none is produced by the code under test.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "envs/hfo/geometry.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {
namespace {

constexpr double kTol = 1e-9;
constexpr double kPi = std::numbers::pi;

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

BallState make_ball(Vec2 pos, Vec2 vel = {}) {
  return BallState{pos, vel};
}

// A sim whose ball lies far from the agent and from every goal post, so that only the agent's
// own movement matters.
SoccerSim sim_with_agent(const PlayerState& agent, Vec2 ball_pos = {-30.0, 30.0}) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(agent, make_ball(ball_pos));
  return sim;
}

// ---------------------------------------------------------------------------------------
// §2.11 derived numbers: Dash(100, 0) from rest.
// accel = power * rate(0) * effort * dash_power_rate = 100 * 1.0 * 1.0 * 0.006 = 0.6.
// cycle 1: v = 0 + 0.6 = 0.6        -> x = 0.6,            observed v = 0.6 * 0.4 = 0.24
// cycle 2: v = 0.24 + 0.6 = 0.84    -> x = 0.6 + 0.84 = 1.44, observed 0.84 * 0.4 = 0.336
// cycle 3: v = 0.336 + 0.6 = 0.936  -> x = 2.376,          observed 0.936 * 0.4 = 0.3744
// cycle 4: v = 0.3744 + 0.6 = 0.9744 -> x = 3.3504,        observed 0.38976
// cycle 5: v = 0.38976 + 0.6 = 0.98976 -> x = 4.34016,     observed 0.395904
TEST(HfoPhysics, DashFromRestDistancesAndSpeeds) {
  SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}));
  const double dist[] = {0.6, 0.84, 0.936, 0.9744, 0.98976};
  const double speed[] = {0.24, 0.336, 0.3744, 0.38976, 0.395904};
  const double xs[] = {0.6, 1.44, 2.376, 3.3504, 4.34016};
  double prev_x = 0.0;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(sim.dash(100.0, 0.0));
    sim.step();
    const PlayerState& a = sim.agent();
    EXPECT_NEAR(a.pos.x - prev_x, dist[i], kTol) << "cycle " << i + 1;
    EXPECT_NEAR(a.pos.x, xs[i], kTol) << "cycle " << i + 1;
    EXPECT_NEAR(a.pos.y, 0.0, kTol);
    EXPECT_NEAR(a.vel.x, speed[i], kTol) << "cycle " << i + 1;
    EXPECT_NEAR(a.vel.y, 0.0, kTol);
    EXPECT_NEAR(a.body_deg, 0.0, kTol);  // a dash never turns the body
    prev_x = a.pos.x;
  }
}

// After many cycles of full dashing the observed speed tends to 0.6 * 0.4 / (1 - 0.4) = 0.4
// and the distance per cycle to 0.4 + 0.6 = 1.0 (below speed max 1.05).
TEST(HfoPhysics, DashSteadyStateSpeed) {
  SoccerSim sim = sim_with_agent(make_agent({-40.0, -20.0}));
  for (int i = 0; i < 40; ++i) {
    ASSERT_TRUE(sim.dash(100.0, 0.0));
    sim.step();
  }
  const double x0 = sim.agent().pos.x;
  EXPECT_NEAR(sim.agent().vel.x, 0.4, kTol);
  ASSERT_TRUE(sim.dash(100.0, 0.0));
  sim.step();
  EXPECT_NEAR(sim.agent().pos.x - x0, 1.0, kTol);
}

// ---------------------------------------------------------------------------------------
// §2.4 direction rates. Body 0, from rest, Dash(100, d): accel = 0.6 * r(d) along d, so the
// displacement is polar(0.6 r(d), d) and the observed velocity polar(0.24 r(d), d).
//   r(0) = 0.4 + 0.6 * (1 - 0/90) = 1.0
//   r(45) = 0.4 + 0.6 * (1 - 45/90) = 0.7
//   r(90) = 0.4 + 0.6 * 0 = 0.4
//   r(135) = 0.6 - 0.2 * (1 - 45/90) = 0.5
//   r(180) = 0.6 - 0.2 * (1 - 90/90) = 0.6
TEST(HfoPhysics, DashDirectionRates) {
  struct Case {
    double dir;
    double rate;
  };
  const Case cases[] = {{0, 1.0},   {45, 0.7},   {-45, 0.7}, {90, 0.4},  {-90, 0.4},
                        {135, 0.5}, {-135, 0.5}, {180, 0.6}, {-180, 0.6}};
  for (const Case& c : cases) {
    SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}));
    ASSERT_TRUE(sim.dash(100.0, c.dir));
    // Forward dash power 100 always costs 100 stamina whatever the direction: 8000 - 100.
    EXPECT_NEAR(sim.agent().stamina, 7900.0, kTol) << "dir " << c.dir;
    sim.step();
    const double a = 0.6 * c.rate;
    const double th = c.dir * kPi / 180.0;
    EXPECT_NEAR(sim.agent().pos.x, a * std::cos(th), kTol) << "dir " << c.dir;
    EXPECT_NEAR(sim.agent().pos.y, a * std::sin(th), kTol) << "dir " << c.dir;
    EXPECT_NEAR(sim.agent().vel.r(), 0.4 * a, kTol) << "dir " << c.dir;
    EXPECT_NEAR(sim.agent().body_deg, 0.0, kTol);
  }
}

// §2.4 discretization: dir <- wrap(dir), then 45 * rint(dir / 45) (half to even).
//   22 / 45 = 0.489 -> 0     -> 0 deg, rate 1.0, displacement (0.6, 0)
//   23 / 45 = 0.511 -> 1     -> 45 deg, rate 0.7, displacement 0.42 * (cos45, sin45)
//   22.5 / 45 = 0.5 -> 0 (half to even) -> 0 deg
//   67.5 / 45 = 1.5 -> 2 (half to even) -> 90 deg, rate 0.4, displacement (0, 0.24)
//   -100 / 45 = -2.22 -> -2  -> -90 deg, displacement (0, -0.24)
//   200 -> wrap -160; -160 / 45 = -3.56 -> -4 -> -180 deg, rate 0.6, displacement (-0.36, 0)
//   -200 -> wrap 160; 160 / 45 = 3.56 -> 4 -> 180 deg, displacement (-0.36, 0)
//   400 -> wrap 40; 40 / 45 = 0.89 -> 1 -> 45 deg
TEST(HfoPhysics, DashDirectionDiscretization) {
  struct Case {
    double dir;
    double dx;
    double dy;
  };
  const double s45 = std::sqrt(0.5);
  const Case cases[] = {
      {22.0, 0.6, 0.0},     {23.0, 0.42 * s45, 0.42 * s45},
      {22.5, 0.6, 0.0},     {67.5, 0.0, 0.24},
      {-100.0, 0.0, -0.24}, {200.0, -0.36, 0.0},
      {-200.0, -0.36, 0.0}, {400.0, 0.42 * s45, 0.42 * s45},
  };
  for (const Case& c : cases) {
    SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}));
    ASSERT_TRUE(sim.dash(100.0, c.dir));
    sim.step();
    EXPECT_NEAR(sim.agent().pos.x, c.dx, kTol) << "dir " << c.dir;
    EXPECT_NEAR(sim.agent().pos.y, c.dy, kTol) << "dir " << c.dir;
  }
}

// A dash is relative to the body and never turns it. Body 90, Dash(100, 45): direction
// 90 + 45 = 135 deg, rate r(45) = 0.7, accel 0.42 -> displacement 0.42 * (cos135, sin135)
// = (-0.29698, 0.29698); the body stays 90.
TEST(HfoPhysics, DashIsRelativeToBody) {
  SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}, 90.0));
  ASSERT_TRUE(sim.dash(100.0, 45.0));
  sim.step();
  const double s45 = std::sqrt(0.5);
  EXPECT_NEAR(sim.agent().pos.x, -0.42 * s45, kTol);
  EXPECT_NEAR(sim.agent().pos.y, 0.42 * s45, kTol);
  EXPECT_NEAR(sim.agent().body_deg, 90.0, kTol);
}

// §2.4 back dash. Dash(-100, 0): need = -2 * -100 = 200 -> stamina 8000 - 200 = 7800;
// power = -200/2 = -100; e = |1 * -100 * r(0) * 0.006| = 0.6 along body + 0 + 180 = 180 deg.
// Dash(100, 180): need 100 -> 7900; e = 100 * r(180) * 0.006 = 100 * 0.6 * 0.006 = 0.36
// along 180 deg. After the step stamina recovers +45 (recovery 1 * 45): 7845 and 7945.
TEST(HfoPhysics, BackDashCostsDoubleAndMovesAtFullRate) {
  SoccerSim back = sim_with_agent(make_agent({0.0, 0.0}));
  ASSERT_TRUE(back.dash(-100.0, 0.0));
  EXPECT_NEAR(back.agent().stamina, 7800.0, kTol);
  back.step();
  EXPECT_NEAR(back.agent().pos.x, -0.6, kTol);
  EXPECT_NEAR(back.agent().pos.y, 0.0, kTol);
  EXPECT_NEAR(back.agent().vel.x, -0.24, kTol);  // -0.6 * 0.4
  EXPECT_NEAR(back.agent().stamina, 7845.0, kTol);
  EXPECT_NEAR(back.agent().body_deg, 0.0, kTol);

  SoccerSim side = sim_with_agent(make_agent({0.0, 0.0}));
  ASSERT_TRUE(side.dash(100.0, 180.0));
  EXPECT_NEAR(side.agent().stamina, 7900.0, kTol);
  side.step();
  EXPECT_NEAR(side.agent().pos.x, -0.36, kTol);
  EXPECT_NEAR(side.agent().pos.y, 0.0, kTol);
  EXPECT_NEAR(side.agent().vel.x, -0.144, kTol);  // -0.36 * 0.4
  EXPECT_NEAR(side.agent().stamina, 7945.0, kTol);
}

// Dash power is clamped to [-100, 100]: Dash(250, 0) is Dash(100, 0); Dash(-250, 0) is
// Dash(-100, 0).
TEST(HfoPhysics, DashPowerClamped) {
  SoccerSim fwd = sim_with_agent(make_agent({0.0, 0.0}));
  ASSERT_TRUE(fwd.dash(250.0, 0.0));
  EXPECT_NEAR(fwd.agent().stamina, 7900.0, kTol);
  fwd.step();
  EXPECT_NEAR(fwd.agent().pos.x, 0.6, kTol);

  SoccerSim bwd = sim_with_agent(make_agent({0.0, 0.0}));
  ASSERT_TRUE(bwd.dash(-250.0, 0.0));
  EXPECT_NEAR(bwd.agent().stamina, 7800.0, kTol);
  bwd.step();
  EXPECT_NEAR(bwd.agent().pos.x, -0.6, kTol);
}

// §2.4 stamina conservation with little stamina left: S = 30.
// Forward: need 100 > 30 + 50 = 80 -> power 80; server: need min(80, 80) = 80,
// S = max(0, 30 - 80) = 0; e = 80 * 1.0 * 0.006 = 0.48.
// Back: need 200 > 80 -> power -(30 + 50)/2 = -40; server need 80 -> S = 0, power -40,
// e = 40 * 0.006 = 0.24 backwards.
// Then §2.5 with S = 0 <= 2400: recovery 1 - 0.002 = 0.998, effort 1 - 0.005 = 0.995,
// inc = 0.998 * 45 = 44.91 -> S = 44.91.
TEST(HfoPhysics, DashStaminaConservation) {
  PlayerState tired = make_agent({0.0, 0.0});
  tired.stamina = 30.0;
  SoccerSim fwd = sim_with_agent(tired);
  ASSERT_TRUE(fwd.dash(100.0, 0.0));
  EXPECT_NEAR(fwd.agent().stamina, 0.0, kTol);
  fwd.step();
  EXPECT_NEAR(fwd.agent().pos.x, 0.48, kTol);
  EXPECT_NEAR(fwd.agent().stamina, 44.91, kTol);
  EXPECT_NEAR(fwd.agent().recovery, 0.998, kTol);
  EXPECT_NEAR(fwd.agent().effort, 0.995, kTol);

  SoccerSim bwd = sim_with_agent(tired);
  ASSERT_TRUE(bwd.dash(-100.0, 0.0));
  EXPECT_NEAR(bwd.agent().stamina, 0.0, kTol);
  bwd.step();
  EXPECT_NEAR(bwd.agent().pos.x, -0.24, kTol);
}

// §2.4 client speed conservation. v = (0.9, 0), Dash(100, 0): |0.9 + 0.6|^2 = 2.25 >
// 1.05^2 + 1e-4 -> acc = sqrt(1.05^2 - 0^2) - 0.9 = 0.15 -> power = 0.15 / (0.006 * 1 * 1) = 25.
// Server: stamina 8000 - 25 = 7975; v = 0.9 + 0.15 = 1.05 -> x = 1.05, observed 1.05 * 0.4 = 0.42;
// recovery: inc = min(45, 8000 - 7975 = 25) -> 8000.
TEST(HfoPhysics, DashSpeedConservation) {
  SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}, 0.0, {0.9, 0.0}));
  ASSERT_TRUE(sim.dash(100.0, 0.0));
  EXPECT_NEAR(sim.agent().stamina, 7975.0, 1e-6);
  sim.step();
  EXPECT_NEAR(sim.agent().pos.x, 1.05, 1e-6);
  EXPECT_NEAR(sim.agent().vel.x, 0.42, 1e-6);
  EXPECT_NEAR(sim.agent().stamina, 8000.0, kTol);
}

// ---------------------------------------------------------------------------------------
// §2.5 stamina after N full forward dashes from full stamina: each dash costs 100, then +45
// (recovery 1 * 45) while S < 8000, so S_N = 8000 - 55 N as long as the pre-recovery stamina
// stays above 2400:
//   N = 1: 8000 - 100 + 45 = 7945;  N = 2: 7945 - 100 + 45 = 7890;  N = 10: 8000 - 550 = 7450;
//   N = 100: 8000 - 5500 = 2500.
// Dash 101: pre-recovery S = 2500 - 100 = 2400 <= 2400 -> recovery 0.998, effort 0.995,
// inc = 0.998 * 45 = 44.91 -> S = 2444.91; capacity 130600 - 100 * 45 - 44.91 = 126055.09.
// Dash 102 is the first with reduced effort: accel = 100 * 0.995 * 0.006 = 0.597; pre-recovery
// S = 2444.91 - 100 = 2344.91 -> recovery 0.996, effort 0.99, inc = 0.996 * 45 = 44.82 ->
// S = 2389.73.
TEST(HfoPhysics, StaminaAfterFullDashes) {
  // Agent far from the ball and the posts (y = -20) so 102 cycles of running hit nothing.
  SoccerSim sim = sim_with_agent(make_agent({-60.0, -20.0}), {0.0, 30.0});
  for (int n = 1; n <= 100; ++n) {
    ASSERT_TRUE(sim.dash(100.0, 0.0));
    sim.step();
    EXPECT_NEAR(sim.agent().stamina, 8000.0 - 55.0 * n, kTol) << "after " << n << " dashes";
    EXPECT_EQ(sim.agent().effort, 1.0) << "after " << n << " dashes";
    EXPECT_EQ(sim.agent().recovery, 1.0) << "after " << n << " dashes";
    if (n == 1) {
      EXPECT_NEAR(sim.agent().stamina, 7945.0, kTol);
    } else if (n == 2) {
      EXPECT_NEAR(sim.agent().stamina, 7890.0, kTol);
    } else if (n == 10) {
      EXPECT_NEAR(sim.agent().stamina, 7450.0, kTol);
    }
  }
  EXPECT_NEAR(sim.agent().stamina, 2500.0, kTol);
  EXPECT_NEAR(sim.agent().capacity, 130600.0 - 4500.0, kTol);

  ASSERT_TRUE(sim.dash(100.0, 0.0));  // dash 101
  sim.step();
  EXPECT_NEAR(sim.agent().stamina, 2444.91, kTol);
  EXPECT_NEAR(sim.agent().effort, 0.995, kTol);
  EXPECT_NEAR(sim.agent().recovery, 0.998, kTol);
  EXPECT_NEAR(sim.agent().capacity, 126055.09, kTol);

  const double v_before = sim.agent().vel.x;  // 0.4 (steady state)
  EXPECT_NEAR(v_before, 0.4, kTol);
  ASSERT_TRUE(sim.dash(100.0, 0.0));  // dash 102
  sim.step();
  EXPECT_NEAR(sim.agent().vel.x, (v_before + 0.597) * 0.4, kTol);  // (0.4 + 0.597) * 0.4 = 0.3988
  EXPECT_NEAR(sim.agent().stamina, 2389.73, kTol);
  EXPECT_NEAR(sim.agent().effort, 0.99, kTol);
  EXPECT_NEAR(sim.agent().recovery, 0.996, kTol);
}

// §2.5 rules without dashing. S = 5000 >= 4800, effort 0.8 -> effort 0.81, S = 5045.
// S = 2000, recovery 0.5 (minimum), effort 0.6 (minimum): both stay, inc = 0.5 * 45 = 22.5.
// S = 7990: inc = min(45, 8000 - 7990) = 10 -> 8000 (never above the maximum).
TEST(HfoPhysics, StaminaRecoveryAndEffortRules) {
  PlayerState p = make_agent({0.0, 0.0});
  p.stamina = 5000.0;
  p.effort = 0.8;
  SoccerSim a = sim_with_agent(p);
  a.step();
  EXPECT_NEAR(a.agent().effort, 0.81, kTol);
  EXPECT_NEAR(a.agent().stamina, 5045.0, kTol);

  p.stamina = 2000.0;
  p.effort = 0.6;
  p.recovery = 0.5;
  SoccerSim b = sim_with_agent(p);
  b.step();
  EXPECT_NEAR(b.agent().effort, 0.6, kTol);
  EXPECT_NEAR(b.agent().recovery, 0.5, kTol);
  EXPECT_NEAR(b.agent().stamina, 2022.5, kTol);

  p = make_agent({0.0, 0.0});
  p.stamina = 7990.0;
  SoccerSim c = sim_with_agent(p);
  c.step();
  EXPECT_NEAR(c.agent().stamina, 8000.0, kTol);
  EXPECT_NEAR(c.agent().capacity, 130600.0 - 10.0, kTol);
}

// ---------------------------------------------------------------------------------------
// §2.6 turn. Net effect of Turn(theta) at speed v: clamp(theta (1 + 5v), -180, 180) / (1 + 5v).
//   v = 0:   Turn(180) -> 180 / 1 = 180
//   v = 0.2: 1 + 5 * 0.2 = 2; Turn(180) -> clamp(360) = 180 -> 180 / 2 = 90
//   v = 0.4: 1 + 5 * 0.4 = 3; Turn(180) -> 180 / 3 = 60
TEST(HfoPhysics, LargestTurnBySpeed) {
  struct Case {
    double speed;
    double turned;
  };
  const Case cases[] = {{0.0, 180.0}, {0.2, 90.0}, {0.4, 60.0}};
  for (const Case& c : cases) {
    SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}, 0.0, {0.0, c.speed}));
    ASSERT_TRUE(sim.turn(180.0));
    sim.step();
    EXPECT_NEAR(sim.agent().body_deg, c.turned, kTol) << "speed " << c.speed;
  }
  // Same limit the other way (-180 itself wraps to +180): Turn(-179) at v = 0.4 ->
  // moment -179 * 3 = -537 -> clamp -180 -> -180 / 3 = -60.
  SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}, 0.0, {0.4, 0.0}));
  ASSERT_TRUE(sim.turn(-179.0));
  sim.step();
  EXPECT_NEAR(sim.agent().body_deg, -60.0, kTol);
}

// Client pre-compensation: below the limit the desired turn is executed exactly.
//   v = 0.2, Turn(30): moment 30 * 2 = 60 -> 60 / 2 = 30
//   v = 0.1, Turn(45.5): inertia 1.5, moment 68.25 -> 68.25 / 1.5 = 45.5
//   v = 0.2, Turn(-120): moment -240 -> clamp -180 -> -180 / 2 = -90
//   v = 0.4, Turn(-50): moment -150 -> -50
//   v = 0.4, Turn(70): moment 210 -> 180 -> 60
TEST(HfoPhysics, TurnInertiaPrecompensation) {
  struct Case {
    double speed;
    double turn;
    double turned;
  };
  const Case cases[] = {
      {0.2, 30.0, 30.0}, {0.1, 45.5, 45.5}, {0.2, -120.0, -90.0}, {0.4, -50.0, -50.0}, {0.4, 70.0, 60.0}};
  for (const Case& c : cases) {
    SoccerSim sim = sim_with_agent(make_agent({0.0, 0.0}, 0.0, {c.speed, 0.0}));
    ASSERT_TRUE(sim.turn(c.turn));
    sim.step();
    EXPECT_NEAR(sim.agent().body_deg, c.turned, kTol) << "speed " << c.speed << " turn " << c.turn;
  }
}

// Turn wrapping: the argument is wrapped (270 -> -90) and the body is wrapped to (-180, 180]
// (170 + 20 = 190 -> -170). While turning the player keeps drifting: v = (0.2, 0) -> x = 0.2,
// observed v = 0.2 * 0.4 = 0.08; a turn uses no stamina: 8000.
TEST(HfoPhysics, TurnWrapsAndKeepsDrifting) {
  SoccerSim a = sim_with_agent(make_agent({0.0, 0.0}, 0.0));
  ASSERT_TRUE(a.turn(270.0));
  a.step();
  EXPECT_NEAR(a.agent().body_deg, -90.0, kTol);

  SoccerSim b = sim_with_agent(make_agent({0.0, 0.0}, 170.0));
  ASSERT_TRUE(b.turn(20.0));
  b.step();
  EXPECT_NEAR(b.agent().body_deg, -170.0, kTol);

  SoccerSim c = sim_with_agent(make_agent({0.0, 0.0}, 0.0, {0.2, 0.0}));
  ASSERT_TRUE(c.turn(30.0));
  c.step();
  EXPECT_NEAR(c.agent().body_deg, 30.0, kTol);
  EXPECT_NEAR(c.agent().pos.x, 0.2, kTol);
  EXPECT_NEAR(c.agent().pos.y, 0.0, kTol);
  EXPECT_NEAR(c.agent().vel.x, 0.08, kTol);
  EXPECT_NEAR(c.agent().stamina, 8000.0, kTol);
}

// ---------------------------------------------------------------------------------------
// §2.7 kick effective power: eff = power * 0.027 * (1 - 0.25 phi/pi - 0.25 delta/0.7),
// delta = d - 0.3 - 0.085, then accel clamp 2.7, v += a, speed clamp 3.0, p += v, v *= 0.94.

// Ball touching the body straight ahead (d = 0.385 -> delta = 0, phi = 0): factor 1,
// eff = 100 * 0.027 = 2.7. Ball: v = 2.7, x = 0.385 + 2.7 = 3.085, observed v = 2.7 * 0.94 = 2.538.
TEST(HfoPhysics, KickMaxPowerTouching) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({0.385, 0.0}));
  ASSERT_TRUE(sim.kick(100.0, 0.0));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 3.085, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 0.0, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 2.538, kTol);
  EXPECT_NEAR(sim.state().ball.vel.y, 0.0, kTol);
}

// At the client's kickable limit d = 1.03 straight ahead: delta = 1.03 - 0.385 = 0.645,
// factor = 1 - 0.25 * 0.645 / 0.7 = 1 - 0.2303571428571 = 0.7696428571429,
// eff = 2.7 * 0.7696428571429 = 2.0780357142857. Ball x = 1.03 + 2.0780357142857 = 3.1080357142857,
// observed v = 2.0780357142857 * 0.94 = 1.9533535714286.
TEST(HfoPhysics, KickAtClientLimit) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({1.03, 0.0}));
  ASSERT_TRUE(sim.kick(100.0, 0.0));
  sim.step();
  const double eff = 2.7 * (1.0 - 0.25 * 0.645 / 0.7);
  EXPECT_NEAR(eff, 2.0780357142857, 1e-12);
  EXPECT_NEAR(sim.state().ball.pos.x, 1.03 + 2.0780357142857, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 1.9533535714286, kTol);
  EXPECT_NEAR(sim.state().ball.vel.y, 0.0, kTol);
}

// Ball at 90 deg to the side, d = 0.5: phi = pi/2 -> 0.25 * 0.5 = 0.125; delta = 0.115 ->
// 0.25 * 0.115 / 0.7 = 0.0410714285714; factor = 1 - 0.125 - 0.0410714285714 = 0.8339285714286;
// eff = 2.7 * 0.8339285714286 = 2.2516071428571. Kick dir 0 is relative to the body (+x), not
// toward the ball (+y): the ball moves along +x from (0, 0.5).
TEST(HfoPhysics, KickBallToTheSideGoesAlongBody) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({0.0, 0.5}));
  ASSERT_TRUE(sim.kick(100.0, 0.0));
  sim.step();
  const double eff = 2.2516071428571;
  EXPECT_NEAR(sim.state().ball.pos.x, eff, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 0.5, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, eff * 0.94, kTol);
  EXPECT_NEAR(sim.state().ball.vel.y, 0.0, kTol);
}

// Ball straight behind, d = 0.5: phi = pi -> 0.25; factor = 1 - 0.25 - 0.0410714285714 =
// 0.7089285714286; eff = 2.7 * 0.7089285714286 = 1.9141071428571, kicked forward (+x) it passes
// through the player (no continuous collision detection): x = -0.5 + 1.9141071428571.
TEST(HfoPhysics, KickBallBehind) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({-0.5, 0.0}));
  ASSERT_TRUE(sim.kick(100.0, 0.0));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, -0.5 + 1.9141071428571, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 1.9141071428571 * 0.94, kTol);
}

// Direction relative to the body: body 90, ball straight ahead at (0, 0.6), Kick(50, -90):
// direction 90 - 90 = 0 deg (global +x). delta = 0.6 - 0.385 = 0.215 ->
// factor = 1 - 0.25 * 0.215 / 0.7 = 0.9232142857143; eff = 50 * 0.027 * 0.9232142857143 =
// 1.35 * 0.9232142857143 = 1.2463392857143.
// Kick(100, 270) with body 0 and ball at (0.5, 0): 270 wraps to -90 -> global -90 deg;
// eff = 2.7 * (1 - 0.0410714285714) = 2.5891071428571 along -y.
TEST(HfoPhysics, KickDirectionRelativeToBody) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}, 90.0), make_ball({0.0, 0.6}));
  ASSERT_TRUE(sim.kick(50.0, -90.0));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 1.2463392857143, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 0.6, kTol);

  SoccerSim wrap(quiet_config(), 1);
  wrap.set_state(make_agent({0.0, 0.0}), make_ball({0.5, 0.0}));
  ASSERT_TRUE(wrap.kick(100.0, 270.0));
  wrap.step();
  EXPECT_NEAR(wrap.state().ball.pos.x, 0.5, kTol);
  EXPECT_NEAR(wrap.state().ball.pos.y, -2.5891071428571, kTol);
}

// Kick power is clamped to [0, 100]: Kick(150, 0) equals Kick(100, 0) (eff 2.5891071428571
// for d = 0.5), a negative power becomes 0 and leaves the ball at rest.
TEST(HfoPhysics, KickPowerClamped) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({0.5, 0.0}));
  ASSERT_TRUE(sim.kick(150.0, 0.0));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 0.5 + 2.5891071428571, kTol);

  SoccerSim neg(quiet_config(), 1);
  neg.set_state(make_agent({0.0, 0.0}), make_ball({0.5, 0.0}));
  neg.kick(-50.0, 0.0);
  neg.step();
  EXPECT_NEAR(neg.state().ball.pos.x, 0.5, kTol);
  EXPECT_NEAR(neg.state().ball.vel.r(), 0.0, kTol);
}

// The kick is added to the current ball velocity, then the speed is clamped to 3.0.
// Ball at (0.5, 0) moving (2, 0), Kick(100, 0): eff = 2.5891071428571; v = 4.5891071428571 >
// 3.0 -> 3.0; x = 0.5 + 3.0 = 3.5; observed v = 3.0 * 0.94 = 2.82.
// Ball at (0.5, 0) moving (0, 1), Kick(40, 0): eff = 40 * 0.027 * 0.9589285714286 =
// 1.08 * 0.9589285714286 = 1.0356428571429; v = (1.0356428571429, 1) (|v| = 1.4396 < 3);
// p = (1.5356428571429, 1.0); observed v = (0.9735042857143, 0.94).
TEST(HfoPhysics, KickAddsToBallVelocityAndClamps) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({0.5, 0.0}, {2.0, 0.0}));
  ASSERT_TRUE(sim.kick(100.0, 0.0));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 3.5, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 2.82, kTol);

  SoccerSim add(quiet_config(), 1);
  add.set_state(make_agent({0.0, 0.0}), make_ball({0.5, 0.0}, {0.0, 1.0}));
  ASSERT_TRUE(add.kick(40.0, 0.0));
  add.step();
  EXPECT_NEAR(add.state().ball.pos.x, 1.5356428571429, kTol);
  EXPECT_NEAR(add.state().ball.pos.y, 1.0, kTol);
  EXPECT_NEAR(add.state().ball.vel.x, 0.9735042857143, kTol);
  EXPECT_NEAR(add.state().ball.vel.y, 0.94, kTol);
}

// §2.7 client gating: the ball at 1.05 m (> 1.03, though <= 1.085 for the server) is not
// kickable for the client: kick() returns false and the ball stays where it is. At 1.02 m the
// kick is sent.
TEST(HfoPhysics, KickGatedByClientKickableArea) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({1.05, 0.0}));
  EXPECT_FALSE(sim.agent_kickable());
  EXPECT_FALSE(sim.kick(100.0, 0.0));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 1.05, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 0.0, kTol);
  EXPECT_NEAR(sim.state().ball.vel.r(), 0.0, kTol);
  EXPECT_NEAR(sim.agent().stamina, 8000.0, kTol);

  SoccerSim ok(quiet_config(), 1);
  ok.set_state(make_agent({0.0, 0.0}), make_ball({1.02, 0.0}));
  EXPECT_TRUE(ok.agent_kickable());
  EXPECT_TRUE(ok.kick(100.0, 0.0));
  ok.step();
  EXPECT_GT(ok.state().ball.pos.x, 2.0);
}

// ---------------------------------------------------------------------------------------
// §2.8 tackle freeze: the counter is set to 10 and decremented at the start of each step, so
// after the tackle's own step it reads 9 and the next 9 observed states are frozen; the
// commands of those 9 cycles (dash, turn, kick, tackle) are refused.
TEST(HfoPhysics, TackleFreezesNineObservedCycles) {
  SoccerSim sim(quiet_config(), 1);
  // Ball behind (tackle fails) but kickable for the client (0.5 m).
  sim.set_state(make_agent({0.0, 0.0}), make_ball({-0.5, 0.0}));
  ASSERT_TRUE(sim.tackle(0.0));
  sim.step();
  int frozen_observations = 0;
  while (sim.agent().tackle_cycles > 0 && frozen_observations < 20) {
    ++frozen_observations;
    EXPECT_FALSE(sim.dash(100.0, 0.0));
    EXPECT_FALSE(sim.turn(90.0));
    EXPECT_FALSE(sim.kick(100.0, 0.0));
    EXPECT_FALSE(sim.tackle(0.0));
    sim.step();
    EXPECT_NEAR(sim.agent().pos.x, 0.0, kTol);
    EXPECT_NEAR(sim.agent().body_deg, 0.0, kTol);
    EXPECT_NEAR(sim.state().ball.pos.x, -0.5, kTol);
    EXPECT_NEAR(sim.agent().stamina, 8000.0, kTol);
  }
  EXPECT_EQ(frozen_observations, 9);
  EXPECT_TRUE(sim.dash(100.0, 0.0));
  sim.step();
  EXPECT_NEAR(sim.agent().pos.x, 0.6, kTol);
}

// A tackle with the ball behind (q.x <= 0; back tackle distance 0) always fails; a tackle with
// f = (q.x/2)^6 + (|q.y|/1.25)^6 >= 1 fails: ball at (2, 0): f = 1^6 = 1; ball at (0.5, 1.3):
// f = 0.25^6 + 1.04^6 = 1.2656 > 1; ball at (-0.3, 0.3) behind. Every failed tackle still freezes.
TEST(HfoPhysics, TackleFailures) {
  const Vec2 balls[] = {{-0.5, 0.0}, {-0.3, 0.3}, {2.0, 0.0}, {0.5, 1.3}, {2.1, 0.0}};
  for (uint64_t seed = 0; seed < 20; ++seed) {
    for (const Vec2& b : balls) {
      SoccerSim sim(quiet_config(), seed);
      sim.set_state(make_agent({0.0, 0.0}), make_ball(b));
      ASSERT_TRUE(sim.tackle(0.0));
      EXPECT_EQ(sim.agent().tackle_cycles, 10);
      sim.step();
      EXPECT_EQ(sim.agent().tackle_cycles, 9);
      EXPECT_NEAR(sim.state().ball.pos.x, b.x, kTol) << "ball " << b.x << "," << b.y;
      EXPECT_NEAR(sim.state().ball.pos.y, b.y, kTol) << "ball " << b.x << "," << b.y;
      EXPECT_NEAR(sim.state().ball.vel.r(), 0.0, kTol);
    }
  }
  // Same in the body frame: body 90, ball at (0, -0.5) is behind the agent.
  SoccerSim sim(quiet_config(), 3);
  sim.set_state(make_agent({0.0, 0.0}, 90.0), make_ball({0.0, -0.5}));
  sim.tackle(0.0);
  sim.step();
  EXPECT_NEAR(sim.state().ball.vel.r(), 0.0, kTol);
}

// A tackle with tiny f succeeds (f = (0.5/2)^6 = 0.000244; fixed seed). With A = 90:
// eff = 100 * (1 - 90/180) * 0.027 * (1 - 0.5 * |atan2(0, 0.5)| / pi) = 50 * 0.027 = 1.35 along
// body + 90 = 90 deg -> ball (0.5, 1.35), observed v = (0, 1.35 * 0.94 = 1.269).
TEST(HfoPhysics, TackleSuccessPushesBall) {
  SoccerSim sim(quiet_config(), 7);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({0.5, 0.0}));
  ASSERT_TRUE(sim.tackle(90.0));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 0.5, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 1.35, kTol);
  EXPECT_NEAR(sim.state().ball.vel.y, 1.269, kTol);
}

// ---------------------------------------------------------------------------------------
// §2.9 ball-player collision. Agent at (0, 0) moving (0.1, 0); ball at (1, 0) moving (-0.8, 0);
// no commands. After movement: agent x = 0.1 (v 0.04), ball x = 1 - 0.8 = 0.2 (v -0.752).
// Distance 0.1 < 0.385 -> midpoint 0.15, each moved to 0.385/2 + 1e-10 = 0.1925 + 1e-10 from it:
// ball 0.3425 + 1e-10, agent -0.0425 - 1e-10 (distance 0.385 + 2e-10). Velocities * -0.1:
// ball -0.752 * -0.1 = 0.0752, agent 0.04 * -0.1 = -0.004. The agent's collided_ball flag is set
// for this cycle only: next cycle agent -0.0465, ball 0.4177, 0.4642 apart -> no collision.
TEST(HfoPhysics, BallPlayerCollision) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}, 0.0, {0.1, 0.0}), make_ball({1.0, 0.0}, {-0.8, 0.0}));
  sim.step();
  const PlayerState& a = sim.agent();
  const BallState& b = sim.state().ball;
  EXPECT_NEAR(b.pos.x, 0.3425, kTol);
  EXPECT_NEAR(a.pos.x, -0.0425, kTol);
  EXPECT_NEAR(b.pos.y, 0.0, kTol);
  EXPECT_NEAR(a.pos.y, 0.0, kTol);
  EXPECT_NEAR((b.pos - a.pos).r(), 0.385 + 2e-10, 1e-12);
  EXPECT_GE((b.pos - a.pos).r(), 0.385);
  EXPECT_NEAR((b.pos.x + a.pos.x) / 2.0, 0.15, 1e-12);  // symmetric about the midpoint
  EXPECT_NEAR(b.vel.x, 0.0752, kTol);
  EXPECT_NEAR(a.vel.x, -0.004, kTol);
  EXPECT_TRUE(a.collided_ball);

  sim.step();
  EXPECT_FALSE(sim.agent().collided_ball);
  EXPECT_NEAR(sim.agent().pos.x, -0.0425 - 0.004, kTol);
  EXPECT_NEAR(sim.state().ball.pos.x, 0.3425 + 0.0752, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 0.0752 * 0.94, kTol);
}

// Collision in two dimensions: agent at rest at (0, 0), ball at rest at (0.18, 0.24) (0.3 m
// away, overlapping). Midpoint (0.09, 0.12), unit (0.6, 0.8): ball -> (0.09, 0.12) + 0.1925 *
// (0.6, 0.8) = (0.2055, 0.274), agent -> (0.09, 0.12) - 0.1925 * (0.6, 0.8) = (-0.0255, -0.034).
TEST(HfoPhysics, BallPlayerCollisionAlongLineOfCentres) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}), make_ball({0.18, 0.24}));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 0.2055, 1e-9);
  EXPECT_NEAR(sim.state().ball.pos.y, 0.274, 1e-9);
  EXPECT_NEAR(sim.agent().pos.x, -0.0255, 1e-9);
  EXPECT_NEAR(sim.agent().pos.y, -0.034, 1e-9);
  EXPECT_TRUE(sim.agent().collided_ball);
}

// ---------------------------------------------------------------------------------------
// §2.3 goal post bounce (post circle at (52.44, 7.07), radius 0.06; ball radius 0.085 ->
// contact at centre distance 0.145).
// Head-on: ball at (51.44, 7.07) moving (1.5, 0). Contact at x = 52.44 - 0.145 = 52.295 after
// 0.855 of the 1.5 m; the remaining 0.645 is mirrored: x = 52.295 - 0.645 = 51.65 (- 1e-10);
// v = (-1.5, 0), speed preserved, then decay: (-1.41, 0).
TEST(HfoPhysics, GoalPostHeadOnBounce) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({30.0, -20.0}), make_ball({51.44, 7.07}, {1.5, 0.0}));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 51.65, 1e-9);
  EXPECT_NEAR(sim.state().ball.pos.y, 7.07, 1e-9);
  EXPECT_NEAR(sim.state().ball.vel.x, -1.41, 1e-9);
  EXPECT_NEAR(sim.state().ball.vel.y, 0.0, 1e-9);
}

// Oblique: ball at (51.44, 7.07 + 0.145 sin30 = 7.1425) moving (1.5, 0). Contact normal
// n = (-cos30, sin30) = (-0.8660254, 0.5) at x = 52.44 - 0.145 cos30 = 52.44 - 0.1255737 =
// 52.3144263. Reflection: v - 2 (v.n) n = (1.5, 0) + 2.5980762 * (-0.8660254, 0.5) =
// (1.5 - 2.25, 1.2990381) = (-0.75, 1.2990381): |v| = 1.5 preserved, direction 120 deg.
// Remaining distance 1.5 - (52.3144263 - 51.44) = 0.6255737 along 120 deg:
// p = (52.3144263 - 0.3127868, 7.1425 + 0.5417627) = (52.0016395, 7.6842627).
// Observed v = 0.94 * (-0.75, 1.2990381) = (-0.705, 1.2210958).
TEST(HfoPhysics, GoalPostObliqueBounceIsElastic) {
  SoccerSim sim(quiet_config(), 1);
  const double c30 = std::cos(kPi / 6.0);
  const double y0 = 7.07 + 0.145 * 0.5;
  sim.set_state(make_agent({30.0, -20.0}), make_ball({51.44, y0}, {1.5, 0.0}));
  sim.step();
  const double contact_x = 52.44 - 0.145 * c30;
  const double rest = 1.5 - (contact_x - 51.44);
  EXPECT_NEAR(sim.state().ball.pos.x, contact_x - 0.5 * rest, 1e-9);
  EXPECT_NEAR(sim.state().ball.pos.y, y0 + c30 * rest, 1e-9);
  EXPECT_NEAR(sim.state().ball.pos.x, 52.0016395, 1e-6);
  EXPECT_NEAR(sim.state().ball.pos.y, 7.6842627, 1e-6);
  EXPECT_NEAR(sim.state().ball.vel.x, -0.705, 1e-9);
  EXPECT_NEAR(sim.state().ball.vel.y, 0.94 * 1.5 * c30, 1e-9);
  EXPECT_NEAR(sim.state().ball.vel.r(), 0.94 * 1.5, 1e-9);
}

// A ball passing 0.2 m from the post (> 0.145) is not deflected: from (51.44, 7.27) moving
// (1.5, 0) it ends at (52.94, 7.27) with v (1.41, 0).
TEST(HfoPhysics, GoalPostMissedByBall) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({30.0, -20.0}), make_ball({51.44, 7.27}, {1.5, 0.0}));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 52.94, 1e-9);
  EXPECT_NEAR(sim.state().ball.pos.y, 7.27, 1e-9);
  EXPECT_NEAR(sim.state().ball.vel.x, 1.41, 1e-9);
}

// ---------------------------------------------------------------------------------------
// §2.3 decay. Ball (10, 10) moving (1, 0.5): p = (11, 10.5), v = 0.94 * (1, 0.5) = (0.94, 0.47);
// next cycle p = (11.94, 10.97), v = (0.8836, 0.4418).
// Player (0, 0) moving (0.5, 0), no command: p = 0.5, v = 0.4 * 0.5 = 0.2; then p = 0.7, v = 0.08.
TEST(HfoPhysics, BallAndPlayerDecay) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}, 0.0, {0.5, 0.0}), make_ball({10.0, 10.0}, {1.0, 0.5}));
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 11.0, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 10.5, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 0.94, kTol);
  EXPECT_NEAR(sim.state().ball.vel.y, 0.47, kTol);
  EXPECT_NEAR(sim.agent().pos.x, 0.5, kTol);
  EXPECT_NEAR(sim.agent().vel.x, 0.2, kTol);
  sim.step();
  EXPECT_NEAR(sim.state().ball.pos.x, 11.94, kTol);
  EXPECT_NEAR(sim.state().ball.pos.y, 10.97, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 0.8836, kTol);
  EXPECT_NEAR(sim.state().ball.vel.y, 0.4418, kTol);
  EXPECT_NEAR(sim.agent().pos.x, 0.7, kTol);
  EXPECT_NEAR(sim.agent().vel.x, 0.08, kTol);
}

// §2.3 step 1: the speed clamps apply only in cycles with a non-zero acceleration. A player
// set moving at 1.2 (> 1.05) with no command moves 1.2 and observes 1.2 * 0.4 = 0.48; a ball
// moving at 3.5 (> 3.0) moves 3.5 and observes 3.5 * 0.94 = 3.29.
TEST(HfoPhysics, SpeedClampOnlyWithAcceleration) {
  SoccerSim sim(quiet_config(), 1);
  sim.set_state(make_agent({0.0, 0.0}, 0.0, {1.2, 0.0}), make_ball({10.0, -10.0}, {3.5, 0.0}));
  sim.step();
  EXPECT_NEAR(sim.agent().pos.x, 1.2, kTol);
  EXPECT_NEAR(sim.agent().vel.x, 0.48, kTol);
  EXPECT_NEAR(sim.state().ball.pos.x, 13.5, kTol);
  EXPECT_NEAR(sim.state().ball.vel.x, 3.29, kTol);
}

}  // namespace
}  // namespace pamdp::hfo
