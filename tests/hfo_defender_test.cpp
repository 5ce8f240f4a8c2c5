// agent2d's field defenders in the embedded game (env.defense_npcs, issue 83): the settings,
// the starts HFO draws for them, their opponent blocks, STATE.json's "defenders", and a game
// that runs to its end. Their decisions against the real server's: hfo_defender_real_data_test.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "envs/hfo/defender.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/soccer_sim.hpp"
#include "envs/hfo/state_io.hpp"

namespace pamdp::hfo {
namespace {

TEST(Defenders, DefenseNpcsCountsTheGoalieFirst) {
  for (int k = 0; k <= 3; ++k) {
    const app::ExperimentConfig c =
        app::parse_experiment_config("[env]\nname = \"hfo\"\ndefense_npcs = " + std::to_string(k) + "\n", "test", {});
    const SoccerSimConfig s = sim_config(c.env.params);
    EXPECT_EQ(s.goalie, k >= 1) << k;
    EXPECT_EQ(s.field_defenders, std::max(0, k - 1)) << k;
    EXPECT_EQ(app::observation_size(c.env), feature_count(1 + k)) << k;  // 58 + 8 per defense player
    EXPECT_EQ(defense_players(c.env.params), k);
  }
  // env.goalie alone stays the goalie.
  const app::ExperimentConfig g = app::parse_experiment_config("[env]\nname = \"hfo\"\ngoalie = true\n", "test", {});
  EXPECT_EQ(defense_players(g.env.params), 1);
  EXPECT_EQ(sim_config(g.env.params).field_defenders, 0);
  EXPECT_THROW((void)app::parse_experiment_config("[env]\nname = \"hfo\"\ndefense_npcs = 4\n", "test", {}),
               std::runtime_error);
  SoccerSimConfig bad;
  bad.field_defenders = 1;  // without the goalie
  EXPECT_THROW(SoccerSim(bad, 1), std::invalid_argument);
}

TEST(Defenders, ResetsPlaceThemWhereHfoDoes) {
  SoccerSimConfig c;
  c.goalie = true;
  c.field_defenders = 2;
  SoccerSim sim(c, 7);
  double min_x = 100.0;
  double max_x = -100.0;
  double min_y = 100.0;
  double max_y = -100.0;
  for (int e = 0; e < 400; ++e) {
    sim.reset_episode();
    for (int k = 0; k < 2; ++k) {
      // Two cycles after the reset: the defenders have moved from their places by at most 2 m.
      const PlayerState& d = sim.state().players[static_cast<size_t>(sim.defender_index(k))];
      EXPECT_EQ(d.team, Team::kDefense);
      EXPECT_FALSE(d.goalie);
      min_x = std::min(min_x, d.pos.x);
      max_x = std::max(max_x, d.pos.x);
      min_y = std::min(min_y, d.pos.y);
      max_y = std::max(max_y, d.pos.y);
    }
  }
  EXPECT_GT(min_x, 42.0 - 2.0);
  EXPECT_LT(min_x, 43.0);
  EXPECT_GT(max_x, 51.0);
  EXPECT_LT(max_x, 52.5 + 2.0);
  EXPECT_LT(min_y, -25.0);
  EXPECT_GT(max_y, 25.0);
  EXPECT_EQ(sim.state().num_players, 4);
}

TEST(Defenders, AGameWithThemRunsToItsEnd) {
  const app::ExperimentConfig c =
      app::parse_experiment_config("[env]\nname = \"hfo\"\ndefense_npcs = 3\noffense_agents = 2\n", "test", {});
  auto env = app::make_env(c.env);
  ASSERT_EQ(env->agents(), 2);
  std::vector<float> obs(static_cast<size_t>(env->observation_size() * 2));
  std::vector<float> rewards(2);
  int captured = 0;
  for (int e = 0; e < 20; ++e) {
    env->reset(static_cast<uint64_t>(e), obs);
    std::vector<ParamAction> idle(2, ParamAction{kDash, std::vector<float>(6, 0.0F)});
    StepResult r;
    for (int t = 0; t < 600 && !r.terminal(); ++t) {
      r = env->step_team(idle, obs, rewards);
    }
    ASSERT_TRUE(r.terminal());
    captured += r.status == kCapturedByDefense ? 1 : 0;
  }
  // Two attackers standing still: the defense comes for the ball and takes it.
  EXPECT_GE(captured, 15);
}

TEST(Defenders, StateJsonTakesThem) {
  const InitialState s = parse_state_json(
      R"({"agent": {"x": 30, "y": 0}, "ball": {"x": 31, "y": 0}, "goalie": {},
          "defenders": [{"x": 40, "y": -3, "tackle_cycles": 2}, {"x": 42, "y": 8, "body_deg": 90}]})",
      "s.json");
  ASSERT_EQ(s.defenders.size(), 2U);
  EXPECT_EQ(s.defenders[0].pos.x, 40.0);
  EXPECT_EQ(s.defenders[0].tackle_cycles, 2);
  EXPECT_EQ(s.defenders[0].body_deg, 180.0);
  EXPECT_EQ(s.defenders[1].body_deg, 90.0);
  try {
    (void)parse_state_json(R"({"agent": {"x": 30, "y": 0}, "ball": {"x": 31, "y": 0},
                               "defenders": [{"x": 40, "y": 0, "speed": 1}]})",
                           "s.json");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("speed"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)parse_state_json(R"({"agent": {"x": 30, "y": 0}, "ball": {"x": 31, "y": 0},
                                          "defenders": [{"x": 1, "y": 0}, {"x": 2, "y": 0}, {"x": 3, "y": 0}]})",
                                      "s.json"),
               std::runtime_error);
}

TEST(Defenders, StateJsonTakesTheirMemory) {
  const InitialState s = parse_state_json(
      R"({"agent": {"x": 10, "y": 0}, "ball": {"x": 30, "y": 0}, "goalie": {},
          "defenders": [{"x": 31, "y": 0, "intention": {"kind": "dribble", "x": 22, "y": 1, "turns": 1, "dashes": 6}},
                        {"x": 42, "y": 8, "recover_mode": true,
                         "intention": {"kind": "turn_to_forward", "x": -42, "y": 4}}]})",
      "s.json");
  ASSERT_EQ(s.defenders.size(), 2U);
  const PlayerState::Intention& a = s.defenders[0].intention;
  EXPECT_EQ(a.kind, PlayerState::Intention::Kind::kDribble);
  EXPECT_EQ(a.target.x, 22.0);
  EXPECT_EQ(a.turns, 1);
  EXPECT_EQ(a.dashes, 6);
  EXPECT_EQ(a.last_cycle, -1);  // queued the cycle before the state's cycle 0
  EXPECT_EQ(s.defenders[1].intention.kind, PlayerState::Intention::Kind::kTurnToForward);
  EXPECT_FALSE(s.defenders[0].recover_mode);
  EXPECT_TRUE(s.defenders[1].recover_mode);
  for (const char* bad : {R"({"kind": "shoot", "x": 1, "y": 0})", R"({"kind": "dribble", "x": 1, "y": 0, "turns": -1})",
                          R"({"kind": "dribble", "y": 0})"}) {
    try {
      (void)parse_state_json(std::string(R"({"agent": {"x": 10, "y": 0}, "ball": {"x": 30, "y": 0}, "goalie": {},
                                             "defenders": [{"x": 31, "y": 0, "intention": )") +
                                 bad + "}]}",
                             "s.json");
      FAIL() << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("defenders[0].intention"), std::string::npos) << e.what();
    }
  }
}

// A game state by hand: one attacker far from play, the goalie at home, one field defender.
SoccerState defender_game(Vec2 defender, double defender_body, Vec2 ball, Vec2 ball_vel, Vec2 attacker) {
  SoccerState s;
  s.num_players = 3;
  s.players[0].pos = attacker;
  s.players[0].team = Team::kOffense;
  s.players[1].pos = {52.5, 0.0};
  s.players[1].body_deg = 180.0;
  s.players[1].team = Team::kDefense;
  s.players[1].goalie = true;
  s.players[2].pos = defender;
  s.players[2].body_deg = defender_body;
  s.players[2].team = Team::kDefense;
  s.ball.pos = ball;
  s.ball.vel = ball_vel;
  s.cycle = 40;
  return s;
}

TEST(Defenders, WithTheBallAndRoomAheadTheyDribbleOutOfTheirHalf) {
  // Facing the half-way line (body 180 in HFO's frame), the ball at its feet, the attacker far
  // behind it: the self-pass sends the ball toward x = 0 and queues the run after it.
  const SoccerState s = defender_game({30.0, 5.0}, 180.0, {29.4, 5.0}, {}, {45.0, -20.0});
  const DefenderDecision d = decide_defender(s, 2, 2, false);
  ASSERT_EQ(d.rule, DefenderDecision::Rule::kSelfPass);
  EXPECT_EQ(d.command.kind, agent2d::Command::Kind::kKick);
  EXPECT_GT(d.command.p1, 10.0);
  EXPECT_LT(d.target.x, 29.4 - 4.0);  // forward, toward the half-way line (6 dashes at most from x 29.4)
  EXPECT_EQ(d.intention.kind, PlayerState::Intention::Kind::kDribble);
  EXPECT_EQ(d.intention.target.x, d.target.x);
  EXPECT_EQ(d.intention.last_cycle, s.cycle);
  EXPECT_GE(d.intention.dashes, 5);
}

TEST(Defenders, TheQueuedDribblePlaysOnlyTheCycleAfter) {
  // The ball rolling ahead after the kick, the queue of dashes toward its receive point.
  SoccerState s = defender_game({30.0, 5.0}, 180.0, {28.6, 5.0}, {-0.8, 0.0}, {45.0, -20.0});
  s.players[2].intention = {PlayerState::Intention::Kind::kDribble, {22.0, 5.0}, 0, 6, s.cycle - 1};
  const DefenderDecision d = decide_defender(s, 2, 2, false);
  ASSERT_EQ(d.rule, DefenderDecision::Rule::kDribbleQueue);
  EXPECT_EQ(d.command.kind, agent2d::Command::Kind::kDash);
  EXPECT_NEAR(d.command.p1, 100.0, 1e-9);
  EXPECT_EQ(d.intention.dashes, 5);
  EXPECT_EQ(d.intention.last_cycle, s.cycle);
  // Not played the cycle before (IntentionNormalDribble::finished): the defender decides afresh.
  s.players[2].intention.last_cycle = s.cycle - 2;
  EXPECT_NE(decide_defender(s, 2, 2, false).rule, DefenderDecision::Rule::kDribbleQueue);
  // An attacker at the ball breaks it off (checkOpponent).
  s.players[2].intention.last_cycle = s.cycle - 1;
  s.players[0].pos = {28.0, 5.6};
  EXPECT_NE(decide_defender(s, 2, 2, false).rule, DefenderDecision::Rule::kDribbleQueue);
}

TEST(Defenders, FacingTheirOwnGoalWithTheBallTheyTurnAround) {
  // Body 0 faces the defense's own goal; the ball at its feet stays there: turn first
  // (Bhv_ChainAction::doTurnToForward), with no opponent within 4 m.
  const SoccerState s = defender_game({30.0, 6.0}, 0.0, {30.5, 6.0}, {}, {45.0, -20.0});
  const DefenderDecision d = decide_defender(s, 2, 2, false);
  ASSERT_EQ(d.rule, DefenderDecision::Rule::kTurnForward);
  EXPECT_EQ(d.command.kind, agent2d::Command::Kind::kTurn);
  EXPECT_NEAR(d.target.x, -42.0, 1e-9);  // (42, y / 2) in its own frame
  EXPECT_NEAR(d.target.y, 3.0, 1e-9);
  // An attacker within 4 m: no turn; the chain action plays instead.
  SoccerState near = s;
  near.players[0].pos = {33.0, 6.0};
  EXPECT_NE(decide_defender(near, 2, 2, false).rule, DefenderDecision::Rule::kTurnForward);
}

TEST(Defenders, TheRecoverModeHoldsBetweenHalfAndSevenTenthsOfTheirStamina) {
  // An attacker with the ball 15 m out; the defender moves to its home position
  // (Strategy::get_normal_dash_power): 76.5 normally, its recovery less 25 while recovering.
  SoccerState s = defender_game({30.0, 12.0}, 180.0, {20.5, 0.0}, {}, {20.0, 0.0});
  s.players[2].stamina = 5000.0;  // between half and 0.7 of 8000: the mode stays as it was
  // Facing its home position, so that it dashes.
  const Vec2 home = decide_defender(s, 2, 2, false).target;
  s.players[2].body_deg = std::atan2(home.y - 12.0, home.x - 30.0) * kRadToDeg;
  const DefenderDecision normal = decide_defender(s, 2, 2, false);
  s.players[2].recover_mode = true;
  const DefenderDecision recovering = decide_defender(s, 2, 2, false);
  ASSERT_EQ(normal.rule, DefenderDecision::Rule::kBasicMove);
  ASSERT_EQ(recovering.rule, DefenderDecision::Rule::kBasicMove);
  EXPECT_FALSE(normal.recover_mode);
  EXPECT_TRUE(recovering.recover_mode);
  ASSERT_EQ(normal.command.kind, agent2d::Command::Kind::kDash);
  EXPECT_NEAR(normal.command.p1, 76.5, 1e-9);
  EXPECT_NEAR(recovering.command.p1, 45.0 - 25.0, 1e-9);
  s.players[2].recover_mode = false;
  s.players[2].stamina = 3900.0;  // under half: on
  EXPECT_TRUE(decide_defender(s, 2, 2, false).recover_mode);
  s.players[2].recover_mode = true;
  s.players[2].stamina = 5700.0;  // over 0.7 of 8000 (5,600): off
  EXPECT_FALSE(decide_defender(s, 2, 2, false).recover_mode);
}

}  // namespace
}  // namespace pamdp::hfo
