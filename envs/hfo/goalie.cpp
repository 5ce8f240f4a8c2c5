// agent2d's goalie, from its rules (see goalie.hpp for the sources). Everything below works in
// the goalie's own frame (goal at x = -52.5), as agent2d does; goalie_world() mirrors once.
#include "envs/hfo/goalie.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>

namespace pamdp::hfo {
namespace {

using agent2d::angle_norm;
using agent2d::Command;
using agent2d::GoalieWorld;
using agent2d::InterceptTable;
using agent2d::kOurPenaltyLineX;
using agent2d::th_deg;

// ServerParam values agent2d reads (librcsc common/server_param.cpp defaults).
constexpr double kPenaltyHalfWidth = kPenaltyBoxHalfWidth;  // penaltyAreaHalfWidth(): 20.16
constexpr double kErrorValue = DBL_MAX;                     // Vector2D::ERROR_VALUE

// librcsc Line2D: a x + b y + c = 0.
struct Line {
  double a;
  double b;
  double c;
  static Line through(Vec2 p1, Vec2 p2) {
    const double a = -(p2.y - p1.y);
    const double b = p2.x - p1.x;
    return {a, b, -a * p1.x - b * p1.y};
  }
  static Line from(Vec2 origin, double dir_deg) {
    const double a = -std::sin(dir_deg * kDegToRad);
    const double b = std::cos(dir_deg * kDegToRad);
    return {a, b, -a * origin.x - b * origin.y};
  }
  [[nodiscard]] double y_at(double x) const { return std::fabs(b) < 1e-10 ? kErrorValue : -(a * x + c) / b; }
  [[nodiscard]] double dist(Vec2 p) const { return std::fabs((a * p.x + b * p.y + c) / std::sqrt(a * a + b * b)); }
  // Line2D::intersection; an invalid point is (ERROR_VALUE, ERROR_VALUE).
  [[nodiscard]] Vec2 intersection(const Line& o) const {
    const double tmp = a * o.b - b * o.a;
    if (std::fabs(tmp) < 1e-10) {
      return {kErrorValue, kErrorValue};
    }
    return {(b * o.c - o.b * c) / tmp, (o.a * c - a * o.c) / tmp};
  }
};

bool valid(Vec2 p) {
  return p.x != kErrorValue && p.y != kErrorValue;
}

struct Context {
  const GoalieWorld& w;
  InterceptTable& t;
  Command* out;
  // The goalie's own reach, predicted on first use (predict_self).
  [[nodiscard]] int self_min() const {
    if (!t.self_predicted) {
      agent2d::predict_self(w, &t);
    }
    return t.self_reach_cycle;
  }
  [[nodiscard]] const InterceptTable& table_with_self() const {
    (void)self_min();
    return t;
  }
};

// --- Bhv_GoalieBasicMove -------------------------------------------------------------------

Vec2 basic_target_point(const Context& c) {
  const GoalieWorld& w = c.w;
  constexpr double kBaseMoveX = -49.8;
  constexpr double kDangerMoveX = -51.5;
  int ball_reach_step = 0;
  if (!w.exist_kickable_opponent) {
    ball_reach_step = std::min(c.t.teammate_reach_cycle, c.t.opponent_reach_cycle);
  }
  const Vec2 base_pos = agent2d::ball_inertia_point(w, ball_reach_step);
  if (base_pos.y > kGoalHalfWidth + 3.0) {
    const double a = th_deg(Vec2{-kPitchHalfLength, kGoalHalfWidth} - base_pos);
    if (-140.0 < a && a < -90.0) {
      return {kDangerMoveX, kGoalHalfWidth + 0.001};
    }
  } else if (base_pos.y < -kGoalHalfWidth - 3.0) {
    const double a = th_deg(Vec2{-kPitchHalfLength, -kGoalHalfWidth} - base_pos);
    if (90.0 < a && a < 140.0) {
      return {kDangerMoveX, -kGoalHalfWidth - 0.001};
    }
  }
  if (base_pos.x < -kPitchHalfLength + 8.0 && std::fabs(base_pos.y) > kGoalHalfWidth + 2.0) {
    return {kBaseMoveX, (base_pos.y < 0.0 ? -1.0 : 1.0) * (kGoalHalfWidth - 0.1)};
  }
  constexpr double kXBack = 7.0;
  constexpr double kYBuf = 0.5;
  int ball_pred_cycle = 5;
  const Vec2 base_point{-kPitchHalfLength - kXBack, 0.0};
  Vec2 ball_point = base_pos;
  if (!w.exist_kickable_opponent) {
    ball_pred_cycle = std::min(ball_pred_cycle, c.t.opponent_reach_cycle);
    // inertia_n_step_point(base_pos, ball vel, n, ball_decay)
    ball_point = base_pos + w.ball_vel * ((1.0 - agent2d::ball_decay_pow(ball_pred_cycle)) / (1.0 - kBallDecay));
  }
  if (ball_point.x < base_point.x + 0.1) {
    ball_point.x = base_point.x + 0.1;
  }
  double move_y = Line::through(ball_point, base_point).y_at(kBaseMoveX);
  move_y = std::min(move_y, kGoalHalfWidth - kYBuf);
  move_y = std::max(move_y, -kGoalHalfWidth + kYBuf);
  return {kBaseMoveX, move_y};
}

double basic_dash_power(const Context& c, Vec2 move_point) {
  const GoalieWorld& w = c.w;
  const double my_inc = kStaminaIncMax * w.self.recovery;
  if (std::fabs(w.self.pos.x - move_point.x) > 3.0) {
    return kMaxDashPower;
  }
  if (w.ball_pos.x > -30.0) {
    return w.self.stamina < kStaminaMax * 0.9 ? my_inc * 0.5 : my_inc;
  }
  if (w.ball_pos.x > kOurPenaltyLineX) {
    if (std::fabs(w.ball_pos.y) > 20.0) {
      return my_inc;
    }
    if (w.ball_vel.x > 1.0) {
      return my_inc * 0.5;
    }
    if (c.t.opponent_reach_cycle <= 3) {
      return kMaxDashPower;
    }
    if (w.self.stamina < kStaminaMax * 0.7) {
      return my_inc * 0.7;
    }
    return kMaxDashPower * 0.6;
  }
  if (std::fabs(w.ball_pos.y) < 15.0 || w.ball_pos.y * w.self.pos.y < 0.0) {
    return kMaxDashPower;
  }
  return my_inc;
}

double dist_thr_of(const GoalieWorld& w, double rate) {
  return std::max(0.5, w.ball_dist_from_self * rate);
}

// Bhv_GoalieBasicMove::doGoToPointLookBall: in play_on Bhv_GoToPointLookBall; in any other
// play mode (here: after its own catch) Body_GoToPoint with its default arguments, or else
// Body_TurnToAngle to the ball's direction, the body angle every caller passes.
void go_to_point_look_ball(const Context& c, Vec2 target, double dist_thr, double dash_power) {
  if (!c.w.catch_mode) {
    agent2d::go_to_point_look_ball(c.w, target, dist_thr, dash_power, 0.7, c.out);
    return;
  }
  if (!agent2d::body_go_to_point(c.w, target, dist_thr, dash_power, -1.0, 100, true, 15.0, c.out)) {
    agent2d::body_turn_to_angle(c.w, c.w.ball_angle_from_self_deg, c.out);
  }
}

bool prepare_deep_cross(const Context& c, Vec2 move_point) {
  const GoalieWorld& w = c.w;
  if (std::fabs(move_point.y) < kGoalHalfWidth - 0.8) {
    return false;
  }
  if (std::fabs(th_deg(w.ball_pos - Vec2{-kPitchHalfLength, 0.0})) < 60.0) {
    return false;
  }
  const double thr = dist_thr_of(w, 0.1);
  if ((agent2d::self_inertia_final_point(w) - move_point).r() > thr) {
    go_to_point_look_ball(c, move_point, thr, basic_dash_power(c, move_point));
    return true;
  }
  agent2d::body_turn_to_angle(w, w.ball_pos.y < 0.0 ? 10.0 : -10.0, c.out);
  return true;
}

bool stop_at_move_point(const Context& c, Vec2 move_point) {
  const GoalieWorld& w = c.w;
  const double thr = dist_thr_of(w, 0.1);
  if ((w.self.pos - move_point).r() < thr) {
    if ((agent2d::self_inertia_final_point(w) - move_point).r() < thr) {
      return false;
    }
    // Body_StopDash may decide that no dash is worth it: then no body command goes out.
    agent2d::body_stop_dash(w, true, c.out);
    return true;
  }
  return false;
}

bool go_to_move_point(const Context& c, Vec2 move_point) {
  const GoalieWorld& w = c.w;
  const double thr = dist_thr_of(w, 0.08);
  const double y_diff = std::fabs(move_point.y - w.self.pos.y);
  if (y_diff < thr) {
    return false;
  }
  double dash_power = basic_dash_power(c, move_point);
  if (std::fabs(std::fabs(w.self.body_deg) - 90.0) < 7.0) {
    const double required = y_diff / (w.self.effort * kDashPowerRate);
    dash_power = std::min(dash_power, required);
    if (move_point.y > w.self.pos.y) {
      if (w.self.body_deg < 0.0) {
        dash_power = -dash_power;
      }
    } else if (w.self.body_deg > 0.0) {
      dash_power = -dash_power;
    }
    *c.out = agent2d::do_dash(w, clamp(dash_power, kMinDashPower, kMaxDashPower), 0.0);
  } else {
    go_to_point_look_ball(c, move_point, thr, dash_power);
  }
  return true;
}

bool move_for_dangerous_state(const Context& c, Vec2 move_point) {
  const GoalieWorld& w = c.w;
  const Vec2 ball_next = w.ball_pos + w.ball_vel;
  if (std::fabs(move_point.x - w.self.pos.x) > 0.5 && ball_next.x < -kPitchHalfLength + 11.0 &&
      std::fabs(ball_next.y) < kGoalHalfWidth + 1.0) {
    if (w.num_opponents > 0 && (w.opponents[0].pos - w.ball_pos).r() < 2.0) {
      Vec2 block = w.opponents[0].pos;
      block.x -= 2.5;
      block.y = move_point.y;
      if (w.self.pos.x < block.x) {
        block.x = w.self.pos.x;
      }
      if (go_to_move_point(c, block)) {
        return true;
      }
      go_to_point_look_ball(c, move_point, dist_thr_of(w, 0.1), kMaxDashPower);
      return true;
    }
  }
  return false;
}

bool correct_x(const Context& c, Vec2 move_point) {
  const GoalieWorld& w = c.w;
  constexpr double kXBuf = 0.5;
  if (std::fabs(move_point.x - w.self.pos.x) < kXBuf) {
    return false;
  }
  if ((!w.exist_kickable_opponent && c.t.opponent_reach_cycle >= 4) || w.ball_dist_from_self > 18.0) {
    const double power = basic_dash_power(c, move_point);
    if (!w.exist_kickable_opponent && w.ball_dist_from_self > 30.0) {
      if (!agent2d::body_go_to_point(w, move_point, kXBuf, power, -1.0, 100, true, 15.0, c.out)) {
        agent2d::body_turn_to_angle(w, w.self.body_deg > 0.0 ? 90.0 : -90.0, c.out);
      }
      return true;
    }
    go_to_point_look_ball(c, move_point, kXBuf, power);
    return true;
  }
  return false;
}

bool correct_body_dir(const Context& c, Vec2 move_point, bool consider_opp) {
  const GoalieWorld& w = c.w;
  const Vec2 ball_next = w.ball_pos + w.ball_vel;
  const double target_angle = ball_next.y < 0.0 ? -90.0 : 90.0;
  if (std::fabs(angle_norm(w.self.body_deg - target_angle)) < 5.0) {
    return false;
  }
  if (std::fabs(th_deg(w.ball_pos - Vec2{-kPitchHalfLength, 0.0})) >= 60.0) {
    return false;
  }
  const double opp_ball_dist = w.num_opponents == 0 ? 100.0 : (w.opponents[0].pos - w.ball_pos).r();
  if (!consider_opp || opp_ball_dist > 7.0 || w.ball_dist_from_self > 20.0 ||
      (std::fabs(move_point.y - w.self.pos.y) < 1.0 && !w.exist_kickable_opponent)) {
    agent2d::body_turn_to_angle(w, target_angle, c.out);
    return true;
  }
  return false;
}

bool basic_tackle(const Context& c);

void basic_move(const Context& c) {
  const Vec2 move_point = basic_target_point(c);
  if (basic_tackle(c) || prepare_deep_cross(c, move_point) || stop_at_move_point(c, move_point) ||
      move_for_dangerous_state(c, move_point) || correct_x(c, move_point) || correct_body_dir(c, move_point, true) ||
      go_to_move_point(c, move_point) || correct_body_dir(c, move_point, false)) {
    return;
  }
  *c.out = agent2d::do_turn(c.w, 0.0);
}

// --- Bhv_BasicTackle(0.8, 90) ---------------------------------------------------------------

// SelfObject's tackle probability (librcsc self_object.cpp, updateBallInfo): the server's
// tackle failure (ball in the body frame against tackle_dist, tackle_back_dist, tackle_width,
// tackle_exponent).
double tackle_probability(const GoalieWorld& w, double exponent = kTackleExponent) {
  const double a = (w.self.body_deg) * kDegToRad;
  const Vec2 d = w.ball_pos - w.self.pos;
  const double x = d.x * std::cos(a) + d.y * std::sin(a);
  const double y = -d.x * std::sin(a) + d.y * std::cos(a);
  const double dist = x > 0.0 ? kTackleDist : kTackleBackDist;
  if (dist <= 0.0) {
    return 0.0;
  }
  const double fail = std::pow(std::fabs(x) / dist, exponent) + std::pow(std::fabs(y) / kTackleWidth, exponent);
  return fail >= 1.0 ? 0.0 : std::max(0.0, 1.0 - fail);
}

// --- TackleGenerator (HFO src/chain_action/tackle_generator.cpp, its active branches) ------

// librcsc Segment2D, as far as the generator uses it.
struct Segment {
  Vec2 origin;
  Vec2 terminal;
  [[nodiscard]] bool contains(Vec2 p) const {
    constexpr double kCalcError = 1.0e-9;  // Segment2D::CALC_ERROR
    return (p.x - origin.x) * (p.x - terminal.x) <= kCalcError && (p.y - origin.y) * (p.y - terminal.y) <= kCalcError;
  }
  [[nodiscard]] Vec2 intersection(const Line& l) const {
    const Vec2 p = Line::through(origin, terminal).intersection(l);
    return valid(p) && contains(p) ? p : Vec2{kErrorValue, kErrorValue};
  }
};

// Rect2D::intersection(Line2D) for the pitch: the edges in librcsc's order (left, right, top,
// bottom), at most two points, one when both are the same corner.
int pitch_intersections(const Line& l, std::array<Vec2, 2>* sol) {
  constexpr double kL = -kPitchHalfLength;
  constexpr double kR = kPitchHalfLength;
  constexpr double kT = -kPitchHalfWidth;
  constexpr double kB = kPitchHalfWidth;
  int n = 0;
  const auto edge = [&](Segment e, bool side) {
    if (n >= 2) {
      return;
    }
    const Vec2 p = e.intersection(l);
    if (valid(p) && (side ? (kT <= p.y && p.y <= kB) : (kL <= p.x && p.x <= kR))) {
      (*sol)[static_cast<size_t>(n++)] = p;
    }
  };
  edge({{kL, kT}, {kL, kB}}, true);
  edge({{kR, kT}, {kR, kB}}, true);
  edge({{kL, kT}, {kR, kT}}, false);
  edge({{kL, kB}, {kR, kB}}, false);
  if (n == 2 && std::fabs((*sol)[0].x - (*sol)[1].x) < 1.0e-5 && std::fabs((*sol)[0].y - (*sol)[1].y) < 1.0e-5) {
    n = 1;
  }
  return n;
}

// Rect2D::intersection for a ray or a segment: the line's points that lie on it.
template <typename On>
int pitch_intersections(const Line& l, On on, Vec2* first) {
  std::array<Vec2, 2> sol{};
  int n = pitch_intersections(l, &sol);
  if (n > 1 && !on(sol[1])) {
    --n;
  }
  if (n > 0 && !on(sol[0])) {
    sol[0] = sol[1];
    --n;
  }
  *first = sol[0];
  return n;
}

bool out_of_pitch(Vec2 p) {
  return std::fabs(p.x) > kPitchHalfLength || std::fabs(p.y) > kPitchHalfWidth;
}

Vec2 ball_after(Vec2 pos, Vec2 vel, int n) {  // inertia_n_step_point with the ball's decay
  return pos + vel * ((1.0 - agent2d::ball_decay_pow(n)) / (1.0 - kBallDecay));
}

// ServerParam::ballMoveStep: cycles for a ball at this speed to cover the distance.
int ball_move_step(double speed, double dist) {
  double n = -1.0;  // calc_length_geom_series
  if (speed > 1.0e-6 && dist >= 0.0) {
    const double tmp = 1.0 + dist * (kBallDecay - 1.0) / speed;
    n = dist <= 1.0e-6 ? 0.0 : (tmp <= 1.0e-6 ? -1.0 : std::log(tmp) / std::log(kBallDecay));
  }
  return static_cast<int>(std::ceil(n) + 1.0e-10);
}

// TackleGenerator::predictOpponentReachStep, with full state (no position or body count).
int opponent_reach_step(const agent2d::PlayerView& o, Vec2 ball_pos, Vec2 ball_vel, double move_deg, int max_cycle) {
  const double speed = o.vel.r();
  // FieldAnalyzer::estimate_min_reach_cycle.
  const Vec2 d = o.pos - ball_pos;
  const double a = -move_deg * kDegToRad;
  const Vec2 rel{d.x * std::cos(a) - d.y * std::sin(a), d.x * std::sin(a) + d.y * std::cos(a)};
  int min_cycle =
      rel.x < -1.0 ? -1 : std::max(1, static_cast<int>(std::floor(std::fabs(rel.y) / agent2d::kRealSpeedMax)));
  if (min_cycle < 0) {
    min_cycle = 10;
  }
  for (int cycle = min_cycle; cycle < max_cycle; ++cycle) {
    const Vec2 ball = ball_after(ball_pos, ball_vel, cycle);
    if (out_of_pitch(ball)) {
      return 1000;
    }
    const Vec2 inertia = o.pos + o.vel * ((1.0 - std::pow(kPlayerDecay, cycle)) / (1.0 - kPlayerDecay));
    const double target_dist = (ball - inertia).r();
    if (target_dist - kKickableArea < 0.001) {
      return cycle;
    }
    double dash_dist = target_dist;
    if (cycle > 1) {
      dash_dist -= kKickableArea + 0.5;
    }
    if (dash_dist > agent2d::kRealSpeedMax * cycle) {
      continue;
    }
    const int n_dash = agent2d::cycles_to_reach_distance(dash_dist);
    if (n_dash > cycle) {
      continue;
    }
    const int n_turn =
        agent2d::predict_player_turn_cycle(o.body_deg, speed, target_dist, th_deg(ball - inertia), kKickableArea, true);
    int n_step = n_turn == 0 ? n_dash : n_turn + n_dash + 1;
    if (o.tackling) {
      n_step += 5;
    }
    if (n_step <= cycle) {
      return cycle;
    }
  }
  return 1000;
}

// TackleGenerator::predictOpponentsReachStep.
int opponents_reach_step(const GoalieWorld& w, Vec2 ball_vel, double move_deg) {
  int first_min_step = 50;
  if (out_of_pitch(w.ball_pos + ball_vel * (1.0 / (1.0 - kBallDecay)))) {
    Vec2 sol;
    const auto ahead = [&](Vec2 p) { return std::fabs(angle_norm(th_deg(p - w.ball_pos) - move_deg)) < 1.0; };
    if (pitch_intersections(Line::from(w.ball_pos, move_deg), ahead, &sol) == 1) {
      first_min_step = ball_move_step(ball_vel.r(), (sol - w.ball_pos).r());
    }
  }
  int min_step = first_min_step;
  for (int i = 0; i < w.num_opponents; ++i) {
    min_step = std::min(min_step, opponent_reach_step(w.opponents[i], w.ball_pos, ball_vel, move_deg, min_step));
  }
  return min_step == first_min_step ? 1000 : min_step;
}

// TackleGenerator::evaluate: the score of a tackle that leaves the ball with velocity `vel`.
double tackle_score(const GoalieWorld& w, Vec2 vel) {
  const Vec2 end = w.ball_pos + vel * (1.0 / (1.0 - kBallDecay));  // inertia_final_point
  const Segment ball_line{w.ball_pos, end};
  const double speed = vel.r();
  const double move_deg = th_deg(vel);
  const double half_max = kBallSpeedMax * 0.5;
  if (end.x > kPitchHalfLength && (w.ball_pos - Vec2{kPitchHalfLength, 0.0}).r2() < 20.0 * 20.0) {
    const Vec2 p = ball_line.intersection(Line::through({kPitchHalfLength, 10.0}, {kPitchHalfLength, -10.0}));
    if (valid(p) && std::fabs(p.y) < kGoalHalfWidth) {
      constexpr double kGoalWidth = 2.0 * kGoalHalfWidth;
      return 1000000.0 * (1.0 - std::exp(-speed * speed / (2.0 * half_max * half_max))) *
             std::exp(-p.y * p.y / (2.0 * kGoalWidth * kGoalWidth));
    }
  }
  if (end.x < -kPitchHalfLength) {
    const Vec2 p = ball_line.intersection(Line::through({-kPitchHalfLength, 10.0}, {-kPitchHalfLength, -10.0}));
    if (valid(p) && std::fabs(p.y) < kGoalHalfWidth + 1.0) {
      const double dy = std::fabs(p.y) - kGoalHalfWidth;
      return -10000.0 * std::exp(-dy * dy / (2.0 * kGoalHalfWidth * kGoalHalfWidth)) +
             10000.0 * std::exp(-speed * speed / (2.0 * half_max * half_max));
    }
  }
  const int opp_step = opponents_reach_step(w, vel, move_deg);
  Vec2 final_point = ball_after(w.ball_pos, vel, opp_step);
  {
    const Segment seg{w.ball_pos, final_point};
    Vec2 sol;
    if (pitch_intersections(
            Line::through(seg.origin, seg.terminal), [&](Vec2 p) { return seg.contains(p); }, &sol) > 0) {
      final_point = sol;
    }
  }
  const double goal_diff = std::fabs(angle_norm(th_deg(Vec2{-kPitchHalfLength, 0.0} - w.ball_pos) - move_deg));
  const double goal_rate = 1.0 - std::exp(-goal_diff * goal_diff / (2.0 * 40.0 * 40.0));
  const double y_off = std::fabs(final_point.y) - kPitchHalfWidth;
  const double y_rate = std::fabs(final_point.y) > kPitchHalfWidth - 0.1
                            ? 1.0
                            : std::exp(-y_off * y_off / (2.0 * std::pow(kPitchHalfWidth * 0.7, 2)));
  const double opp = static_cast<double>(opp_step);
  const double opp_rate = 1.0 - std::exp(-opp * opp / (2.0 * 30.0 * 30.0));
  return 10000.0 * goal_rate * y_rate * opp_rate;
}

// TackleGenerator::calculate: 40 directions from -180 degrees in 9-degree steps relative to the
// body; the global direction of the best (the first of equal scores).
double best_tackle_angle(const GoalieWorld& w) {
  constexpr int kAngleDivs = 40;
  constexpr double kStep = (kMaxMoment - kMinMoment) / kAngleDivs;
  const double ball_rel = std::fabs(angle_norm(w.ball_angle_from_self_deg - w.self.body_deg));
  const double tackle_rate = kTacklePowerRate * (1.0 - 0.5 * ball_rel / 180.0);
  double best_angle = 0.0;  // TackleResult::clear
  double best_score = -DBL_MAX;
  for (int i = 0; i < kAngleDivs; ++i) {
    const double dir = angle_norm(kMinMoment + kStep * i);
    const double eff =
        (kMaxBackTacklePower + (kMaxTacklePower - kMaxBackTacklePower) * (1.0 - std::fabs(dir) / 180.0)) * tackle_rate;
    const double angle = angle_norm(w.self.body_deg + dir);
    Vec2 vel = w.ball_vel + polar(eff, angle * kDegToRad);
    if (const double v = vel.r(); v > kBallSpeedMax) {
      vel *= kBallSpeedMax / v;
    }
    const double score = tackle_score(w, vel);
    if (score > best_score) {
      best_score = score;
      best_angle = angle;
    }
  }
  return best_angle;
}

bool basic_tackle(const Context& c) {
  const GoalieWorld& w = c.w;
  // In its own penalty area the goalie has no foul option (version 14 rule of
  // Bhv_BasicTackle::execute), and outside it HFO's goalie never stands.
  if (tackle_probability(w) < 0.8) {
    return false;
  }
  const int self_min = c.self_min();
  const int opp_min = c.t.opponent_reach_cycle;
  const Vec2 self_reach_point = agent2d::ball_inertia_point(w, self_min);
  bool ball_into_goal = false;
  if (self_reach_point.x < -kPitchHalfLength) {
    // Ray2D from the ball along its velocity against the goal line.
    const Line ball_line = Line::from(w.ball_pos, th_deg(w.ball_vel));
    const Vec2 p = ball_line.intersection(Line::through({-kPitchHalfLength, 10.0}, {-kPitchHalfLength, -10.0}));
    const bool ahead = valid(p) && (p - w.ball_pos).dot(w.ball_vel) >= 0.0;
    ball_into_goal = ahead && std::fabs(p.y) < kGoalHalfWidth + 1.0;
  }
  const Vec2 their_goal{kPitchHalfLength, 0.0};
  if (!(w.exist_kickable_opponent || ball_into_goal ||
        (opp_min < self_min - 3 && opp_min < c.t.teammate_reach_cycle - 3) ||
        (self_min >= 5 && (w.ball_pos - their_goal).r2() < 100.0 &&
         std::fabs(angle_norm(th_deg(their_goal - w.self.pos) - w.self.body_deg)) < 45.0))) {
    return false;
  }
  // Bhv_BasicTackle::executeV14 without a foul: always a tackle, in TackleGenerator's best
  // direction.
  *c.out = {Command::Kind::kTackle, angle_norm(best_tackle_angle(w) - w.self.body_deg), 0.0};
  return true;
}

// --- Bhv_GoalieChaseBall -------------------------------------------------------------------

void go_to_catch_point(const Context& c, Vec2 target) {
  const GoalieWorld& w = c.w;
  const Vec2 d = target - w.self.pos;
  const double a = -w.self.body_deg * kDegToRad;
  const Vec2 rel{d.x * std::cos(a) - d.y * std::sin(a), d.x * std::sin(a) + d.y * std::cos(a)};
  const double rel_angle = th_deg(rel);
  const double angle_buf = std::fabs(std::atan2(agent2d::kCatchableArea * 0.9, rel.r()) * kRadToDeg);
  if (std::fabs(rel_angle) < angle_buf) {
    *c.out = agent2d::do_dash(w, std::min(w.self.stamina + kExtraStamina, kMaxDashPower), 0.0);
  } else if (std::fabs(rel_angle) > 180.0 - angle_buf) {
    double power = kMinDashPower;
    const double required = kMinDashPower < 0.0 ? kMinDashPower * -2.0 : kMinDashPower;
    if (w.self.stamina + kExtraStamina < required) {
      power = (w.self.stamina + kExtraStamina) * -0.5;
      power = std::max(power, kMinDashPower);
    }
    *c.out = agent2d::do_dash(w, power, 0.0);
  } else if (std::fabs(rel_angle) < 90.0) {
    *c.out = agent2d::do_turn(w, rel_angle);
  } else {
    *c.out = agent2d::do_turn(w, angle_norm(rel_angle - 180.0));
  }
}

bool ball_shoot_moving(const GoalieWorld& w) {
  if (w.ball_dist_from_self > 30.0 || w.ball_pos.x > -34.5 || w.exist_kickable_opponent) {
    return false;
  }
  if (std::fabs(w.ball_vel.x) < 0.1) {
    return w.ball_pos.x < -46.0 && std::fabs(w.ball_pos.y) < kGoalHalfWidth + 2.0;
  }
  const Line ball_line = Line::from(w.ball_pos, th_deg(w.ball_vel));
  const double y = ball_line.y_at(-kPitchHalfLength);
  if (std::fabs(ball_line.b) > 0.1 && std::fabs(y) < kGoalHalfWidth + 2.0 && w.ball_pos.x < -40.0 &&
      std::fabs(w.ball_pos.y) < 15.0) {
    const Vec2 end_point = w.ball_pos + w.ball_vel * (1.0 / (1.0 - kBallDecay));
    return w.ball_vel.r() > 0.5 && end_point.x < -kPitchHalfLength + 2.0;
  }
  return false;
}

// Whether the ball's whole path, from where it is to where it stops, stays outside the region
// x < x_max, |y| < y_max: then the point where the goalie would reach it does too, whatever the
// cycle (x and y change monotonically along the path).
bool path_stays_outside(const GoalieWorld& w, double x_max, double y_max) {
  const Vec2 end = w.ball_pos + w.ball_vel * (1.0 / (1.0 - kBallDecay));
  if (std::min(w.ball_pos.x, end.x) >= x_max) {
    return true;
  }
  const double y_lo = std::min(w.ball_pos.y, end.y);
  const double y_hi = std::max(w.ball_pos.y, end.y);
  return y_lo >= y_max || y_hi <= -y_max;
}

bool ball_chase_situation(const Context& c) {
  const GoalieWorld& w = c.w;
  const int opp_min = c.t.opponent_reach_cycle;
  const Vec2 ball_next = w.ball_pos + w.ball_vel;
  if (ball_next.x < -kPitchHalfLength + 8.0 && std::fabs(ball_next.y) < kGoalHalfWidth + 3.0) {
    const int self_min = c.self_min();
    if (w.ball_dist_from_self < 3.0 && self_min <= 3) {
      return true;
    }
    return !(self_min > opp_min + 3 && opp_min < 7);
  }
  if (ball_shoot_moving(w) && c.self_min() < opp_min) {
    return true;
  }
  const double pen_thr = std::max(1.0, w.ball_dist_from_self * 0.1 + 1.0);
  // Below, a reach point outside its penalty area (less pen_thr) rules chasing out; the path
  // tells that often without the goalie's own intercept prediction.
  if (path_stays_outside(w, kOurPenaltyLineX - pen_thr, kPenaltyHalfWidth - pen_thr)) {
    return false;
  }
  const int self_min = c.self_min();
  const Vec2 my_int_pos = agent2d::ball_inertia_point(w, self_min);
  if (std::fabs(my_int_pos.y) > kPenaltyHalfWidth - pen_thr || my_int_pos.x > kOurPenaltyLineX - pen_thr) {
    return false;
  }
  if (opp_min <= self_min - 2) {
    return false;
  }
  const double my_dist_to_catch = (w.self.pos - my_int_pos).r();
  double opp_min_dist = 10000.0;
  for (int i = 0; i < w.num_opponents; ++i) {
    opp_min_dist = std::min(opp_min_dist, (w.opponents[i].pos - my_int_pos).r());
  }
  return opp_min_dist >= my_dist_to_catch - 2.0;
}

void chase_ball(const Context& c) {
  const GoalieWorld& w = c.w;
  if (basic_tackle(c)) {
    return;
  }
  const Vec2 my_int_pos = agent2d::ball_inertia_point(w, c.self_min());
  const double pen_thr = std::max(1.0, w.ball_dist_from_self * 0.1 + 1.0);
  const Line ball_line = Line::from(w.ball_pos, th_deg(w.ball_vel));
  const Line defend_line = Line::through({w.self.pos.x, -10.0}, {w.self.pos.x, 10.0});
  if (my_int_pos.x > -kPitchHalfLength - 1.0 && my_int_pos.x < kOurPenaltyLineX - pen_thr &&
      std::fabs(my_int_pos.y) < kPenaltyHalfWidth - pen_thr) {
    const bool save_recovery = ball_line.dist(w.self.pos) < agent2d::kCatchableArea;
    agent2d::body_intercept(w, c.table_with_self(), save_recovery, c.out);
    return;
  }
  const int self_min = c.self_min();
  const int opp_min = c.t.opponent_reach_cycle;
  Vec2 inter = ball_line.intersection(defend_line);
  if (!valid(inter) || ball_line.dist(w.self.pos) < agent2d::kCatchableArea * 0.8 ||
      std::fabs(inter.y) > kGoalHalfWidth + 3.0) {
    if (!w.exist_kickable_opponent) {
      if (self_min <= opp_min + 2 && my_int_pos.x > -kPitchHalfLength - 2.0 &&
          my_int_pos.x < kOurPenaltyLineX - pen_thr && std::fabs(my_int_pos.y) < kPenaltyHalfWidth - pen_thr) {
        if (agent2d::body_intercept(w, c.table_with_self(), false, c.out)) {
          return;
        }
      }
      go_to_catch_point(c, w.ball_pos);
      return;
    }
  }
  if (std::fabs(inter.x) > kPitchHalfLength + agent2d::kCatchableArea ||
      inter.x > kOurPenaltyLineX - agent2d::kCatchableArea ||
      std::fabs(inter.y) > kPenaltyHalfWidth - agent2d::kCatchableArea) {
    if (!agent2d::body_intercept(w, c.table_with_self(), false, c.out)) {
      basic_move(c);
    }
    return;
  }
  const Vec2 my_final = agent2d::self_inertia_final_point(w);
  const double dist_thr = std::max(0.5, 0.2 + w.ball_dist_from_self * 0.1);
  if ((my_final - inter).r() < dist_thr) {
    agent2d::body_stop_dash(w, false, c.out);  // may send nothing
    return;
  }
  if (w.ball_pos.x > -35.0) {
    inter.y = w.ball_pos.y * inter.y < 0.0 ? 0.0 : inter.y * 0.5;
  }
  go_to_catch_point(c, inter);
}

// Our penalty area as RoleGoalie::execute shrinks it (Rect2D: left-top and size).
bool in_catch_area(Vec2 p) {
  const double left = -kPitchHalfLength;
  const double top = -kPenaltyHalfWidth + 1.0;
  return left <= p.x && p.x <= left + (16.5 - 1.0) && top <= p.y && p.y <= top + (2.0 * kPenaltyHalfWidth - 2.0);
}

}  // namespace

double tackle_success_probability(const agent2d::GoalieWorld& w, bool foul) {
  return tackle_probability(w, foul ? kFoulExponent : kTackleExponent);
}

double tackle_generator_angle(const agent2d::GoalieWorld& w) {
  return best_tackle_angle(w);
}

agent2d::GoalieWorld defense_world(const SoccerState& s, int self, bool server_noise) {
  using agent2d::mirror;
  auto view = [&](const PlayerState& p) {
    agent2d::PlayerView v;
    v.pos = mirror(p.pos);
    v.vel = mirror(p.vel);
    v.body_deg = angle_norm(p.body_deg + 180.0);
    v.tackling = p.tackle_cycles > 0;
    v.goalie = p.goalie;
    return v;
  };
  const PlayerState& me = s.players[self];
  GoalieWorld w;
  w.self.pos = mirror(me.pos);
  w.self.vel = mirror(me.vel);
  w.self.body_deg = angle_norm(me.body_deg + 180.0);
  w.self.stamina = me.stamina;
  w.self.effort = me.effort;
  w.self.recovery = me.recovery;
  w.self.capacity = me.capacity;
  w.self.frozen = me.tackle_cycles > 0;
  w.self.goalie = me.goalie;
  w.ball_pos = mirror(s.ball.pos);
  w.ball_vel = mirror(s.ball.vel);
  w.player_rand = server_noise ? kPlayerRand : 0.0;
  w.ball_rand = server_noise ? kBallRand : 0.0;
  for (int i = 0; i < s.num_players; ++i) {
    const PlayerState& p = s.players[i];
    if (i == self) {
      continue;
    }
    if (p.team == me.team) {
      if (w.num_teammates < GoalieWorld::kMaxTeammates) {
        w.teammates[w.num_teammates++] = view(p);
      }
    } else if (w.num_opponents < GoalieWorld::kMaxOpponents) {
      w.opponents[w.num_opponents++] = view(p);
    }
  }
  // Nearest to the ball first (WorldModel::teammatesFromBall, opponentsFromBall).
  agent2d::sort_from_ball(std::span(w.teammates).first(static_cast<size_t>(w.num_teammates)), w.ball_pos);
  agent2d::sort_from_ball(std::span(w.opponents).first(static_cast<size_t>(w.num_opponents)), w.ball_pos);
  w.finish();
  return w;
}

agent2d::GoalieWorld goalie_world(const SoccerState& s, int goalie, bool server_noise) {
  GoalieWorld w = defense_world(s, goalie, server_noise);
  const PlayerState& me = s.players[goalie];
  w.since_catch = me.since_catch;
  w.catch_mode = me.caught;
  return w;
}

GoalieCommand decide_goalie(const SoccerState& s, int goalie, bool server_noise) {
  const GoalieWorld w = goalie_world(s, goalie, server_noise);
  if (w.self.frozen) {
    return {};  // librcsc refuses every body command while the tackle freezes the player
  }
  if (w.catch_mode) {
    // Not play_on: SamplePlayer runs Bhv_SetPlay, which gives the goalie Bhv_GoalieFreeKick.
    // Without the ball kickable that is Bhv_GoalieBasicMove, with no catch and no chase.
    if (w.self_kickable) {
      // Bhv_GoalieFreeKick::doWait (its first two cycles): face the field. Its later moves
      // and kick are not carried over: HFO's referee ends the episode when the ball is
      // within the goalie's kickable area, so in play this branch is reached only from a
      // state set by hand.
      Command out;
      const double line_x = kOurPenaltyLineX;
      const Vec2 face = w.self.pos.x > line_x - kBallSize - kPlayerSize - 0.5 ? Vec2{line_x - 1.0, 0.0} : Vec2{};
      agent2d::body_turn_to_point(w, face, 1, &out);
      return out;
    }
    InterceptTable table;
    agent2d::predict_ball_and_opponents(w, &table);
    Command out;
    basic_move(Context{w, table, &out});
    return out;
  }
  // RoleGoalie::execute.
  if (w.since_catch > kCatchBanCycles && w.ball_dist_from_self < agent2d::kCatchableArea - 0.05 &&
      in_catch_area(w.ball_pos)) {
    // ActionEffector::setCatch: the ball's direction plus the angle of the rectangle's diagonal.
    const double diagonal = std::atan2(kCatchableAreaWidth * 0.5, kCatchableAreaLength) * kRadToDeg;
    return {GoalieCommand::Kind::kCatch, angle_norm(w.ball_angle_from_self_deg - w.self.body_deg + diagonal), 0.0};
  }
  Command out;
  if (w.self_kickable) {
    // RoleGoalie::doKick calls Body_ClearBall. HFO's referee ends the episode before the
    // ball comes this close, so this is reached only from a state set by hand; a full-power
    // kick straight away from the goal stands in for the clearing kick there.
    const double dir = angle_norm(th_deg(w.ball_pos - Vec2{-kPitchHalfLength, 0.0}) - w.self.body_deg);
    return {GoalieCommand::Kind::kKick, kMaxKickPower, dir};
  }
  InterceptTable table;
  agent2d::predict_ball_and_opponents(w, &table);
  const Context c{w, table, &out};
  if (ball_chase_situation(c)) {
    chase_ball(c);
  } else {
    basic_move(c);
  }
  return out;
}

const char* goalie_command_name(GoalieCommand::Kind kind) {
  switch (kind) {
    case GoalieCommand::Kind::kDash: return "DASH";
    case GoalieCommand::Kind::kTurn: return "TURN";
    case GoalieCommand::Kind::kCatch: return "CATCH";
    case GoalieCommand::Kind::kKick: return "KICK";
    case GoalieCommand::Kind::kTackle: return "TACKLE";
    case GoalieCommand::Kind::kNone: return "NONE";
  }
  return "NONE";
}

}  // namespace pamdp::hfo
