// The project's HFO action (DASH, TURN, TACKLE, KICK with the 6 shared parameters) as the
// arguments of HFO's low-level commands, kept within what the server accepts, and a count of
// every parameter that was not. Built in every build (no HFO needed), so it is tested everywhere.
//
// Ranges (rcssserver serverparam.cpp and player.cpp; librcsc action_effector.cpp, which HFO's
// client calls for act(KICK/DASH/TURN/TACKLE)):
//  - kick power [0, 100]: the server bounds it to [minpower, maxpower] = [-100, 100]
//    (NormalizeKickPower in Player::kick) and librcsc's setKick has already clipped it to
//    [0, maxpower], printing "kick power is over max. com=..." or "negative kick power ...";
//  - dash power [-100, 100]: min/max_dash_power (NormalizeDashPower; librcsc setDash likewise);
//  - every direction (dash, turn, tackle, kick) (-180, 180]: librcsc normalizes an angle by
//    wrapping it (AngleDeg, normalize_angle), the server bounds it to min/maxmoment = ±180.
// These are the same conversions the embedded simulator applies in SoccerSim::kick_player,
// dash_player, turn_player and tackle_player, so a parameter outside its range means the same
// thing on both; doing it here only makes the client's clipping explicit and counted.
#pragma once

#include <cstdint>

#include "core/action_space.hpp"

namespace pamdp::hfo_server {

// Parameters that arrived outside the server's range, over an env's lifetime.
struct ActionClampCounts {
  int64_t kick_power = 0;  // > 100 or < 0, clipped
  int64_t dash_power = 0;  // outside [-100, 100], clipped
  int64_t direction = 0;   // outside [-180, 180], wrapped
  [[nodiscard]] int64_t total() const { return kick_power + dash_power + direction; }
};

// The arguments of one low-level command: `p1` is the power (DASH, KICK) or the direction
// (TURN, TACKLE); `p2` the direction of DASH and KICK (0 for the others).
struct ServerCommandArgs {
  double p1 = 0.0;
  double p2 = 0.0;
};

// The command arguments for `action` (ids and parameter layout of hfo::hfo_action_space()),
// within the ranges above; adds to `counts` for every parameter that was outside. SHOOT
// (env.shoot_action) gives a KICK's arguments from its own two parameters. The caller checks the
// id and that params holds the 6 parameters (8 with SHOOT). No allocation.
ServerCommandArgs server_command_args(const ParamAction& action, ActionClampCounts& counts);

}  // namespace pamdp::hfo_server
