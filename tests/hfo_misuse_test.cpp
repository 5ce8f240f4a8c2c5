// Misuse of HfoEnv stops the process with a message (also in Release); malformed action
// scripts are user errors and throw with the file and line.
#include <gtest/gtest.h>

#include <array>
#include <stdexcept>
#include <vector>

#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/state_io.hpp"

namespace pamdp::hfo {
namespace {

TEST(HfoEnvMisuseDeathTest, BadActionIdStops) {
  HfoEnv env;
  std::vector<float> obs(58);
  env.reset(1, obs);
  std::array<float, 6> p{};
  EXPECT_DEATH(env.step({7, p}, obs), "action id out of range");
}

TEST(HfoEnvMisuseDeathTest, ShortParameterVectorStops) {
  HfoEnv env;
  std::vector<float> obs(58);
  env.reset(1, obs);
  std::array<float, 2> p{};
  EXPECT_DEATH(env.step({kDash, p}, obs), "6 HFO parameters");
}

TEST(HfoEnvMisuseDeathTest, StepAfterTerminalStops) {
  SoccerSimConfig cfg;
  cfg.noise = false;
  HfoEnv env(cfg);
  std::vector<float> obs(58);
  env.reset(1, obs);
  PlayerState agent;
  agent.pos = {10, 0};
  env.set_state(agent, BallState{{60, 0}, {0, 0}}, obs);  // ball already out: OOB next cycle
  std::array<float, 6> p{};
  ASSERT_TRUE(env.step({kTurn, p}, obs).terminal());
  EXPECT_DEATH(env.step({kTurn, p}, obs), "call reset");
}

TEST(ActionsCsv, TrailingCommaAndIndentedCommentsAreHandled) {
  EXPECT_THROW(parse_actions_csv("DASH,100,0,\n", "a.csv"), std::runtime_error);
  const auto actions = parse_actions_csv("  # a comment\nTURN,30\n", "a.csv");
  ASSERT_EQ(actions.size(), 1U);
  EXPECT_EQ(actions[0].id, kTurn);
}

}  // namespace
}  // namespace pamdp::hfo
