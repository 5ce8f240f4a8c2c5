#include "envs/hfo/defender.hpp"

#include <algorithm>
#include <cmath>

#include "envs/hfo/agent2d_formation.hpp"
#include "envs/hfo/defender_ball.hpp"
#include "envs/hfo/goalie.hpp"

namespace pamdp::hfo {
namespace {

using agent2d::Command;
using agent2d::GoalieWorld;
using agent2d::InterceptTable;
using agent2d::mirror;

// Line through p along `deg`, met with the goal line: Ray2D::intersection in Bhv_BasicTackle.
bool ball_into_our_goal(const GoalieWorld& w, Vec2 self_reach_point) {
  if (self_reach_point.x >= -kPitchHalfLength || w.ball_vel.r2() <= 0.0) {
    return false;
  }
  if (w.ball_vel.x >= 0.0) {
    return false;  // the ray never reaches x = -52.5 ahead of the ball
  }
  const double t = (-kPitchHalfLength - w.ball_pos.x) / w.ball_vel.x;
  const double y = w.ball_pos.y + w.ball_vel.y * t;
  return std::fabs(y) < kGoalHalfWidth + 1.0;
}

// Bhv_BasicTackle(0.8, 80)::execute with its version-14 foul option.
bool basic_tackle(const GoalieWorld& w, const InterceptTable& t, DefenderDecision* d) {
  double prob = tackle_success_probability(w, false);
  bool foul = false;
  const double foul_prob = tackle_success_probability(w, true);
  if ((w.ball_pos.x > agent2d::kOurPenaltyLineX + 0.5 || std::fabs(w.ball_pos.y) > kPenaltyBoxHalfWidth + 0.5) &&
      prob < foul_prob) {
    prob = foul_prob;
    foul = true;
  }
  if (prob < 0.8) {
    return false;
  }
  const int self_min = t.self_reach_cycle;
  const int mate_min = t.teammate_reach_cycle;
  const int opp_min = t.opponent_reach_cycle;
  const Vec2 their_goal{kPitchHalfLength, 0.0};
  if (!(w.exist_kickable_opponent || ball_into_our_goal(w, agent2d::ball_inertia_point(w, self_min)) ||
        (opp_min < self_min - 3 && opp_min < mate_min - 3) ||
        (self_min >= 5 && (w.ball_pos - their_goal).r2() < 100.0 &&
         std::fabs(agent2d::angle_norm(agent2d::th_deg(their_goal - w.self.pos) - w.self.body_deg)) < 45.0))) {
    return false;
  }
  d->rule = DefenderDecision::Rule::kTackle;
  d->foul = foul;
  d->command = {Command::Kind::kTackle, agent2d::angle_norm(tackle_generator_angle(w) - w.self.body_deg), 0.0};
  return true;
}

// Strategy::get_normal_dash_power, with its memory: the recover mode, on below half the maximum
// stamina and off above 0.7 of it (static thread_local in agent2d: each defender its own).
double normal_dash_power(const GoalieWorld& w, const InterceptTable& t, bool* recover_mode) {
  const agent2d::StaminaModel stamina = agent2d::stamina_of(w.self);
  if (stamina.capacity_is_empty()) {
    return std::min(kMaxDashPower, w.self.stamina + kExtraStamina);
  }
  if (w.self.stamina < kStaminaMax * 0.5) {
    *recover_mode = true;
  } else if (w.self.stamina > kStaminaMax * 0.7) {
    *recover_mode = false;
  }
  const double my_inc = kStaminaIncMax * w.self.recovery;
  // WorldModel::ourDefenseLineX: the second-deepest of its side (itself included), 0 at most,
  // and the ball's x when the ball is deeper.
  double first = 0.0;
  double second = 0.0;
  const auto consider = [&](double x) {
    if (x < second) {
      second = x;
      if (second < first) {
        std::swap(first, second);
      }
    }
  };
  consider(w.self.pos.x);
  for (int i = 0; i < w.num_teammates; ++i) {
    consider(w.teammates[static_cast<size_t>(i)].pos.x);
  }
  const double defense_line = std::min(second, w.ball_pos.x);
  if (defense_line > w.self.pos.x && w.ball_pos.x < defense_line + 20.0) {
    return kMaxDashPower;
  }
  if (*recover_mode) {
    return std::max(0.0, my_inc - 25.0);
  }
  if (w.exist_kickable_teammate && w.ball_dist_from_self < 20.0) {
    return std::min(my_inc * 1.1, kMaxDashPower);
  }
  if (w.ball_pos.x > 25.0 && w.ball_pos.x > w.self.pos.x + 10.0 && t.self_reach_cycle < t.opponent_reach_cycle - 6 &&
      t.teammate_reach_cycle < t.opponent_reach_cycle - 6) {
    return std::clamp(my_inc * 0.5, kMaxDashPower * 0.1, kMaxDashPower);
  }
  return std::min(my_inc * 1.7, kMaxDashPower);
}

}  // namespace

GoalieWorld defender_world(const SoccerState& s, int defender, bool server_noise) {
  GoalieWorld w = defense_world(s, defender, server_noise);
  if (w.exist_kickable_opponent && !w.self_kickable) {
    w.ball_vel = {};  // BallObject::setOpponentControlEffect
  }
  return w;
}

DefenderDecision decide_defender(const SoccerState& s, int defender, int unum, bool server_noise) {
  const GoalieWorld w = defender_world(s, defender, server_noise);
  DefenderDecision d;
  d.recover_mode = s.players[static_cast<size_t>(defender)].recover_mode;
  if (w.self.frozen) {
    d.rule = DefenderDecision::Rule::kFrozen;
    return d;
  }
  if (defender_ball::play_intention(w, s.cycle, s.players[static_cast<size_t>(defender)].intention, &d)) {
    return d;
  }
  // SamplePlayer::doPreprocess checks the simultaneous kick before the role plays.
  if (w.self_kickable && w.exist_kickable_opponent) {
    d.rule = DefenderDecision::Rule::kKick;
    d.command = defender_ball::force_kick(w);
    return d;
  }
  // RoleCenterBack::execute: kickable unless a teammate with the ball kickable is nearer to it.
  bool kickable = w.self_kickable;
  if (w.exist_kickable_teammate && (w.teammates[0].pos - w.ball_pos).r() < w.ball_dist_from_self) {
    kickable = false;
  }
  if (kickable) {
    defender_ball::chain_action(w, s.cycle, &d);
    return d;
  }
  InterceptTable table;
  agent2d::predict_ball_and_opponents(w, &table);
  // Its own reach, librcsc's costliest prediction, is skipped while an opponent holds a ball
  // more than 6 m beyond its kickable area (believed at rest: 5 cycles at least, at 1.05 m a
  // cycle). Every rule below then reads it only through comparisons that come out the same for
  // any value of 5 or more: no tackle (the ball is out of reach), no intercept (at most 3, or
  // under opp_min + 3 = 3), ball_step 0, the situation from min(self, mates) >= 2 or the mates'
  // own, the dash power's "self_min < opp_min - 6". 1000 stands for it.
  if (!(w.exist_kickable_opponent && w.ball_dist_from_self > kKickableArea + 6.0)) {
    agent2d::predict_self(w, &table);
  }
  if (basic_tackle(w, table, &d)) {
    return d;
  }
  const int self_min = table.self_reach_cycle;
  const int mate_min = table.teammate_reach_cycle;
  const int opp_min = table.opponent_reach_cycle;
  if (!w.exist_kickable_teammate && (self_min <= 3 || (self_min <= mate_min && self_min < opp_min + 3))) {
    d.rule = DefenderDecision::Rule::kIntercept;
    agent2d::body_intercept(w, table, true, &d.command);
    return d;
  }
  // Strategy::updatePosition: the formation of the situation at the ball's inertia point after
  // the fewest reach cycles of anyone. The offside clamp (x <= offside line - 1) never binds in
  // HFO's half field: the attackers' "defense line" is at x >= 0 in the defenders' frame.
  const int ball_step = std::min({1000, mate_min, opp_min, self_min});
  const Vec2 focus = agent2d::ball_inertia_point(w, ball_step);
  const agent2d::FormationKind kind = agent2d::formation_for(std::min(self_min, mate_min), opp_min);
  const Vec2 target = agent2d::formation_position(agent2d::formation_data(kind), unum, focus);
  d.rule = DefenderDecision::Rule::kBasicMove;
  d.target = mirror(target);
  const double dash_power = normal_dash_power(w, table, &d.recover_mode);
  const double dist_thr = std::max(1.0, w.ball_dist_from_self * 0.1);
  if (!agent2d::body_go_to_point(w, target, dist_thr, dash_power, -1.0, 100, true, 15.0, &d.command)) {
    agent2d::body_turn_to_point(w, agent2d::ball_inertia_point(w, 1), 1, &d.command);
  }
  return d;
}

}  // namespace pamdp::hfo
