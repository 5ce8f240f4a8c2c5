// HFO's goalie in the embedded simulator: agent2d's keeper (HFO b8b2a1d `src/role_goalie.cpp`,
// `bhv_goalie_basic_move.cpp`, `bhv_goalie_chase_ball.cpp`, `bhv_basic_tackle.cpp`) on
// librcsc d222758, re-implemented from its rules (goalie_world.hpp has the world model and
// the librcsc actions). It is checked one cycle at a time against the real server's goalie
// (tests/hfo_goalie_real_data_test.cpp, docs/simulator.md).
//
// decide_goalie() is a pure function of the state at the start of a cycle plus the memory the
// real goalie keeps, which lives in the state (PlayerState::since_catch, and PlayerState::caught
// for the play mode it believes in after a catch). It returns the
// command the goalie's client sends to the server, in the server's units (dash power and
// direction after librcsc's client adjustments, turn moment, catch direction relative to the
// body), which SoccerSim then executes with the server's handling. It draws no random numbers
// and allocates nothing.
//
// What it does each cycle (role_goalie.cpp, RoleGoalie::execute):
//  1. catch, when the catch ban is over (more than catch_ban_cycle = 5 cycles since its last
//     catch), the ball is within catchableArea - 0.05 = 1.25 m and inside its penalty area
//     shrunk by 1 m at the sides and the front;
//  2. otherwise, when the ball is kickable (never in HFO play: the referee ends the episode
//     first), a clearing kick;
//  3. otherwise it chases the ball when Bhv_GoalieChaseBall::is_ball_chase_situation says so
//     (intercepting with Body_Intercept2009 or going to the point where the ball's path
//     crosses its line), and else it keeps its basic position (Bhv_GoalieBasicMove: on the
//     line from the ball to a point 7 m behind the goal centre, at x = 2.7 m in front of the
//     goal line, turning to face across the goal when there).
// While frozen by its own tackle it sends no body command. After a successful catch it hears
// the referee's goalie_catch_ball_r and, the ball flying on in HFO mode, keeps that play mode
// to the end of the episode: then it only keeps its basic position (Bhv_GoalieFreeKick ->
// Bhv_GoalieBasicMove, going with Body_GoToPoint instead of Bhv_GoToPointLookBall).
#pragma once

#include "envs/hfo/goalie_world.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

using GoalieCommand = agent2d::Command;

// The goalie's world model, mirrored into its own frame (goalie_world.hpp). `server_noise`
// says whether the server runs with its noise parameters (SoccerSimConfig::noise) or with
// them at 0, which the goalie reads from the server as the real one does.
agent2d::GoalieWorld goalie_world(const SoccerState& state, int goalie, bool server_noise);

// The world model of defense player `self` (the goalie or a field defender) as librcsc builds it
// from full state, mirrored into its frame: itself, the ball, its teammates and its opponents,
// each group nearest to the ball first. goalie_world adds the goalie's catch memory.
agent2d::GoalieWorld defense_world(const SoccerState& state, int self, bool server_noise);

// The goalie's command for this cycle; `goalie` indexes state.players.
GoalieCommand decide_goalie(const SoccerState& state, int goalie, bool server_noise);

// SelfObject::tackleProbability (foul false) or foulProbability (foul true): the server's
// tackle failure with tackle_exponent 6 or foul_exponent 10 (rcssserver serverparam.cpp).
// Shared with the field defenders (defender.hpp).
double tackle_success_probability(const agent2d::GoalieWorld& w, bool foul);

// TackleGenerator::bestResult's tackle angle (global, in the player's frame; HFO
// src/chain_action/tackle_generator.cpp). Shared with the field defenders.
double tackle_generator_angle(const agent2d::GoalieWorld& w);

// The command's name as the server's log writes it (DASH, TURN, CATCH, KICK, TACKLE, NONE).
const char* goalie_command_name(GoalieCommand::Kind kind);

}  // namespace pamdp::hfo
