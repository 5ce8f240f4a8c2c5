#include "envs/hfo/defender.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include "envs/hfo/agent2d_formation.hpp"
#include "envs/hfo/goalie.hpp"

namespace pamdp::hfo {
namespace {

using agent2d::Command;
using agent2d::GoalieWorld;
using agent2d::InterceptTable;

Vec2 mirror(Vec2 v) {
  return {-v.x, -v.y};
}

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

// Strategy::get_normal_dash_power without its memory (the recover mode, kept while stamina is
// between half and 0.7 of the maximum; the smoothed defense line).
double normal_dash_power(const GoalieWorld& w, const InterceptTable& t) {
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
  if (w.self.stamina < kStaminaMax * 0.5) {
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

// Body_KickOneStep::get_max_possible_vel: the fastest first velocity along `angle_deg` one kick
// can give a ball moving at `ball_vel` (relative to the ball), or the kick that stops the ball
// when no kick reaches that direction. Circle2D::intersection(Ray2D) counts the circle's points
// on the ray's side (within 1 degree of its direction).
Vec2 max_possible_vel(double angle_deg, double kick_rate, Vec2 ball_vel, bool stop_when_none = true) {
  const double max_accel = std::min(kMaxKickPower * kick_rate, kBallAccelMax);
  const Vec2 u = polar(1.0, angle_deg * kDegToRad);
  const double along = u.x * ball_vel.x + u.y * ball_vel.y;
  const double disc = along * along - (ball_vel.r2() - max_accel * max_accel);
  Vec2 sols[2];
  int n = 0;
  if (disc >= 0.0) {
    for (const double t : {along - std::sqrt(disc), along + std::sqrt(disc)}) {
      const Vec2 p = u * t;
      if (std::fabs(agent2d::angle_norm(agent2d::th_deg(p) - angle_deg)) < 1.0) {
        sols[n++] = p;
      }
    }
  }
  if (n == 0) {
    if (!stop_when_none) {
      return {};  // KickTable::calc_max_velocity
    }
    Vec2 accel = ball_vel * -1.0;  // stop the ball
    if (const double r = accel.r(); r > max_accel) {
      accel *= max_accel / r;
    }
    return accel;
  }
  if (n == 1) {
    if (sols[0].r() > kBallSpeedMax) {
      // Only a circle holding the origin can bring the ball down to the speed limit.
      return ball_vel.r2() <= max_accel * max_accel ? sols[0] * (kBallSpeedMax / sols[0].r()) : Vec2{};
    }
    return sols[0];
  }
  Vec2 far = sols[0].r() >= sols[1].r() ? sols[0] : sols[1];
  const Vec2 near = sols[0].r() >= sols[1].r() ? sols[1] : sols[0];
  if (far.r() > kBallSpeedMax) {
    far = near.r() > kBallSpeedMax ? Vec2{} : far * (kBallSpeedMax / far.r());
  }
  return far;
}

double self_kick_rate(const GoalieWorld& w) {
  // SelfObject::updateBallInfo's kick rate (soccer_math.h kick_rate).
  const double dir_diff = std::fabs(agent2d::angle_norm(w.ball_angle_from_self_deg - w.self.body_deg));
  return kKickPowerRate *
         (1.0 - 0.25 * dir_diff / 180.0 - 0.25 * (w.ball_dist_from_self - kBallSize - kPlayerSize) / kKickableMargin);
}

// SamplePlayer::doForceKick: with the ball kickable by itself and an opponent alike, a field
// player kicks it as fast as one kick can toward the opponents' goal (Body_KickOneStep to
// (52.5, 0) in its own frame at ServerParam::ballSpeedMax; (45, 0) from beyond x 36 and |y| 10,
// which HFO's half field never puts a defender).
Command force_kick(const GoalieWorld& w) {
  Vec2 target{kPitchHalfLength, 0.0};
  if (w.self.pos.x > 36.0 && std::fabs(w.self.pos.y) > 10.0) {
    target.x = 45.0;
  }
  const double kick_rate = self_kick_rate(w);
  Vec2 first_vel = max_possible_vel(agent2d::th_deg(target - w.ball_pos), kick_rate, w.ball_vel);
  if (const double r = first_vel.r(); r > kBallSpeedMax) {
    first_vel *= kBallSpeedMax / r;
  }
  const Vec2 accel = first_vel - w.ball_vel;
  const double power = std::min(accel.r() / kick_rate, kMaxKickPower);
  return {Command::Kind::kKick, power, agent2d::angle_norm(agent2d::th_deg(accel) - w.self.body_deg)};
}

// --- The chain action with the ball kickable (RoleCenterBack::doKick -> Bhv_ChainAction) -------
//
// HFO's base team searches chains of cooperative actions (SamplePlayer::createActionGenerator):
// a shot only as a chain's second action, and a pass, a cross, a short dribble or a self-pass
// as its first. The defender is over 35 m from the goal it attacks (its own frame's (52.5, 0)),
// so no chain reaches a shot, and the search is one step deep: every candidate's end state is
// scored by SampleFieldEvaluator (the ball's x, plus 40 minus its distance to that goal when
// positive), and the best one above the present state's score is played; with none, the
// default hold. Modelled here: the self-pass (SelfPassGenerator), the first kick of the dribble
// it plays (Bhv_NormalDribble) and the hold. Not yet: the pass (StrictCheckPassGenerator) and
// the short dribble (ShortDribbleGenerator), 5 % of the recorded chain actions together.

// SampleFieldEvaluator's evaluate_state for a state with the defender holding the ball at `ball`
// (no shot bonus: FieldAnalyzer::can_shoot_from needs the goal within reach).
double field_evaluation(Vec2 ball) {
  if (std::fabs(ball.x) > kPitchHalfLength || std::fabs(ball.y) > kPitchHalfWidth) {
    return -DBL_MAX / 2.0;
  }
  return ball.x + std::max(0.0, 40.0 - (Vec2{kPitchHalfLength, 0.0} - ball).r());
}

struct SelfPass {
  Vec2 receive;
  double first_speed = 0.0;
  int n_turn = 0;
  int n_dash = 0;
};

// SelfPassGenerator::createSelfCache: where the defender stands after one step of inertia (the
// kick), n_turn steps of inertia and full dashes along `dash_deg`; stops early where stamina,
// the goal line or the touch line ends the run. Returns the number of positions.
int self_pass_cache(const GoalieWorld& w, double dash_deg, int n_turn, int max_dash, std::array<Vec2, 24>* cache) {
  int n = 0;
  const double stamina_thr =
      agent2d::stamina_of(w.self).capacity_is_empty() ? -kExtraStamina : kRecoverDecThreshold + 350.0;
  agent2d::StaminaModel stamina = agent2d::stamina_of(w.self);
  Vec2 pos = w.self.pos + w.self.vel;
  Vec2 vel = w.self.vel * kPlayerDecay;
  stamina.wait();
  for (int i = 0; i < n_turn; ++i) {
    pos += vel;
    vel *= kPlayerDecay;
    stamina.wait();
    (*cache)[static_cast<size_t>(n++)] = pos;
  }
  const Vec2 dir = polar(1.0, dash_deg * kDegToRad);
  for (int i = 0; i < max_dash; ++i) {
    if (stamina.stamina < stamina_thr) {
      break;
    }
    const double power = std::min(kMaxDashPower, std::max(0.0, stamina.stamina - stamina_thr));
    vel += dir * (power * kDashPowerRate * stamina.effort);
    pos += vel;
    if (pos.x > kPitchHalfLength - 2.5) {
      break;
    }
    if (std::fabs(pos.y) > kPitchHalfWidth - 3.0 &&
        ((pos.y > 0.0 && dash_deg > 0.0) || (pos.y < 0.0 && dash_deg < 0.0))) {
      break;
    }
    vel *= kPlayerDecay;
    stamina.dash(power);
    (*cache)[static_cast<size_t>(n++)] = pos;
  }
  return n;
}

// SelfPassGenerator::canKick: one kick gives the ball its first speed, and neither the defender
// nor an opponent (after its inertia, or one full dash along its body) can touch it next cycle.
bool self_pass_can_kick(const GoalieWorld& w, double kick_rate, Vec2 receive, double first_speed) {
  const double target_deg = agent2d::th_deg(receive - w.ball_pos);
  const Vec2 max_vel = max_possible_vel(target_deg, kick_rate, w.ball_vel, false);
  if (max_vel.r2() < first_speed * first_speed) {
    return false;
  }
  const Vec2 my_next = w.self.pos + w.self.vel;
  const Vec2 ball_next = w.ball_pos + polar(first_speed, target_deg * kDegToRad);
  if ((my_next - ball_next).r2() < std::pow(kPlayerSize + kBallSize + 0.1, 2)) {
    return false;
  }
  for (int i = 0; i < w.num_opponents; ++i) {
    const agent2d::PlayerView& o = w.opponents[static_cast<size_t>(i)];
    Vec2 o_next = o.pos + o.vel;
    if ((ball_next - o_next).r2() < std::pow(kKickableArea + 0.1, 2)) {
      return false;
    }
    // Full state: its body is always fresh (bodyCount 0), so one full dash along it.
    o_next += polar(kMaxDashPower * kDashPowerRate * kEffortMax, o.body_deg * kDegToRad);
    if ((ball_next - o_next).r2() < kKickableArea * kKickableArea) {
      return false;
    }
  }
  return true;
}

// FieldAnalyzer::predict_player_turn_cycle without back dashes.
int turn_cycles(double body_deg, double speed, double target_dist, double target_deg, double dist_thr) {
  double angle_diff = std::fabs(agent2d::angle_norm(target_deg - body_deg));
  double turn_margin = 180.0;
  if (dist_thr < target_dist) {
    turn_margin = std::max(15.0, std::asin(dist_thr / target_dist) * kRadToDeg);
  }
  int n_turn = 0;
  while (angle_diff > turn_margin) {
    angle_diff -= kMaxMoment / (1.0 + kInertiaMoment * speed);
    speed *= kPlayerDecay;
    ++n_turn;
  }
  return n_turn;
}

// SelfPassGenerator::checkOpponent: no opponent reaches the receive point first (with full
// state every position and velocity count is 0, which fixes the bonus steps).
bool self_pass_safe(const GoalieWorld& w, int n_turn, int n_dash, Vec2 receive) {
  const int self_step = 1 + n_turn + n_dash;
  const double target_deg = agent2d::th_deg(receive - w.ball_pos);
  for (int i = 0; i < w.num_opponents; ++i) {
    const agent2d::PlayerView& o = w.opponents[static_cast<size_t>(i)];
    const Vec2 rel = agent2d::rotate_deg(o.pos - w.ball_pos, -target_deg);
    if (rel.x < -4.0) {
      continue;
    }
    const Vec2 opp_pos = o.pos + o.vel * ((1.0 - agent2d::player_decay_pow(self_step)) / (1.0 - kPlayerDecay));
    const double target_dist = (opp_pos - receive).r();
    if (target_dist > agent2d::kRealSpeedMax * self_step + kKickableArea) {
      continue;
    }
    if (target_dist - kKickableArea < 0.001) {
      return false;
    }
    const double dash_dist = target_dist - kKickableArea - 0.2 - (o.pos - w.self.pos).r() * 0.01;
    const int opp_n_dash = agent2d::cycles_to_reach_distance(dash_dist);
    const int opp_n_turn =
        turn_cycles(o.body_deg, o.vel.r(), target_dist, agent2d::th_deg(receive - opp_pos), kKickableArea);
    const int opp_n_step = opp_n_turn == 0 ? opp_n_dash : opp_n_turn + opp_n_dash + 1;
    int bonus_step = receive.x < 27.0 ? 1 : 0;
    if (o.tackling) {
      bonus_step = -5;
    }
    if (rel.x > 0.8) {
      bonus_step += 1;  // and the position count's bonus, 0 with full state
    } else {
      // The generator assigns here, dropping the two bonuses above: bound(0, posCount -
      // penalty, 3), 0 with full state.
      bonus_step = 0;
    }
    if (opp_n_step - bonus_step <= self_step) {
      return false;
    }
  }
  return true;
}

// SelfPassGenerator::createCourses and the one-step search over its courses: the best
// self-pass by the field evaluation (ties to the course nearer the goal it attacks, the
// generator's order), or false when none beats holding the ball where it is.
bool best_self_pass(const GoalieWorld& w, double kick_rate, SelfPass* out) {
  constexpr int kAngleDivs = 60;
  constexpr double kAngleStep = 360.0 / kAngleDivs;
  constexpr int kMinDash = 5;
  const Vec2 ball = w.ball_pos;
  const int max_dash = ball.x < -20.0 ? 6 : ball.x < 0.0 ? 7 : ball.x < 10.0 ? 13 : ball.x < 20.0 ? 15 : 20;
  const double max_effective_turn = kMaxMoment / (1.0 + kInertiaMoment * w.self.vel.r() * kPlayerDecay);
  const Vec2 our_goal{-kPitchHalfLength, 0.0};
  const Vec2 their_goal{kPitchHalfLength, 0.0};
  constexpr double kTheirPenaltyLineX = kPitchHalfLength - 16.5;
  double best_eval = field_evaluation(ball);  // the present state: ActionChainGraph's start
  double best_goal_dist2 = DBL_MAX;
  bool found = false;
  std::array<Vec2, 24> cache{};
  for (int a = 0; a < kAngleDivs; ++a) {
    const double add_angle = kAngleStep * a;
    int n_turn = 0;
    if (a != 0) {
      if (std::fabs(agent2d::angle_norm(add_angle)) > max_effective_turn) {
        continue;
      }
      n_turn = 1;
    }
    const double dash_deg = agent2d::angle_norm(w.self.body_deg + add_angle);
    if (ball.x < kTheirPenaltyLineX + 5.0 && std::fabs(dash_deg) > 85.0) {
      continue;
    }
    const int size = self_pass_cache(w, dash_deg, n_turn, max_dash, &cache);
    int n_dash = size - n_turn;
    int count = 0;
    int dash_dec = 2;
    for (; n_dash >= kMinDash; n_dash -= dash_dec) {
      if (n_dash <= 10) {
        dash_dec = 1;
      }
      const Vec2 receive = cache[static_cast<size_t>(n_turn + n_dash - 1)];
      if ((receive - our_goal).r2() < 18.0 * 18.0) {
        continue;
      }
      const int steps = 1 + n_turn + n_dash;
      const double first_speed = agent2d::first_term_geom_series((receive - ball).r(), kBallDecay, steps);
      const bool ck = self_pass_can_kick(w, kick_rate, receive, first_speed);
      const bool sf = ck && self_pass_safe(w, n_turn, n_dash, receive);
      if (!sf) {
        continue;
      }
      const double eval = field_evaluation(receive);
      const double goal_dist2 = (receive - their_goal).r2();
      if (eval > best_eval || (found && eval == best_eval && goal_dist2 < best_goal_dist2)) {
        best_eval = eval;
        best_goal_dist2 = goal_dist2;
        *out = {receive, first_speed, n_turn, n_dash};
        found = true;
      }
      if (++count >= 10) {
        break;
      }
    }
  }
  return found;
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
  if (w.self.frozen) {
    d.rule = DefenderDecision::Rule::kFrozen;
    return d;
  }
  // SamplePlayer::doPreprocess checks the simultaneous kick before the role plays.
  if (w.self_kickable && w.exist_kickable_opponent) {
    d.rule = DefenderDecision::Rule::kKick;
    d.command = force_kick(w);
    return d;
  }
  // RoleCenterBack::execute: kickable unless a teammate with the ball kickable is nearer to it.
  bool kickable = w.self_kickable;
  if (w.exist_kickable_teammate && (w.teammates[0].pos - w.ball_pos).r() < w.ball_dist_from_self) {
    kickable = false;
  }
  if (kickable) {
    d.rule = DefenderDecision::Rule::kKick;
    d.command = {Command::Kind::kKick, 0.0, 0.0};  // the hold: its kick is not modelled
    const double kick_rate = self_kick_rate(w);
    SelfPass pass;
    if (best_self_pass(w, kick_rate, &pass)) {
      // Bhv_NormalDribble's first kick: the ball toward the receive point at the first speed.
      const Vec2 first_vel = polar(pass.first_speed, agent2d::th_deg(pass.receive - w.ball_pos) * kDegToRad);
      const Vec2 accel = first_vel - w.ball_vel;
      d.rule = DefenderDecision::Rule::kSelfPass;
      d.target = mirror(pass.receive);
      d.command = {Command::Kind::kKick, accel.r() / kick_rate,
                   agent2d::angle_norm(agent2d::th_deg(accel) - w.self.body_deg)};
    }
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
  const double dash_power = normal_dash_power(w, table);
  const double dist_thr = std::max(1.0, w.ball_dist_from_self * 0.1);
  if (!agent2d::body_go_to_point(w, target, dist_thr, dash_power, -1.0, 100, true, 15.0, &d.command)) {
    agent2d::body_turn_to_point(w, agent2d::ball_inertia_point(w, 1), 1, &d.command);
  }
  return d;
}

}  // namespace pamdp::hfo
