// The hand-coded NPC goalie of the embedded simulator (1v1, SoccerSimConfig::goalie).
//
// decide_goalie() is a pure function of the state at the start of a cycle: it reads the exact
// positions and velocities (the goalie has full state, like the agent) and returns one body
// command, which SoccerSim then executes with the same client and server handling as the
// agent's commands (dash with 45-degree directions, stamina and effort, turn with inertia) or
// as the goalie's catch. It draws no random numbers and allocates nothing.
//
// What it does, in order:
//  1. catch: the ball is inside the penalty area, within the catchable length (1.2 m) and
//     the catch ban is over -> catch toward the ball;
//  2. intercept: it predicts the ball's path (no noise, decay 0.94) and finds the first cycle
//     at which it can be within reach of the ball (turn, if needed, then full dashes); it goes
//     there if the point is in its penalty area and either the ball is heading into the goal
//     or it gets there before the attacker can;
//  3. otherwise it guards: it stands between the ball and the goal, on the bisector of the
//     angle the goal mouth makes at the ball, 70% of the way out toward the ball (at least
//     1 m, at most 12 m from the goal line), and faces the ball.
// It never kicks: the referee already ends the episode once the goalie is within the
// kickable area of the ball (reference §5.2), so there is nothing left to clear.
#pragma once

#include <cstdint>

#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

struct GoalieCommand {
  enum class Kind : uint8_t { kNone, kDash, kTurn, kCatch };
  Kind kind = Kind::kNone;
  double power = 0.0;    // dash power
  double dir_deg = 0.0;  // dash, turn or catch direction, relative to the body
};

// The goalie's command for this cycle; `goalie` indexes state.players.
GoalieCommand decide_goalie(const SoccerState& state, int goalie);

}  // namespace pamdp::hfo
