// Reading states and action scripts for `pamdp sim trace` and tests.
//
// STATE.json: {"agent": {"x", "y", "vx", "vy", "body_deg", "stamina"}, "ball": {"x", "y", "vx", "vy"},
//              "goalie": {"x", "y", "vx", "vy", "body_deg", "stamina", "since_catch", "tackle_cycles",
//                         "caught"}}
// (velocities are the observed, post-decay ones; stamina defaults to 8000, velocities to 0).
// "goalie" is optional; each of its keys missing takes its value at a reset (52.5, 0, at rest,
// body 180, stamina 8000, no catch yet, not frozen); since_catch counts the cycles since its last
// catch command, tackle_cycles the cycles its own tackle still freezes it (0-10), and caught says
// it caught the ball earlier in the episode (it then only keeps its position until the reset).
// ACTIONS.csv: one action per row: DASH,power,dir | TURN,dir | TACKLE,dir | KICK,power,dir;
// blank lines and lines starting with '#' are skipped.
// Both throw std::runtime_error naming the file, line and problem.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

struct InitialState {
  PlayerState agent;
  BallState ball;
  bool has_goalie = false;
  PlayerState goalie;  // when has_goalie
};

InitialState parse_state_json(const std::string& text, const std::string& source_name);
InitialState load_state_json(const std::string& path);

struct ScriptedAction {
  int id = 0;                     // hfo::ActionId
  std::array<float, 6> params{};  // the shared 6-parameter vector
};

std::vector<ScriptedAction> parse_actions_csv(const std::string& text, const std::string& source_name);
std::vector<ScriptedAction> load_actions_csv(const std::string& path);

}  // namespace pamdp::hfo
