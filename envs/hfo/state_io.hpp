// Reading states and action scripts for `pamdp sim trace` and tests.
//
// STATE.json: {"agent": {"x", "y", "vx", "vy", "body_deg", "stamina"}, "ball": {"x", "y", "vx", "vy"},
//              "teammates": [{"x", "y", "vx", "vy", "body_deg", "stamina"}, ...],
//              "goalie": {"x", "y", "vx", "vy", "body_deg", "stamina", "since_catch", "tackle_cycles",
//                         "caught"}}
// (velocities are the observed, post-decay ones; stamina defaults to 8000, velocities to 0).
// "teammates" is optional: the other learned offense players, players 1, 2, ... after the agent
// (player 0), at most kMaxOffenseAgents - 1 of them.
// "goalie" is optional; each of its keys missing takes its value at a reset (52.5, 0, at rest,
// body 180, stamina 8000, no catch yet, not frozen); since_catch counts the cycles since its last
// catch command, tackle_cycles the cycles its own tackle still freezes it (0-10), and caught says
// it caught the ball earlier in the episode (it then only keeps its position until the reset).
// "defenders" is optional (with "goalie" or --goalie): agent2d's field defenders, unums 2 and 3,
// at most 2: [{"x", "y", "vx", "vy", "body_deg", "stamina", "tackle_cycles", "recover_mode",
// "intention"}, ...]. Each key missing takes 0 (velocities, tackle_cycles), 180 (body_deg), 8000
// (stamina) or false (recover_mode, Strategy's recover mode); x and y are required. "intention"
// (optional; none by default) is the defender's memory, queued the cycle before:
// {"kind": "dribble", "x", "y", "turns", "dashes"} (its self-pass's turns and dashes left toward
// the receive point x, y) or {"kind": "turn_to_forward", "x", "y"} (the turn toward x, y after a
// keep kick).
// ACTIONS.csv: one action per row: DASH,power,dir | TURN,dir | TACKLE,dir | KICK,power,dir;
// blank lines and lines starting with '#' are skipped. With several offense players a row holds
// one action per player, in player order, separated by '|': DASH,80,0|KICK,60,-20.
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
  std::vector<PlayerState> teammates;  // offense players 1, 2, ...
  bool has_goalie = false;
  PlayerState goalie;                  // when has_goalie
  std::vector<PlayerState> defenders;  // agent2d's field defenders (unums 2, 3), with the goalie
};

InitialState parse_state_json(const std::string& text, const std::string& source_name);
InitialState load_state_json(const std::string& path);

struct ScriptedAction {
  int id = 0;                     // hfo::ActionId
  std::array<float, 6> params{};  // the shared 6-parameter vector
};

std::vector<ScriptedAction> parse_actions_csv(const std::string& text, const std::string& source_name);
std::vector<ScriptedAction> load_actions_csv(const std::string& path);

// Rows of `players` actions each (players >= 1; one player reads the one-action format).
using TeamActions = std::vector<ScriptedAction>;
std::vector<TeamActions> parse_team_actions_csv(const std::string& text, const std::string& source_name, int players);
std::vector<TeamActions> load_team_actions_csv(const std::string& path, int players);

}  // namespace pamdp::hfo
