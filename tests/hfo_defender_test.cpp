// agent2d's field defenders in the embedded game (env.defense_npcs, issue 83): the settings,
// the starts HFO draws for them, their opponent blocks, STATE.json's "defenders", and a game
// that runs to its end. Their decisions against the real server's: hfo_defender_real_data_test.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
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

}  // namespace
}  // namespace pamdp::hfo
