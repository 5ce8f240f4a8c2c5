// HFO's field defenders in the embedded simulator (issue 83): agent2d's CenterBack,
// the role of unums 2 and 3 that HFO runs for --defense-npcs 2 and 3 (HFO b8b2a1d
// src/role_center_back.cpp, bhv_basic_move.cpp, bhv_basic_tackle.cpp, strategy.cpp on librcsc
// d222758), re-implemented from its rules on the goalie's world model and librcsc actions
// (goalie_world.hpp; the intercept with SelfView::goalie false). What it does with the ball is in
// defender_ball.hpp.
//
// decide_defender() is a pure function of the state at the start of a cycle (the defender's
// memory included: it returns the memory after the decision); the simulator
// plays it for env.defense_npcs >= 2, and it is checked one recorded cycle at a time against the
// real server's defenders (tests/hfo_defender_real_data_test.cpp). What it does each cycle:
//  - frozen by its own tackle: no body command;
//  - the ball kickable by itself and an opponent alike: SamplePlayer::doForceKick, the fastest
//    one-step kick toward the goal it attacks (Body_KickOneStep);
//  - the ball kickable (no teammate nearer to it): RoleCenterBack::doKick, the chain action. Its
//    self-pass (SelfPassGenerator scored by SampleFieldEvaluator, and Bhv_NormalDribble's first
//    kick) is modelled; where no self-pass beats the present state, the hold, whose kick is sent
//    with power 0 (HFO ends the episode as captured about 2 cycles later). The pass and the
//    short dribble (5 % of the recorded chain actions) are not modelled;
//    Before the chain action, Bhv_ChainAction::doTurnToForward: facing its own goal with no
//    opponent within 4 m, it turns toward the other goal, or, when the ball would leave its
//    feet, kicks it to a keep point and turns the next cycle;
//  - before all of these (SamplePlayer::doPreprocess -> doIntention), the intention queued by
//    an earlier cycle (PlayerState::Intention): the self-pass's turns and dashes toward its
//    receive point (IntentionNormalDribble) or the turn after a keep kick (IntentionTurnTo);
//  - otherwise Bhv_BasicMove: a tackle or foul tackle (Bhv_BasicTackle(0.8, 80), TackleGenerator's
//    direction), or intercept (Body_Intercept2009) when its own reach is at most 3 cycles or at
//    most its field teammates' and under the opponents' + 3, or go to its home position
//    (agent2d_formation.hpp) with Body_GoToPoint at Strategy::get_normal_dash_power, or turn to
//    the ball when there.
// Its world model is the truth (both teams get full state), with librcsc's one correction: the
// ball's velocity is believed 0 while an opponent can kick it and the defender cannot
// (WorldModel::updateJustBeforeDecision -> BallObject::setOpponentControlEffect). Its memory
// lives in PlayerState: the queued intention and Strategy's recover mode. Not modelled: the
// smoothing WorldModel::updateOurDefenseLine applies to a defense line moving up by 5-13 m in a
// cycle, and the chain action's pass and short dribble. What the defenders tell each other
// changes none of these decisions with full state (docs/simulator.md).
#pragma once

#include "envs/hfo/goalie_world.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

// What a defender decided, with the .dcl's vocabulary for checking (BasicMove target point).
struct DefenderDecision {
  enum class Rule : uint8_t { kFrozen, kKick, kSelfPass, kDribbleQueue, kTurnForward, kTackle, kIntercept, kBasicMove };
  Rule rule = Rule::kBasicMove;
  agent2d::Command command;
  bool foul = false;                 // a foul tackle ((tackle DIR on))
  Vec2 target;                       // kBasicMove: the home position; kSelfPass: the receive point (global frame)
  PlayerState::Intention intention;  // the defender's memory after this decision:
  bool recover_mode = false;         // and Strategy's recover mode
};

// The defender's world model, mirrored into its own frame (goalie_world.hpp): its teammates are
// the other defense players (the goalie flagged), its opponents the offense.
agent2d::GoalieWorld defender_world(const SoccerState& state, int defender, bool server_noise);

// The defender's decision this cycle; `defender` indexes state.players, `unum` is its uniform
// number (2 or 3: its place in agent2d's formation).
DefenderDecision decide_defender(const SoccerState& state, int defender, int unum, bool server_noise);

}  // namespace pamdp::hfo
