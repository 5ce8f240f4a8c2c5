// The goalie's own ways to the ball: librcsc's SelfInterceptV13 (rcsc/player/self_intercept_v13.cpp,
// librcsc d222758) as agent2d's goalie runs it with full state, and the reach cycles
// InterceptTable::predictSelf takes from it. Our own code; the rules and the constants are
// librcsc's, named after the function they come from. The goalie never kicks in HFO, so the
// last kicker is never its own side: the "goalie mode" (catchable area as the control area inside
// its penalty area) depends on the ball's place only. With SelfView::goalie false it is a field
// player's (agent2d's field defenders): no goalie mode, and back dashes only within 4 cycles.
#include <algorithm>
#include <cmath>

#include "envs/hfo/client_effector.hpp"
#include "envs/hfo/goalie_world.hpp"

namespace pamdp::hfo::agent2d {
namespace {

constexpr int kMaxShortStep = 5;                              // SelfInterceptV13::MAX_SHORT_STEP
constexpr double kMinTurnThr = 12.5;                          // MIN_TURN_THR
constexpr double kBackDashThrAngle = 100.0;                   // BACK_DASH_THR_ANGLE
constexpr double kControlAreaBuf = 0.15;                      // control_area_buf (2009-07-03)
constexpr double kRecoverDecThrValue = kRecoverDecThreshold;  // recover_dec_thr x stamina_max

Vec2 from_polar(double r, double deg) {
  return polar(r, deg * kDegToRad);
}
Vec2 inertia_point(Vec2 pos, Vec2 vel, int n) {
  return pos + vel * ((1.0 - player_decay_pow(n)) / (1.0 - kPlayerDecay));
}
// PlayerType::normalizeAccel(velocity, accel vector).
void normalize_accel(Vec2 vel, Vec2* accel) {
  if ((vel + *accel).r2() > kPlayerSpeedMax * kPlayerSpeedMax + 0.0001) {
    const Vec2 rel_vel = rotate_deg(vel, -th_deg(*accel));
    const double max_dash_x = std::sqrt(kPlayerSpeedMax * kPlayerSpeedMax - rel_vel.y * rel_vel.y);
    const double len = max_dash_x - rel_vel.x;
    const double r = accel->r();
    if (r > 0.0) {
      *accel = *accel * (len / r);
    }
  }
}
// PlayerType::canOverSpeedMax.
bool can_over_speed_max(double dash_power, double effort) {
  return std::fabs(dash_power) * kDashPowerRate * effort > kPlayerSpeedMax * (1.0 - kPlayerDecay);
}
// Segment2D::dist(point).
double segment_dist(Vec2 a, Vec2 b, Vec2 p) {
  const Vec2 d = b - a;
  const double len2 = d.r2();
  if (len2 <= 0.0) {
    return (p - a).r();
  }
  const double t = (p - a).dot(d) / len2;
  if (t <= 0.0) {
    return (p - a).r();
  }
  if (t >= 1.0) {
    return (p - b).r();
  }
  return (p - (a + d * t)).r();
}
// Line2D(origin, angle).dist(point).
double line_dist(Vec2 origin, double dir_deg, Vec2 p) {
  const double a = -std::sin(dir_deg * kDegToRad);
  const double b = std::cos(dir_deg * kDegToRad);
  const double c = -a * origin.x - b * origin.y;
  return std::fabs((a * p.x + b * p.y + c) / std::sqrt(a * a + b * b));
}
// Line2D(p1, p2).projection(p).
Vec2 line_projection(Vec2 p1, Vec2 p2, Vec2 p) {
  const Vec2 d = p2 - p1;
  const double len2 = d.r2();
  if (len2 <= 0.0) {
    return p1;
  }
  return p1 + d * ((p - p1).dot(d) / len2);
}

class SelfIntercept {
 public:
  SelfIntercept(const GoalieWorld& w, InterceptTable* t) : w_(w), t_(t) {}

  void predict(int max_cycle) {
    if (t_->ball_cache_size < 2) {
      return;
    }
    const bool save_recovery = w_.self.capacity != 0.0;
    predict_one_step();
    predict_short_step(max_cycle, save_recovery);
    predict_long_step(max_cycle, save_recovery);
    predict_long_step(max_cycle, false);
    // std::sort with InterceptInfo::Cmp (reach cycle, then turn cycle), as librcsc: with more
    // than 16 entries libstdc++'s introsort reorders equal ones, and Body_Intercept2009 keeps the
    // first of equal scores, so a stable sort can pick another way. std::sort allocates nothing.
    std::sort(t_->self_cache.begin(), t_->self_cache.begin() + t_->self_cache_size,
              [](const InterceptInfo& a, const InterceptInfo& b) {
                return a.reach_cycle() < b.reach_cycle() ||
                       (a.reach_cycle() == b.reach_cycle() && a.turn_cycle < b.turn_cycle);
              });
  }

 private:
  [[nodiscard]] double dash_rate() const { return w_.self.effort * kDashPowerRate; }

  // A goalie's control area is its catchable area inside its penalty area; a field player's is
  // always its kickable area (SelfInterceptV13: self().goalie() and the last kicker's side).
  [[nodiscard]] double control_area_at(Vec2 ball, double x_line, double half_width) const {
    return (w_.self.goalie && ball.x < x_line && std::fabs(ball.y) < half_width) ? kCatchableArea : kKickableArea;
  }

  void push(const InterceptInfo& info) {
    if (t_->self_cache_size < InterceptTable::kMaxSelfCache) {
      t_->self_cache[static_cast<size_t>(t_->self_cache_size++)] = info;
    }
  }

  static InterceptInfo make(InterceptInfo::Mode mode, int n_turn, int n_dash, double power, double dir, Vec2 pos,
                            double ball_dist, double stamina) {
    InterceptInfo i;
    i.mode = mode;
    i.turn_cycle = n_turn;
    i.dash_cycle = n_dash;
    i.dash_power = power;
    i.dash_angle_deg = dir;
    i.self_pos = pos;
    i.ball_dist = ball_dist;
    i.stamina = stamina;
    return i;
  }

  // ---- predictOneStep ----
  void predict_one_step() {
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const double control = control_area_at(ball_next, kOurPenaltyLineX, kPenaltyBoxHalfWidth);
    if (w_.ball_dist_from_self > kBallSpeedMax + kRealSpeedMax + control) {
      return;
    }
    if (predict_no_dash()) {
      return;
    }
    predict_one_dash();
  }

  bool predict_no_dash() {
    const Vec2 my_next = w_.self.pos + w_.self.vel;
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const bool goalie_mode =
        w_.self.goalie && ball_next.x < kOurPenaltyLineX && std::fabs(ball_next.y) < kPenaltyBoxHalfWidth;
    const double control = goalie_mode ? kCatchableArea : kKickableArea;
    const Vec2 next_ball_rel = rotate_deg(ball_next - my_next, -w_.self.body_deg);
    const double ball_noise = w_.ball_vel.r() * w_.ball_rand;
    const double next_ball_dist = next_ball_rel.r();
    if (next_ball_dist > control - 0.15 - ball_noise) {
      return false;
    }
    if (!goalie_mode && next_ball_dist > kPlayerSize + kBallSize) {
      // PlayerType::kickRate at the next ball: a kick that cannot stop the ball is no control.
      const double dir_diff = std::fabs(th_deg(next_ball_rel));
      const double rate = kKickPowerRate * (1.0 - 0.25 * dir_diff / 180.0 -
                                            0.25 * (next_ball_dist - kPlayerSize - kBallSize) / kKickableMargin);
      const Vec2 next_ball_vel = w_.ball_vel * kBallDecay;
      if (kMaxKickPower * rate <= next_ball_vel.r() * kBallDecay * 1.1) {
        return false;
      }
    }
    StaminaModel sm = stamina_of(w_.self);
    sm.wait();
    push(make(InterceptInfo::Mode::kNormal, 1, 0, 0.0, 0.0, my_next, next_ball_dist, sm.stamina));
    return true;
  }

  void predict_one_dash() {
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const double control = control_area_at(ball_next, kOurPenaltyLineX, kPenaltyBoxHalfWidth);
    // dash_angle_step max(5, 45) over [-180, 180): -180, -135, ..., 135.
    const double step = std::max(5.0, kDashAngleStep);
    const double min_dir = step * static_cast<int>(-180.0 / step);
    const double max_dir = step * static_cast<int>(180.0 / step) - 1.0;
    std::array<InterceptInfo, 16> tmp{};
    int n_tmp = 0;
    for (double dir = min_dir; dir < max_dir; dir += step) {
      const double dash_angle = angle_norm(w_.self.body_deg + discretize_dash_dir(clamp(dir, -180.0, 180.0)));
      const double rate = dash_rate() * dash_dir_rate(dir);
      const double forward_power = clamp(w_.self.stamina - kRecoverDecThrValue - 1.0, 0.0, kMaxDashPower);
      const double back_power = clamp((w_.self.stamina - kRecoverDecThrValue - 1.0) * -0.5, kMinDashPower, 0.0);
      Vec2 fwd = from_polar(forward_power * rate, dash_angle);
      Vec2 back = from_polar(back_power * rate, dash_angle);
      normalize_accel(w_.self.vel, &fwd);
      normalize_accel(w_.self.vel, &back);
      InterceptInfo info;
      if (one_dash_adjust(dash_angle, fwd, back, control, &info)) {
        tmp[static_cast<size_t>(n_tmp++)] = info;
        continue;
      }
      if (std::fabs(forward_power - kMaxDashPower) < 1.0 && std::fabs(back_power - kMinDashPower) < 1.0) {
        continue;
      }
      fwd = from_polar(kMaxDashPower * rate, dash_angle);
      back = from_polar(kMinDashPower * rate, dash_angle);
      normalize_accel(w_.self.vel, &fwd);
      normalize_accel(w_.self.vel, &back);
      if (one_dash_adjust(dash_angle, fwd, back, control, &info)) {
        tmp[static_cast<size_t>(n_tmp++)] = info;
      }
    }
    if (n_tmp == 0) {
      return;
    }
    const double safety_ball_dist =
        std::max(control - 0.2 - w_.ball_vel.r() * w_.ball_rand, kPlayerSize + kBallSize + kKickableMargin * 0.4);
    const InterceptInfo* best = &tmp[0];
    for (int i = 1; i < n_tmp; ++i) {
      const InterceptInfo* it = &tmp[static_cast<size_t>(i)];
      if (best->ball_dist < safety_ball_dist && it->ball_dist < safety_ball_dist) {
        if (best->stamina < it->stamina) {
          best = it;
        }
      } else if (best->ball_dist > it->ball_dist ||
                 (std::fabs(best->ball_dist - it->ball_dist) < 0.001 && best->stamina < it->stamina)) {
        best = it;
      }
    }
    push(*best);
  }

  bool one_dash_adjust(double dash_angle, Vec2 max_forward_accel, Vec2 max_back_accel, double control,
                       InterceptInfo* info) const {
    const double control_buf = control - 0.075;
    const double dash_dir = angle_norm(dash_angle - w_.self.body_deg);
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const Vec2 self_next = w_.self.pos + w_.self.vel;
    const Vec2 ball_rel = rotate_deg(ball_next - self_next, -dash_angle);
    const Vec2 forward_rel = rotate_deg(max_forward_accel, -dash_angle);
    const Vec2 back_rel = rotate_deg(max_back_accel, -dash_angle);
    const double rate = dash_rate() * dash_dir_rate(dash_dir);
    if (std::fabs(ball_rel.y) > control_buf || segment_dist(forward_rel, back_rel, ball_rel) > control_buf) {
      return false;
    }
    double dash_power = -1000.0;
    if (back_rel.x < ball_rel.x && ball_rel.x < forward_rel.x) {
      dash_power = one_step_dash_power(ball_rel, dash_angle, forward_rel.x, back_rel.x);
    }
    if (dash_power < -999.0 && forward_rel.x < ball_rel.x && (ball_rel - forward_rel).r() < control_buf) {
      dash_power = forward_rel.x / rate;
    }
    if (dash_power < -999.0 && ball_rel.x < back_rel.x && (ball_rel - back_rel).r() < control_buf) {
      dash_power = back_rel.x / rate;
    }
    if (dash_power < -999.0 && back_rel.x < ball_rel.x && ball_rel.x < forward_rel.x) {
      dash_power = ball_rel.x / rate;
    }
    if (dash_power < -999.0) {
      return false;
    }
    InterceptInfo::Mode mode = InterceptInfo::Mode::kNormal;
    const Vec2 accel = from_polar(dash_power * rate, dash_angle);
    const Vec2 my_vel = w_.self.vel + accel;
    const Vec2 my_pos = w_.self.pos + my_vel;
    StaminaModel sm = stamina_of(w_.self);
    sm.dash(dash_power);
    if (sm.stamina < kRecoverDecThrValue && !sm.capacity_is_empty()) {
      mode = InterceptInfo::Mode::kExhaust;
    }
    *info = make(mode, 0, 1, dash_power, dash_dir, my_pos, (my_pos - ball_next).r(), sm.stamina);
    return true;
  }

  // getOneStepDashPower; note that librcsc passes the global dash angle where it reads a
  // relative direction for the dash rate, which we keep. ServerParam::dashDirRate clamps and
  // discretizes its argument first (common/server_param.cpp), which matters for this angle.
  [[nodiscard]] double one_step_dash_power(Vec2 next_ball_rel, double dash_angle, double max_forward_accel_x,
                                           double max_back_accel_x) const {
    const double rate = dash_rate() * dash_dir_rate(discretize_dash_dir(clamp(dash_angle, -180.0, 180.0)));
    const double best_forward = kPlayerSize + 0.5 * kKickableMargin + kBallSize;
    const double best_backward = kPlayerSize + 0.3 * kKickableMargin + kBallSize;
    if (std::fabs(next_ball_rel.y) > best_forward) {
      return next_ball_rel.x / rate;
    }
    const double forward_trap = next_ball_rel.x - std::sqrt(std::pow(best_forward, 2) - std::pow(next_ball_rel.y, 2));
    const double backward_trap = next_ball_rel.x + std::sqrt(std::pow(best_backward, 2) - std::pow(next_ball_rel.y, 2));
    double min_power = 10000.0;
    const double x_step = (backward_trap - forward_trap) / 5.0;
    if (x_step > 0.0) {
      for (double accel_x = forward_trap; accel_x < backward_trap + 0.01; accel_x += x_step) {
        if ((accel_x >= 0.0 && max_forward_accel_x > accel_x) || (accel_x < 0.0 && max_back_accel_x < accel_x)) {
          const double power = accel_x / rate;
          if (std::fabs(power) < std::fabs(min_power)) {
            min_power = power;
          }
        }
      }
    }
    return min_power < 1000.0 ? min_power : -1000.0;
  }

  // ---- predictShortStep ----
  void predict_short_step(int max_cycle, bool save_recovery) {
    const int max_loop = std::min(kMaxShortStep, max_cycle);
    const double pen_area_x = kOurPenaltyLineX - 0.5;
    const double pen_area_y = kPenaltyBoxHalfWidth - 0.5;
    const Vec2 ball_to_self = rotate_deg(w_.self.pos - w_.ball_pos, -th_deg(w_.ball_vel));
    int min_cycle = static_cast<int>(std::ceil((std::fabs(ball_to_self.y) - kKickableArea) / kRealSpeedMax));
    if (min_cycle >= max_loop) {
      return;
    }
    min_cycle = std::max(min_cycle, 2);
    Vec2 ball_pos = ball_inertia_point(w_, min_cycle - 1);
    Vec2 ball_vel = w_.ball_vel * ball_decay_pow(min_cycle - 1);
    for (int cycle = min_cycle; cycle <= max_loop; ++cycle) {
      n_tmp_ = 0;
      ball_pos += ball_vel;
      ball_vel *= kBallDecay;
      const double control = control_area_at(ball_pos, pen_area_x, pen_area_y);
      if (std::pow(control + kRealSpeedMax * cycle, 2) < (w_.self.pos - ball_pos).r2()) {
        continue;
      }
      turn_dash_short(cycle, ball_pos, control, save_recovery, false, std::max(0.1, control - 0.4));
      turn_dash_short(cycle, ball_pos, control, save_recovery, false, std::max(0.1, control - kControlAreaBuf));
      turn_dash_short(cycle, ball_pos, control, save_recovery, true, std::max(0.1, control - 0.4));
      turn_dash_short(cycle, ball_pos, control, save_recovery, true, control - kControlAreaBuf);
      if (cycle <= 2) {
        omni_dash_short(cycle, ball_pos, control, save_recovery, false);
      }
      if (n_tmp_ == 0) {
        continue;
      }
      const double safety_ball_dist = std::max(control - 0.2 - (w_.ball_pos - ball_pos).r() * w_.ball_rand,
                                               kPlayerSize + kBallSize + kKickableMargin * 0.4);
      const InterceptInfo* best = &tmp_[0];
      for (int i = 1; i < n_tmp_; ++i) {
        const InterceptInfo* it = &tmp_[static_cast<size_t>(i)];
        if (best->ball_dist < safety_ball_dist && it->ball_dist < safety_ball_dist) {
          if (best->turn_cycle > it->turn_cycle) {
            best = it;
          } else if (best->turn_cycle == it->turn_cycle && best->stamina < it->stamina) {
            best = it;
          }
        } else if (best->turn_cycle >= it->turn_cycle &&
                   (best->ball_dist > it->ball_dist ||
                    (std::fabs(best->ball_dist - it->ball_dist) < 0.001 && best->stamina < it->stamina))) {
          best = it;
        }
      }
      push(*best);
    }
  }

  void push_tmp(const InterceptInfo& info) {
    if (n_tmp_ < static_cast<int>(tmp_.size())) {
      tmp_[static_cast<size_t>(n_tmp_++)] = info;
    }
  }

  void turn_dash_short(int cycle, Vec2 ball_pos, double control, bool save_recovery, bool back_dash,
                       double turn_margin_control_area) {
    double dash_angle = w_.self.body_deg;
    const int n_turn = turn_cycle_short(cycle, ball_pos, back_dash, turn_margin_control_area, &dash_angle);
    if (n_turn > cycle) {
      return;
    }
    dash_cycle_short(cycle, n_turn, ball_pos, dash_angle, control, save_recovery, back_dash);
  }

  int turn_cycle_short(int cycle, Vec2 ball_pos, bool back_dash, double dist_thr, double* result_dash_angle) const {
    const Vec2 inertia = self_inertia_point(w_, cycle);
    const double target_dist = (ball_pos - inertia).r();
    const double target_angle = th_deg(ball_pos - inertia);
    const double body_angle = back_dash ? angle_norm(w_.self.body_deg + 180.0) : w_.self.body_deg;
    double angle_diff = std::fabs(angle_norm(target_angle - body_angle));
    double turn_margin = 180.0;
    if (dist_thr < target_dist) {
      turn_margin = std::max(kMinTurnThr, std::asin(dist_thr / target_dist) * kRadToDeg);
    }
    int n_turn = 0;
    if (angle_diff > turn_margin) {
      double speed = w_.self.vel.r();
      while (angle_diff > turn_margin) {
        angle_diff -= kMaxMoment / (1.0 + kInertiaMoment * speed);
        speed *= kPlayerDecay;
        ++n_turn;
      }
    }
    *result_dash_angle = body_angle;
    if (n_turn > 0) {
      angle_diff = std::max(0.0, angle_diff);
      *result_dash_angle = angle_norm(target_angle - body_angle) > 0.0 ? angle_norm(target_angle - angle_diff)
                                                                       : angle_norm(target_angle + angle_diff);
    }
    return n_turn;
  }

  void dash_cycle_short(int cycle, int n_turn, Vec2 ball_pos, double dash_angle, double control, bool save_recovery,
                        bool back_dash) {
    const double recover_dec_thr = kRecoverDecThrValue + 1.0;
    const int max_dash = cycle - n_turn;
    const Vec2 my_inertia = self_inertia_point(w_, cycle);
    Vec2 my_pos = self_inertia_point(w_, n_turn);
    Vec2 my_vel = w_.self.vel * player_decay_pow(n_turn);
    StaminaModel sm = stamina_of(w_.self);
    sm.waits(n_turn);
    if ((my_inertia - ball_pos).r2() < std::pow(control - kControlAreaBuf, 2)) {
      StaminaModel tmp = sm;
      tmp.waits(cycle - n_turn);
      push_tmp(make(InterceptInfo::Mode::kNormal, n_turn, cycle - n_turn, 0.0, 0.0, my_inertia,
                    (my_inertia - ball_pos).r(), tmp.stamina));
    }
    const double target_angle = th_deg(ball_pos - my_inertia);
    if (std::fabs(angle_norm(target_angle - dash_angle)) > 90.0) {
      return;
    }
    const Vec2 accel_unit = from_polar(1.0, dash_angle);
    double first_dash_power = 0.0;
    for (int n_dash = 1; n_dash <= max_dash; ++n_dash) {
      const Vec2 ball_rel = rotate_deg(ball_pos - my_pos, -dash_angle);
      const double first_speed = first_term_geom_series(ball_rel.x, kPlayerDecay, max_dash - n_dash + 1);
      const Vec2 rel_vel = rotate_deg(my_vel, -dash_angle);
      const double required_accel = first_speed - rel_vel.x;
      double dash_power = required_accel / (kDashPowerRate * sm.effort);
      if (back_dash) {
        dash_power = -dash_power;
      }
      const double available = save_recovery ? std::max(0.0, sm.stamina - recover_dec_thr) : sm.stamina + kExtraStamina;
      if (back_dash) {
        dash_power = clamp(dash_power, kMinDashPower, 0.0);
        dash_power = std::max(dash_power, available * -0.5);
      } else {
        dash_power = clamp(dash_power, 0.0, kMaxDashPower);
        dash_power = std::min(available, dash_power);
      }
      if (n_dash == 1) {
        first_dash_power = dash_power;
      }
      const double accel_mag = std::fabs(dash_power * kDashPowerRate * sm.effort);
      my_vel += accel_unit * accel_mag;
      my_pos += my_vel;
      my_vel *= kPlayerDecay;
      sm.dash(dash_power);
    }
    if ((my_pos - ball_pos).r2() < std::pow(control - kControlAreaBuf, 2) ||
        (w_.self.pos - my_pos).r2() > (w_.self.pos - ball_pos).r2()) {
      const InterceptInfo::Mode mode = sm.stamina < kRecoverDecThrValue && !sm.capacity_is_empty()
                                           ? InterceptInfo::Mode::kExhaust
                                           : InterceptInfo::Mode::kNormal;
      push_tmp(make(mode, n_turn, cycle - n_turn, first_dash_power, 0.0, my_pos, (my_pos - ball_pos).r(), sm.stamina));
    }
  }

  void omni_dash_short(int cycle, Vec2 ball_pos, double control, bool save_recovery, bool back_dash) {
    const double body_angle = back_dash ? angle_norm(w_.self.body_deg + 180.0) : w_.self.body_deg;
    const Vec2 my_inertia = self_inertia_point(w_, cycle);
    if (line_dist(ball_pos, body_angle, my_inertia) < control - 0.4) {
      return;
    }
    const double recover_dec_thr = kRecoverDecThrValue + 1.0;
    const double step = std::max(15.0, kDashAngleStep);
    const double min_dir = step * static_cast<int>(-180.0 / step);
    const double max_dir = step * static_cast<int>(180.0 / step) - 1.0;
    const double target_angle = th_deg(ball_pos - my_inertia);
    for (double dir = min_dir; dir < max_dir; dir += step) {
      if (std::fabs(dir) < 1.0) {
        continue;
      }
      const double dash_angle = angle_norm(body_angle + discretize_dash_dir(clamp(dir, -180.0, 180.0)));
      if (std::fabs(angle_norm(dash_angle - target_angle)) > 91.0) {
        continue;
      }
      double first_dash_power = 0.0;
      Vec2 my_pos = w_.self.pos;
      Vec2 my_vel = w_.self.vel;
      StaminaModel sm = stamina_of(w_.self);
      const int n_omni = adjust_omni_dash(cycle, ball_pos, control, save_recovery, back_dash, dir, &my_pos, &my_vel,
                                          &sm, &first_dash_power);
      if (n_omni <= 0) {
        continue;
      }
      {
        const Vec2 inertia = inertia_point(my_pos, my_vel, cycle - n_omni);
        const Vec2 target_rel = rotate_deg(ball_pos - inertia, -body_angle);
        if ((back_dash && target_rel.x > 0.0) || (!back_dash && target_rel.x < 0.0)) {
          continue;
        }
      }
      const Vec2 body_unit = from_polar(1.0, body_angle);
      for (int n_dash = n_omni + 1; n_dash <= cycle; ++n_dash) {
        const double first_speed =
            first_term_geom_series(rotate_deg(ball_pos - my_pos, -body_angle).x, kPlayerDecay, cycle - n_dash + 1);
        const Vec2 rel_vel = rotate_deg(my_vel, -body_angle);
        const double required_accel = first_speed - rel_vel.x;
        double dash_power = required_accel / (kDashPowerRate * sm.effort);
        if (back_dash) {
          dash_power = -dash_power;
        }
        const double available =
            save_recovery ? std::max(0.0, sm.stamina - recover_dec_thr) : sm.stamina + kExtraStamina;
        if (back_dash) {
          dash_power = clamp(dash_power, kMinDashPower, 0.0);
          dash_power = std::max(dash_power, available * -0.5);
        } else {
          dash_power = clamp(dash_power, 0.0, kMaxDashPower);
          dash_power = std::min(available, dash_power);
        }
        const double accel_mag = std::fabs(dash_power) * kDashPowerRate * sm.effort;
        my_vel += body_unit * accel_mag;
        my_pos += my_vel;
        my_vel *= kPlayerDecay;
        sm.dash(dash_power);
      }
      const Vec2 my_move = my_pos - w_.self.pos;
      if ((my_pos - ball_pos).r2() < std::pow(control - kControlAreaBuf, 2) ||
          my_move.r() > std::fabs(rotate_deg(ball_pos - w_.self.pos, -th_deg(my_move)).x)) {
        const InterceptInfo::Mode mode = sm.recovery < w_.self.recovery && !sm.capacity_is_empty()
                                             ? InterceptInfo::Mode::kExhaust
                                             : InterceptInfo::Mode::kNormal;
        push_tmp(make(mode, 0, cycle, first_dash_power, dir, my_pos, (my_pos - ball_pos).r(), sm.stamina));
      }
    }
  }

  int adjust_omni_dash(int cycle, Vec2 ball_pos, double control, bool save_recovery, bool back_dash,
                       double dash_rel_dir, Vec2* my_pos, Vec2* my_vel, StaminaModel* sm,
                       double* first_dash_power) const {
    const double recover_dec_thr = kRecoverDecThrValue + 1.0;
    const int max_omni = std::min(2, cycle);
    const double body_angle = back_dash ? angle_norm(w_.self.body_deg + 180.0) : w_.self.body_deg;
    const Vec2 my_inertia = self_inertia_point(w_, cycle);
    if (line_dist(ball_pos, body_angle, my_inertia) < control - 0.4) {
      *first_dash_power = 0.0;
      return 0;
    }
    const double dash_angle = angle_norm(body_angle + discretize_dash_dir(clamp(dash_rel_dir, -180.0, 180.0)));
    const Vec2 accel_unit = from_polar(1.0, dash_angle);
    const double dir_rate = dash_dir_rate(dash_rel_dir);
    for (int n = 1; n <= max_omni; ++n) {
      const double first_speed =
          first_term_geom_series(std::max(0.0, line_dist(ball_pos, body_angle, *my_pos)), kPlayerDecay, cycle - n + 1);
      const Vec2 rel_vel = rotate_deg(*my_vel, -dash_angle);
      const double required_accel = first_speed - rel_vel.x;
      if (std::fabs(required_accel) < 0.01) {
        return n - 1;
      }
      double dash_power = required_accel / (kDashPowerRate * sm->effort * dir_rate);
      const double available =
          save_recovery ? std::max(0.0, sm->stamina - recover_dec_thr) : sm->stamina + kExtraStamina;
      if (back_dash) {
        dash_power = clamp(dash_power, kMinDashPower, 0.0);
        dash_power = std::max(dash_power, available * -0.5);
      } else {
        dash_power = clamp(dash_power, 0.0, kMaxDashPower);
        dash_power = std::min(available, dash_power);
      }
      if (n == 1) {
        *first_dash_power = dash_power;
      }
      const double accel_mag = std::fabs(dash_power) * kDashPowerRate * sm->effort * dir_rate;
      *my_vel += accel_unit * accel_mag;
      *my_pos += *my_vel;
      *my_vel *= kPlayerDecay;
      sm->dash(dash_power);
      const Vec2 inertia = inertia_point(*my_pos, *my_vel, cycle - n);
      if (line_dist(ball_pos, body_angle, inertia) < control - kControlAreaBuf) {
        return n;
      }
    }
    return -1;
  }

  // ---- predictLongStep ----
  void predict_long_step(int max_cycle, bool save_recovery) {
    const Vec2 ball_to_self = rotate_deg(w_.self.pos - w_.ball_pos, -th_deg(w_.ball_vel));
    int start_cycle = static_cast<int>(std::ceil((std::fabs(ball_to_self.y) - kKickableArea - 0.2) / kRealSpeedMax));
    if (start_cycle <= kMaxShortStep) {
      start_cycle = kMaxShortStep + 1;
    }
    Vec2 ball_pos = ball_inertia_point(w_, start_cycle - 1);
    Vec2 ball_vel = w_.ball_vel * ball_decay_pow(start_cycle - 1);
    bool found = false;
    int max_loop = max_cycle;
    for (int cycle = start_cycle; cycle < max_loop; ++cycle) {
      ball_pos += ball_vel;
      ball_vel *= kBallDecay;
      if (std::fabs(ball_pos.x) > kPitchHalfLength + 10.0 || std::fabs(ball_pos.y) > kPitchHalfWidth + 10.0) {
        break;
      }
      const double control = control_area_at(ball_pos, kOurPenaltyLineX, kPenaltyBoxHalfWidth);
      if (control + kRealSpeedMax * cycle < (w_.self.pos - ball_pos).r()) {
        continue;
      }
      if (can_reach_after_turn_dash(cycle, ball_pos, control, save_recovery)) {
        if (!found) {
          max_loop = std::min(max_cycle, cycle + 10);
        }
        found = true;
      }
    }
    if (!found && save_recovery) {
      predict_final(max_cycle);
    }
    if (t_->self_cache_size == 0) {
      predict_final(max_cycle);
    }
  }

  void predict_final(int max_cycle) {
    const Vec2 my_final = self_inertia_point(w_, 100);
    const Vec2 ball_final = ball_inertia_point(w_, 100);
    const bool goalie_mode =
        w_.self.goalie && ball_final.x < kOurPenaltyLineX && std::fabs(ball_final.y) < kPenaltyBoxHalfWidth;
    const double control = goalie_mode ? kCatchableArea - 0.15 : kKickableArea;
    double dash_angle = w_.self.body_deg;
    bool back_dash = false;
    const int n_turn = predict_turn_cycle(100, ball_final, control, &dash_angle, &back_dash);
    const double dash_dist = (my_final - ball_final).r() - control;
    int n_dash = cycles_to_reach(dash_dist);
    if (max_cycle > n_turn + n_dash) {
      n_dash = max_cycle - n_turn;
    }
    StaminaModel sm = stamina_of(w_.self);
    sm.waits(n_turn);
    sm.dashes(n_dash, kMaxDashPower);
    push(make(InterceptInfo::Mode::kNormal, n_turn, n_dash, kMaxDashPower, 0.0, ball_final, 0.0, sm.stamina));
  }

  bool can_reach_after_turn_dash(int cycle, Vec2 ball_pos, double control, bool save_recovery) {
    double dash_angle = w_.self.body_deg;
    bool back_dash = false;
    const int n_turn = predict_turn_cycle(cycle, ball_pos, control, &dash_angle, &back_dash);
    if (n_turn > cycle) {
      return false;
    }
    return can_reach_after_dash(n_turn, std::max(0, cycle - n_turn), ball_pos, control, save_recovery, dash_angle,
                                back_dash);
  }

  int predict_turn_cycle(int cycle, Vec2 ball_pos, double control, double* dash_angle, bool* back_dash) const {
    const Vec2 inertia = self_inertia_point(w_, cycle);
    const Vec2 target_rel = ball_pos - inertia;
    const double target_angle = th_deg(target_rel);
    double angle_diff = angle_norm(target_angle - *dash_angle);
    const bool diff_is_positive = angle_diff > 0.0;
    angle_diff = std::fabs(angle_diff);
    const double target_dist = target_rel.r();
    double turn_margin = 180.0;
    const double control_buf = std::max(0.5, control - 0.25);
    if (control_buf < target_dist) {
      turn_margin = std::asin(control_buf / target_dist) * kRadToDeg;
    }
    turn_margin = std::max(turn_margin, kMinTurnThr);
    if (can_back_dash_chase(cycle, angle_diff)) {
      *back_dash = true;
      *dash_angle = angle_norm(*dash_angle + 180.0);
      angle_diff = 180.0 - angle_diff;
    }
    const double max_moment = kMaxMoment * (1.0 - w_.player_rand);
    double speed = w_.self.vel.r();
    int n_turn = 0;
    while (angle_diff > turn_margin) {
      angle_diff -= max_moment / (1.0 + kInertiaMoment * speed);
      speed *= kPlayerDecay;
      ++n_turn;
    }
    if (n_turn > 0) {
      angle_diff = std::max(0.0, angle_diff);
      *dash_angle = angle_norm(target_angle + (diff_is_positive ? angle_diff : -angle_diff));
    }
    return n_turn;
  }

  [[nodiscard]] bool can_back_dash_chase(int cycle, double angle_diff) const {
    if (angle_diff < kBackDashThrAngle) {
      return false;
    }
    if (cycle >= 5) {  // a goalie while the opponents kicked last; a field player never
      if (!w_.self.goalie || cycle >= 15) {
        return false;
      }
      const Vec2 goal{-kPitchHalfLength, 0.0};
      if ((goal - ball_inertia_point(w_, cycle)).r() > 21.0) {
        return false;
      }
    }
    const double total_consume = -kMinDashPower * 2.0 * cycle;
    const double total_recover = kStaminaIncMax * w_.self.recovery * (cycle - 1);
    const double result = w_.self.stamina - total_consume + total_recover;
    return result >= kRecoverDecThrValue + 205.0;
  }

  bool can_reach_after_dash(int n_turn, int n_dash, Vec2 ball_pos, double control, bool save_recovery,
                            double dash_angle, bool back_dash) {
    const double player_noise_rate = 1.0 - w_.player_rand * 0.01;
    const Vec2 my_inertia = self_inertia_point(w_, n_turn + n_dash);
    const double recover_dec_thr = kRecoverDecThreshold;
    const Vec2 ball_rel = rotate_deg(ball_pos - w_.self.pos, -dash_angle);
    const double ball_noise = (w_.ball_pos - ball_pos).r() * w_.ball_rand * 0.5;
    const double noised_ball_x = ball_rel.x + ball_noise;
    // PlayerType::inertiaTravel of the velocity over the turns, in the dash frame.
    Vec2 tmp_pos = rotate_deg(w_.self.vel * ((1.0 - player_decay_pow(n_turn)) / (1.0 - kPlayerDecay)), -dash_angle);
    Vec2 tmp_vel = rotate_deg(w_.self.vel * player_decay_pow(n_turn), -dash_angle);
    StaminaModel sm = stamina_of(w_.self);
    sm.waits(n_turn);
    const double prev_effort = sm.effort;
    double power_abs = kMaxDashPower;
    double accel_x = power_abs * kDashPowerRate * sm.effort;
    bool over_speed = can_over_speed_max(power_abs, sm.effort);
    double first_dash_power = power_abs * (back_dash ? -1.0 : 1.0);
    for (int i = 0; i < n_dash; ++i) {
      double available = save_recovery ? std::max(0.0, sm.stamina - recover_dec_thr) : sm.stamina + kExtraStamina;
      if (back_dash) {
        available *= 0.5;
      }
      available = clamp(available, 0.0, kMaxDashPower);
      if (available < power_abs || sm.effort < prev_effort || (!over_speed && power_abs < available)) {
        power_abs = available;
        accel_x = power_abs * kDashPowerRate * sm.effort;
        over_speed = can_over_speed_max(power_abs, sm.effort);
        if (i == 0) {
          first_dash_power = power_abs * (back_dash ? -1.0 : 1.0);
        }
      }
      tmp_vel.x += accel_x;
      if (over_speed && tmp_vel.r2() > kPlayerSpeedMax * kPlayerSpeedMax) {
        tmp_vel.x -= accel_x;
        const double max_dash_x = std::sqrt(kPlayerSpeedMax * kPlayerSpeedMax - tmp_vel.y * tmp_vel.y);
        accel_x = max_dash_x - tmp_vel.x;
        power_abs = std::fabs(accel_x / (kDashPowerRate * sm.effort));
        tmp_vel.x += accel_x;
        over_speed = can_over_speed_max(power_abs, sm.effort);
      }
      tmp_pos += tmp_vel;
      tmp_vel *= kPlayerDecay;
      sm.dash(power_abs * (back_dash ? -1.0 : 1.0));
      if (tmp_pos.x * player_noise_rate + 0.1 > noised_ball_x) {
        Vec2 my_final = w_.self.pos + rotate_deg(tmp_pos, dash_angle);
        if ((my_inertia - my_final).r2() > 0.01) {
          my_final = line_projection(my_inertia, my_final, ball_pos);
        }
        sm.waits(n_dash - (i + 1));
        const InterceptInfo::Mode mode = sm.recovery < w_.self.recovery && !sm.capacity_is_empty()
                                             ? InterceptInfo::Mode::kExhaust
                                             : InterceptInfo::Mode::kNormal;
        push(make(mode, n_turn, n_dash, first_dash_power, 0.0, my_final, (my_final - ball_pos).r(), sm.stamina));
        return true;
      }
    }
    const double player_travel = tmp_pos.r();
    const double player_noise = player_travel * w_.player_rand * 0.5;
    const double last_ball_dist = (ball_rel - tmp_pos).r();
    const double buf = 0.2 + player_noise + ball_noise;
    if (last_ball_dist < std::max(control - 0.225, control - buf)) {
      const Vec2 my_final = w_.self.pos + rotate_deg(tmp_pos, dash_angle);
      const InterceptInfo::Mode mode = sm.recovery < w_.self.recovery && !sm.capacity_is_empty()
                                           ? InterceptInfo::Mode::kExhaust
                                           : InterceptInfo::Mode::kNormal;
      push(make(mode, n_turn, n_dash, first_dash_power, 0.0, my_final, (my_final - ball_pos).r(), sm.stamina));
      return true;
    }
    return false;
  }

  static int cycles_to_reach(double dash_dist);

  const GoalieWorld& w_;
  InterceptTable* t_;
  std::array<InterceptInfo, 16> tmp_{};
  int n_tmp_ = 0;
};

int SelfIntercept::cycles_to_reach(double dash_dist) {
  return cycles_to_reach_distance(dash_dist);
}

}  // namespace

void predict_self(const GoalieWorld& w, InterceptTable* t) {
  t->self_predicted = true;
  t->self_cache_size = 0;
  t->self_reach_cycle = 1000;
  t->self_exhaust_reach_cycle = 1000;
  // InterceptTable::predictSelf.
  if (w.self_kickable) {
    t->self_reach_cycle = 0;
    return;
  }
  const int max_cycle = std::min(InterceptTable::kMaxCycle, t->ball_cache_size);
  SelfIntercept(w, t).predict(max_cycle);
  for (int i = 0; i < t->self_cache_size; ++i) {
    const InterceptInfo& info = t->self_cache[static_cast<size_t>(i)];
    if (info.mode == InterceptInfo::Mode::kNormal) {
      if (info.reach_cycle() < t->self_reach_cycle) {
        t->self_reach_cycle = info.reach_cycle();
        break;
      }
    } else if (info.reach_cycle() < t->self_exhaust_reach_cycle) {
      t->self_exhaust_reach_cycle = info.reach_cycle();
      break;
    }
  }
}

}  // namespace pamdp::hfo::agent2d
