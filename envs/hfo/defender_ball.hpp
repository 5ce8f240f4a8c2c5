// A field defender with the ball, and the intentions it queues (issue 83): the parts of
// decide_defender (defender.hpp) that kick. Internal to the embedded simulator.
#pragma once

#include "envs/hfo/defender.hpp"

namespace pamdp::hfo::defender_ball {

// SamplePlayer::doForceKick: with the ball kickable by itself and an opponent alike, the fastest
// one-step kick toward the goal it attacks (Body_KickOneStep).
agent2d::Command force_kick(const agent2d::GoalieWorld& w);

// RoleCenterBack::doKick -> Bhv_ChainAction, with the ball kickable: doTurnToForward's turn or
// keep kick, else the best self-pass, else the hold. Sets d's rule, command, target and intention.
void chain_action(const agent2d::GoalieWorld& w, int cycle, DefenderDecision* d);

// PlayerAgent::doIntention: the intention queued on an earlier cycle plays this cycle (true, d
// set) or has ended or breaks off (false).
bool play_intention(const agent2d::GoalieWorld& w, int cycle, const PlayerState::Intention& intention,
                    DefenderDecision* d);

}  // namespace pamdp::hfo::defender_ball
