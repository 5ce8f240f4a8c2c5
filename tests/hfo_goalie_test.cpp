// The NPC goalie of the embedded simulator (envs/hfo/goalie.hpp) and the 1v1 task: start
// position (shared/hfo-reference.md §5.1), positioning, the catch and CAPTURED_BY_DEFENSE
// (§5.2), the opponent features (§3.3), determinism, and the scripted offense's scoring rate
// against it.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "envs/hfo/features.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/goalie.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/hfo/soccer_sim.hpp"
#include "learner/evaluation.hpp"

namespace pamdp::hfo {
namespace {

SoccerSimConfig goalie_config(bool noise = false) {
  SoccerSimConfig c;
  c.noise = noise;
  c.goalie = true;
  return c;
}

PlayerState agent_at(Vec2 pos, double body_deg = 0.0) {
  PlayerState p;
  p.pos = pos;
  p.body_deg = body_deg;
  return p;
}

// An action that changes nothing: dash with power 0.
ParamAction no_op(std::array<float, param::kCount>& params) {
  params.fill(0.0F);
  return {kDash, params};
}

TEST(HfoGoalie, OffByDefaultSo1v0Keeps58Features) {
  HfoEnv env;
  EXPECT_EQ(env.observation_size(), kNumAgentFeatures);
  EXPECT_EQ(env.sim().state().num_players, 1);
}

TEST(HfoGoalie, StartsAtGoalCentreEveryEpisode) {
  HfoEnv env(goalie_config(false));
  ASSERT_EQ(env.observation_size(), 66);
  std::vector<float> obs(66);
  std::array<float, param::kCount> params{};
  double body_before_reset = kGoalieStartBodyDeg;
  for (int ep = 0; ep < 3; ++ep) {
    env.reset(static_cast<uint64_t>(ep) + 5, obs);
    const SoccerState& s = env.sim().state();
    EXPECT_EQ(s.num_players, 2);
    // The first observation comes two cycles after the reset, as HFO's client's does; only the
    // goalie has moved. The same two cycles from (52.5, 0) at rest, full stamina, the body it
    // had, must give the same goalie.
    EXPECT_EQ(s.cycle, kCyclesBeforeFirstObservation);
    SoccerSim replay(goalie_config(false), 0);
    PlayerState agent = s.players[0];
    replay.set_state(agent, BallState{s.ball.pos, {0.0, 0.0}});
    PlayerState g0 = replay.state().players[kGoalieIndex];
    g0.body_deg = body_before_reset;
    replay.set_goalie(g0);
    for (int k = 0; k < kCyclesBeforeFirstObservation; ++k) {
      replay.step();
    }
    const PlayerState& g = s.players[kGoalieIndex];
    const PlayerState& want = replay.state().players[kGoalieIndex];
    EXPECT_EQ(g.pos.x, want.pos.x);
    EXPECT_EQ(g.pos.y, want.pos.y);
    EXPECT_EQ(g.body_deg, want.body_deg) << "HFO leaves the goalie's body as it was at the reset";
    EXPECT_EQ(g.stamina, want.stamina);
    EXPECT_LT((g.pos - kGoalieStart).r(), 1.0);
    EXPECT_TRUE(s.ball.vel.is_zero());
    EXPECT_TRUE(s.players[0].vel.is_zero());
    EXPECT_EQ(g.team, Team::kDefense);
    EXPECT_TRUE(g.goalie);
    for (int k = 0; k < 30; ++k) {
      if (env.step(no_op(params), obs).terminal()) {
        break;
      }
    }
    body_before_reset = env.sim().state().players[kGoalieIndex].body_deg;
  }
}

// A tackle freeze outlives the reset, as Player::place leaves it (real goalie transitions rows
// 174-180: frozen from its tackle in cycle 41125 to cycle 41134, across a reset).
TEST(HfoGoalie, TackleFreezeAndCatchMemoryCarryOverTheReset) {
  SoccerSim sim(goalie_config(false), 1);
  sim.reset_episode();
  PlayerState g = sim.state().players[kGoalieIndex];
  g.tackle_cycles = 6;
  g.since_catch = 2;
  g.caught = true;
  sim.set_goalie(g);
  sim.reset_episode();
  const PlayerState& after = sim.state().players[kGoalieIndex];
  // One cycle the server waits after the terminal state, then the two before the observation.
  EXPECT_EQ(after.tackle_cycles, 6 - 1 - kCyclesBeforeFirstObservation);
  EXPECT_EQ(after.since_catch, 2 + 1 + kCyclesBeforeFirstObservation);
  EXPECT_FALSE(after.caught) << "the reset's play_on ends the goalie's catch play mode";
  EXPECT_EQ(after.pos.x, kGoalieStart.x) << "frozen: it could not move in the first two cycles";
  EXPECT_EQ(after.pos.y, kGoalieStart.y);
}

// agent2d's basic position (Bhv_GoalieBasicMove::getTargetPoint): for a ball at rest at
// (30, 15) with the attacker far away, the point 2.7 m in front of the goal line (x = 49.8) on
// the line from the ball to a point 7 m behind the goal centre, y = 15 x 9.7 / 29.5 = 4.93;
// there it stops within its tolerance (8 % of the ball's distance sideways, 0.5 m in x) and
// turns its body across the goal, toward the ball's side (doCorrectBodyDir: 90 degrees).
TEST(HfoGoalie, BasicPositionOnTheLineFromTheBallToBehindTheGoal) {
  SoccerSim sim(goalie_config(), 1);
  sim.set_state(agent_at({5.0, -20.0}), BallState{{30.0, 15.0}, {0.0, 0.0}});
  PlayerState g = sim.state().players[kGoalieIndex];
  g.pos = {50.0, -5.0};
  sim.set_goalie(g);
  for (int k = 0; k < 60; ++k) {
    ASSERT_EQ(sim.step(), kInGame) << "cycle " << k;
  }
  const PlayerState& after = sim.state().players[kGoalieIndex];
  const double ball_dist = (sim.state().ball.pos - after.pos).r();
  EXPECT_NEAR(after.pos.x, 49.8, 0.5);
  EXPECT_NEAR(after.pos.y, 15.0 * 9.7 / 29.5, 0.08 * ball_dist);
  EXPECT_GT(after.pos.y, 2.0) << "it moved over from y = -5";
  EXPECT_LT(after.vel.r(), 0.05) << "and stopped";
  EXPECT_NEAR(after.body_deg, 90.0, 5.0);
}

// The catchable area: 1.2 m long, 1.0 m wide, in the catch direction; a failed attempt bans
// the next one for 5 cycles; only goalies catch. In HFO mode the server refuses no catch for
// the ball's place (CatchRef::ballCaught returns first), and a caught ball is not held: the
// goalie is moved to touch it (0.385 m), faces it and stops, and the ball flies on.
TEST(HfoGoalie, CatchRules) {
  SoccerSim sim(goalie_config(), 1);
  const auto place = [&](Vec2 ball, Vec2 ball_vel = {}) {
    sim.set_state(agent_at({20.0, 20.0}), BallState{ball, ball_vel});
    sim.mutable_state().players[kGoalieIndex].body_deg = 180.0;  // facing -x
  };
  // 1.13 m ahead and a little to the side, moving.
  place({51.4, 0.25}, {0.5, 0.2});
  EXPECT_FALSE(sim.goalie_catch(0, 0.0)) << "the agent is no goalie";
  const double to_ball = wrap_deg(std::atan2(0.25, -1.1) * kRadToDeg - 180.0);
  EXPECT_TRUE(sim.goalie_catch(kGoalieIndex, to_ball));
  const PlayerState& g = sim.state().players[kGoalieIndex];
  const double r = std::hypot(1.1, 0.25);
  EXPECT_NEAR(g.pos.x, 52.5 - 1.1 * (r - 0.385) / r, 1e-9) << "moved to touch the ball";
  EXPECT_NEAR(g.pos.y, 0.25 * (r - 0.385) / r, 1e-9);
  EXPECT_NEAR((sim.state().ball.pos - g.pos).r(), 0.385, 1e-9);
  EXPECT_TRUE(g.vel.is_zero());
  EXPECT_NEAR(g.body_deg, std::atan2(0.25, -1.1) * kRadToDeg, 1e-9) << "facing the ball";
  EXPECT_EQ(sim.state().ball.vel.x, 0.5) << "the ball keeps its flight";
  EXPECT_EQ(sim.state().ball.vel.y, 0.2);
  // The touching distance is computed, not set: where it rounds below 0.385 the server's
  // collisions() at the catch finds the ball touching and bounces it (velocity x -0.1), as here.
  place({51.4, 0.0}, {0.5, 0.2});
  EXPECT_TRUE(sim.goalie_catch(kGoalieIndex, 0.0));
  EXPECT_NEAR(sim.state().ball.vel.x, -0.05, 1e-12);
  EXPECT_NEAR(sim.state().ball.vel.y, -0.02, 1e-12);

  place({51.25, 0.0});  // 1.25 m ahead: beyond the catchable length
  EXPECT_FALSE(sim.goalie_catch(kGoalieIndex, 0.0));
  sim.mutable_state().ball.pos = {51.9, 0.0};  // 0.6 m ahead, but the failed attempt's ban holds
  for (int k = 0; k < kCatchBanCycles; ++k) {
    EXPECT_FALSE(sim.goalie_catch(kGoalieIndex, 0.0)) << "cycle " << k;
    sim.mutable_state().players[kGoalieIndex].catch_ban -= 1;  // what step() does
  }
  EXPECT_TRUE(sim.goalie_catch(kGoalieIndex, 0.0));

  place({51.9, 0.45});  // 0.6 ahead, 0.45 to the side: inside the 1.0 m width
  EXPECT_TRUE(sim.goalie_catch(kGoalieIndex, 0.0));
  place({51.9, 0.55});  // 0.55 to the side: outside
  EXPECT_FALSE(sim.goalie_catch(kGoalieIndex, 0.0));
  place({51.9, 0.55});  // the same ball, caught by turning the catch toward it
  sim.mutable_state().players[kGoalieIndex].catch_ban = 0;
  EXPECT_TRUE(sim.goalie_catch(kGoalieIndex, wrap_deg(std::atan2(0.55, -0.6) * kRadToDeg - 180.0)));
  place({51.4, 0.0});  // behind the catch direction
  EXPECT_FALSE(sim.goalie_catch(kGoalieIndex, 180.0));

  sim.set_state(agent_at({20.0, 20.0}), BallState{{35.0, 0.0}, {0.0, 0.0}});
  PlayerState out = sim.state().players[kGoalieIndex];
  out.pos = {35.8, 0.0};  // ball 0.8 m away, outside the penalty area: caught all the same
  sim.set_goalie(out);
  EXPECT_TRUE(sim.goalie_catch(kGoalieIndex, 180.0 - sim.state().players[kGoalieIndex].body_deg));
}

// A fast ball caught as it passes the goalie's side flies on: the catch alone ends nothing.
// Row 3 of the real goalie transitions (scripted_bottomside_s403, episode 404, t = 70): the
// goalie catches, is moved to (49.29, 5.754) and the ball goes on to (50.905, 5.634), in play.
TEST(HfoGoalie, CaughtBallFliesOnInHfoMode) {
  SoccerSim sim(goalie_config(), 1);
  sim.set_state(agent_at({40.745, 7.0847}), BallState{{48.9381, 5.9098}, {1.9668, -0.276}});
  PlayerState g = sim.state().players[kGoalieIndex];
  g.pos = {49.9714, 5.453};
  g.vel = {0.0, 0.1344};
  g.body_deg = 90.0;
  sim.set_goalie(g);
  // The goalie's own decision this cycle is the recorded catch (its command is the cycle's).
  const GoalieCommand c = decide_goalie(sim.state(), kGoalieIndex, false);
  ASSERT_EQ(c.kind, GoalieCommand::Kind::kCatch);
  EXPECT_NEAR(c.p1, 88.7726, 1e-2);  // the logged state is rounded to 1e-4
  EXPECT_EQ(sim.step(), kInGame);
  EXPECT_TRUE(sim.state().players[kGoalieIndex].caught) << "it heard goalie_catch_ball_r: the set play until the reset";
  const PlayerState& after = sim.state().players[kGoalieIndex];
  EXPECT_NEAR(after.pos.x, 49.2903, 2e-4);
  EXPECT_NEAR(after.pos.y, 5.7541, 2e-4);
  EXPECT_NEAR(after.body_deg, 156.152, 1e-2);
  EXPECT_NEAR(sim.state().ball.pos.x, 50.905, 2e-4) << "the ball moved on by its velocity";
  EXPECT_NEAR(sim.state().ball.pos.y, 5.6338, 2e-4);
}

// The ball 1.15 m in front of the goalie (outside the 1.085 m kickable area, inside the 1.2 m
// catchable length): it catches in the first cycle and the episode ends CAPTURED_BY_DEFENSE
// with reward 0 (no shaping on the first or the terminal transition, no goal).
TEST(HfoGoalie, CatchEndsEpisodeCapturedByDefense) {
  HfoEnv env(goalie_config());
  std::vector<float> obs(66);
  std::array<float, param::kCount> params{};
  env.set_state(agent_at({30.0, 10.0}), BallState{{52.5 - 1.15, 0.0}, {0.0, 0.0}}, obs);
  const StepResult r = env.step(no_op(params), obs);
  EXPECT_EQ(r.status, kCapturedByDefense);
  EXPECT_EQ(r.reward, 0.0F);
  EXPECT_TRUE(env.sim().state().ball_caught);
  EXPECT_EQ(env.status_name(r.status), "CAPTURED_BY_DEFENSE");
}

// A slow ball rolled straight at the goalie from 10 m: it never reaches the goal.
TEST(HfoGoalie, SlowShotStraightAtItIsCaptured) {
  for (const bool noise : {false, true}) {
    HfoEnv env(goalie_config(noise));
    std::vector<float> obs(66);
    std::array<float, param::kCount> params{};
    env.reset(3, obs);  // seeds the noise stream
    env.set_state(agent_at({30.0, 10.0}), BallState{{42.5, 0.0}, {1.0, 0.0}}, obs);
    StepResult r;
    int steps = 0;
    do {
      r = env.step(no_op(params), obs);
      ++steps;
    } while (!r.terminal() && steps < 100);
    EXPECT_EQ(r.status, kCapturedByDefense) << "noise " << noise;
    EXPECT_EQ(r.reward, 0.0F);
    EXPECT_LE(steps, 15);
  }
}

// Reference §3.3 for a hand-placed state: agent at (40, 0) facing +x at rest, goalie at
// (50, 5) facing -x moving (0.3, 0.4).
TEST(HfoGoalie, OpponentFeaturesOfHandPlacedState) {
  SoccerSim sim(goalie_config(), 1);
  sim.set_state(agent_at({40.0, 0.0}), BallState{{45.0, 0.0}, {0.0, 0.0}});
  PlayerState& g = sim.mutable_state().players[kGoalieIndex];
  g.pos = {50.0, 5.0};
  g.body_deg = 180.0;
  g.vel = {0.3, 0.4};
  std::vector<float> f(static_cast<size_t>(feature_count(2)));
  ASSERT_EQ(f.size(), 66U);
  write_features(sim.state(), f);
  const double d = std::sqrt(125.0);
  const double R = std::sqrt(52.5 * 52.5 + 34.0 * 34.0);
  constexpr double kTol = 1e-6;
  EXPECT_NEAR(f[58], 5.0 / d, kTol);                 // sin of the bearing (to the right)
  EXPECT_NEAR(f[59], 10.0 / d, kTol);                // cos
  EXPECT_NEAR(f[60], 1.0 - 2.0 * d / R, kTol);       // proximity, 0.642509
  EXPECT_NEAR(f[61], 0.0, kTol);                     // sin of its body angle 180
  EXPECT_NEAR(f[62], -1.0, kTol);                    // cos
  EXPECT_NEAR(f[63], 2.0 * 0.5 / 0.75 - 1.0, kTol);  // speed 0.5 with max 0.75
  EXPECT_NEAR(f[64], 0.8, kTol);                     // sin of its velocity direction
  EXPECT_NEAR(f[65], 0.6, kTol);                     // cos
  for (float v : f) {
    EXPECT_LE(std::fabs(v), 1.0F);
  }
  // The agent's own 58 features do not depend on the goalie.
  SoccerSim alone({.noise = false}, 1);
  alone.set_state(agent_at({40.0, 0.0}), BallState{{45.0, 0.0}, {0.0, 0.0}});
  std::vector<float> f58(kNumAgentFeatures);
  write_features(alone.state(), f58);
  for (int i = 0; i < kNumAgentFeatures; ++i) {
    EXPECT_EQ(f[static_cast<size_t>(i)], f58[static_cast<size_t>(i)]) << "feature " << i;
  }
  // Only players with x > 0 count (§3.3): a goalie behind the halfway line is a zero block.
  g.pos = {-1.0, 0.0};
  write_features(sim.state(), f);
  for (int i = 58; i < 66; ++i) {
    EXPECT_EQ(f[static_cast<size_t>(i)], 0.0F) << "feature " << i;
  }
}

// Same seed, same episodes, bit for bit (the goalie draws nothing, its movement noise comes
// from the env's stream).
TEST(HfoGoalie, DeterministicWithSeed) {
  const auto play = [](uint64_t seed) {
    HfoEnv env(goalie_config(true));
    ScriptedOffense policy;
    std::vector<float> obs(66);
    std::vector<uint32_t> trace;
    for (int ep = 0; ep < 10; ++ep) {
      if (ep == 0) {
        env.reset(seed, obs);
      } else {
        env.reset(obs);
      }
      StepResult r;
      do {
        r = env.step(policy.act(obs), obs);
        for (float v : obs) {
          trace.push_back(std::bit_cast<uint32_t>(v));
        }
        trace.push_back(static_cast<uint32_t>(r.status));
        trace.push_back(std::bit_cast<uint32_t>(r.reward));
      } while (!r.terminal());
    }
    return trace;
  };
  const auto a = play(11);
  EXPECT_EQ(a, play(11));
  EXPECT_NE(a, play(12));
}

// The scripted offense against the goalie scores clearly less than on the empty goal, as
// Against agent2d's goalie the scripted offense is mostly stopped, as it is on the real server
// (.191 there, best course, 1,000 episodes; .209 here with the server's starts, docs/simulator.md),
// while it scores on the empty goal. 300 episodes here measure .147 (standard error about .02),
// so the bounds (.08 to .35, a drop of at least .5, captured in at least half the episodes)
// leave 3 standard errors and more. The seed is fixed, so the test is deterministic anyway.
TEST(HfoGoalie, ScriptedOffenseIsMostlyStoppedByTheGoalie) {
  constexpr int kEpisodes = 300;
  constexpr uint64_t kSeed = 20160101;
  SoccerSimConfig empty;
  empty.noise = true;
  HfoEnv env_empty(empty);
  HfoEnv env_goalie(goalie_config(true));
  ScriptedOffense policy;
  const EvalResult r_empty = evaluate(env_empty, policy, kEpisodes, kSeed);
  const EvalResult r_goalie = evaluate(env_goalie, policy, kEpisodes, kSeed);
  EXPECT_GE(r_empty.goal_rate, 0.95) << to_json(r_empty);
  EXPECT_LE(r_goalie.goal_rate, r_empty.goal_rate - 0.5) << to_json(r_goalie);
  EXPECT_GE(r_goalie.goal_rate, 0.08) << to_json(r_goalie);
  EXPECT_LE(r_goalie.goal_rate, 0.35) << to_json(r_goalie);
  EXPECT_GE(r_goalie.outcomes.at("CAPTURED_BY_DEFENSE"), kEpisodes / 2) << to_json(r_goalie);
}

// Where the scripted offense's goals cross the goal line (y, m; the bottom post is at +7) over
// `episodes` episodes against the goalie.
std::vector<double> goal_crossings(ShotAim aim, int episodes) {
  HfoEnv env(goalie_config(true));
  ScriptedOffense policy(aim);
  std::vector<float> obs(66);
  std::vector<double> ys;
  env.reset(7, obs);
  for (int ep = 0; ep < episodes; ++ep) {
    if (ep > 0) {
      env.reset(obs);
    }
    StepResult r;
    do {
      r = env.step(policy.act(obs), obs);
    } while (!r.terminal());
    if (r.status == env.success_status()) {
      ys.push_back(env.sim().state().ball.pos.y);
    }
  }
  return ys;
}

// ShotAim::kBottomPost shoots inside the bottom post, so its goals go in on the bottom half of
// the mouth; the best course goes in on both sides (the corner away from the keeper). A goal
// from a ball dribbled in, or a shot bent by the kick noise, can land elsewhere, hence 90 %.
// Against agent2d's goalie goals are rarer, so 400 episodes give the 25 goals each needs.
TEST(HfoGoalie, BottomPostAimScoresOnTheBottomHalf) {
  const auto share_bottom = [](const std::vector<double>& ys, double y0) {
    return static_cast<double>(std::count_if(ys.begin(), ys.end(), [y0](double y) { return y > y0; })) /
           static_cast<double>(ys.size());
  };
  const std::vector<double> post = goal_crossings(ShotAim::kBottomPost, 400);
  const std::vector<double> best = goal_crossings(ShotAim::kBestCourse, 400);
  ASSERT_GE(post.size(), 25U);
  ASSERT_GE(best.size(), 25U);
  EXPECT_GE(share_bottom(post, 2.0), 0.9);
  EXPECT_LE(share_bottom(best, 2.0), 0.8);
  EXPECT_GE(share_bottom(best, 2.0), 0.2);
  // kBottomSide shoots as kBottomPost does, so its goals go in on the same side.
  const std::vector<double> side = goal_crossings(ShotAim::kBottomSide, 400);
  ASSERT_GE(side.size(), 25U);
  EXPECT_GE(share_bottom(side, 2.0), 0.9);
}

// The scripted offense with `aim` against agent2d's goalie, on the same 1,000 of the server's
// starts (seed 1).
EvalResult rate_against_agent2d(ShotAim aim) {
  SoccerSimConfig c = goalie_config(true);
  c.start = StartDistribution::kHfo;
  HfoEnv env(c);
  ScriptedOffense policy(aim);
  return evaluate(env, policy, 1000, 1);
}

// The shot aims rank against agent2d's goalie as on the real server, where the best course
// scores .191 and bottom-side .130 (1,000 episodes each, docs/simulator.md): here, on the
// server's starts, .209 and .145 on these 1,000 starts (sampling noise about ±.012), so the best
// course leads by 3 points at least. (Bottom-side led against the hand-tuned keeper it replaced.)
TEST(HfoGoalie, BestCourseScoresMoreThanBottomSideAsOnTheRealServer) {
  const EvalResult best = rate_against_agent2d(ShotAim::kBestCourse);
  const EvalResult side = rate_against_agent2d(ShotAim::kBottomSide);
  EXPECT_GE(best.goal_rate, side.goal_rate + 0.03) << to_json(best) << " against " << to_json(side);
  EXPECT_LE(best.goal_rate, 0.30) << to_json(best);
}

// The close-in offense, tuned against agent2d's goalie: .997 (best course) and .96 (bottom post)
// on 4,000 of the server's starts, and .995 on the real server (docs/results.md, "A teacher for
// agent2d's goalie"). The others stay at .13-.25 against it (the test above). On these 1,000
// starts the sampling noise is about ±.002 and ±.006, so a regression of a few points fails.
TEST(HfoGoalie, CloseInScoresAgainstAgent2dsGoalie) {
  const EvalResult in = rate_against_agent2d(ShotAim::kCloseIn);
  const EvalResult post = rate_against_agent2d(ShotAim::kCloseInPost);
  EXPECT_GE(in.goal_rate, 0.98) << to_json(in);
  EXPECT_GE(post.goal_rate, 0.93) << to_json(post);
  // The slow dribble takes its time: about 156 steps to a goal against the others' ~80.
  EXPECT_GE(in.avg_steps_to_goal, 110.0) << to_json(in);
}

// env.shoot_action adds SHOOT, a kick with parameters of its own (hfo_env.hpp). The close-in
// offense then shoots with SHOOT and dribbles with KICK, and the game is the same step for step:
// two envs on the same starts, one with SHOOT and one without, see the same features after every
// action, the SHOOT of the one being the other's full-power KICK.
TEST(HfoGoalie, ShootActionIsTheSameKickUnderItsOwnName) {
  SoccerSimConfig c = goalie_config(true);
  c.start = StartDistribution::kHfo;
  HfoEnv with(c, true);
  HfoEnv without(c);
  ASSERT_EQ(without.action_space().num_actions(), 4);
  ASSERT_EQ(with.action_space().num_actions(), 5);
  ASSERT_EQ(with.action_space().num_params(), param::kCountWithShoot);
  EXPECT_EQ(with.action_space().actions[kShoot].name, "SHOOT");
  EXPECT_EQ(with.action_space().params[param::kShootPower].name, "shoot_power");
  EXPECT_EQ(with.action_space().find_action("KICK"), kKick);
  ScriptedOffense shooter(ShotAim::kCloseIn, true);
  ScriptedOffense kicker(ShotAim::kCloseIn);
  std::vector<float> a(static_cast<size_t>(with.observation_size()));
  std::vector<float> b(a.size());
  int shots = 0;
  int goals = 0;
  int soft_kicks = 0;
  for (uint64_t episode = 0; episode < 40; ++episode) {
    with.reset(100 + episode, a);
    without.reset(100 + episode, b);
    for (int step = 0; step < 500; ++step) {
      ASSERT_EQ(a, b) << "episode " << episode << " step " << step;
      const ParamAction s = shooter.act(a);
      const ParamAction k = kicker.act(b);
      ASSERT_EQ(s.params.size(), 8U);
      ASSERT_EQ(k.params.size(), 6U);
      if (s.id == kShoot) {
        ASSERT_EQ(k.id, kKick);
        EXPECT_EQ(s.params[param::kShootPower], 100.0F);
        EXPECT_EQ(s.params[param::kShootPower], k.params[param::kKickPower]);
        EXPECT_EQ(s.params[param::kShootDir], k.params[param::kKickDir]);
        ++shots;
      } else {
        ASSERT_EQ(s.id, k.id);
        if (s.id == kKick) {
          EXPECT_LT(s.params[param::kKickPower], 100.0F);  // a dribbling touch
          ++soft_kicks;
        }
      }
      const StepResult rs = with.step(s, a);
      const StepResult rk = without.step(k, b);
      ASSERT_EQ(rs.status, rk.status);
      ASSERT_EQ(rs.reward, rk.reward);
      if (rs.status != kInGame) {
        goals += rs.status == kGoal ? 1 : 0;
        break;
      }
    }
  }
  EXPECT_GE(goals, 36);  // .993 on 1,000 starts
  EXPECT_GE(shots, goals);
  EXPECT_GE(soft_kicks, 40 * 20);
}

}  // namespace
}  // namespace pamdp::hfo
