// librcsc's body actions as agent2d's goalie calls them (librcsc d222758, rcsc/action/):
// Body_GoToPoint2010, Body_TurnToAngle, Body_TurnToPoint, Body_StopDash,
// Bhv_GoToPointLookBall and Bhv_NeckBodyToPoint, and the world model's derived values.
// Our own code; the rules and constants are librcsc's, cited where they are used.
#include <algorithm>
#include <cmath>

#include "envs/hfo/client_effector.hpp"
#include "envs/hfo/goalie_world.hpp"

namespace pamdp::hfo::agent2d {
namespace {

// ServerParam::recoverDecThrValue(): recover_dec_thr x stamina_max.
constexpr double kRecoverDecThrValue = kRecoverDecThreshold;
// Body_GoToPoint2010: the distance within which a sideways dash is tried (adjustable_dist).
constexpr double kAdjustableDist = 1.0;
constexpr double kIllegalPower = -65535.0;
constexpr double kMaxNeckAngle = 90.0;  // ServerParam::DEFAULT_MAX_NECK_ANGLE
constexpr double kMinNeckAngle = -90.0;

double dash_rate(const GoalieWorld& w) {
  return w.self.effort * kDashPowerRate;  // SelfObject::dashRate()
}

// Number of points where the segment a-b meets the circle (Circle2D::intersection with a
// Segment2D: the line's solutions that the segment contains).
int segment_circle_points(Vec2 a, Vec2 b, Vec2 c, double r) {
  const Vec2 d = b - a;
  const double len2 = d.r2();
  if (len2 <= 0.0) {
    return 0;
  }
  const Vec2 f = a - c;
  const double bq = 2.0 * f.dot(d);
  const double cq = f.r2() - r * r;
  const double disc = bq * bq - 4.0 * len2 * cq;
  if (disc < 0.0) {
    return 0;
  }
  const double sq = std::sqrt(disc);
  int n = 0;
  for (const double t : {(-bq - sq) / (2.0 * len2), (-bq + sq) / (2.0 * len2)}) {
    n += (t >= 0.0 && t <= 1.0) ? 1 : 0;
    if (disc == 0.0) {
      break;
    }
  }
  return n;
}

// AngleDeg::isLeftOf.
bool is_left_of(double a_deg, double b_deg) {
  const double diff = angle_norm(b_deg) - angle_norm(a_deg);
  return (0.0 < diff && diff < 180.0) || diff < -180.0;
}

}  // namespace

void GoalieWorld::finish() {
  const Vec2 rel = ball_pos - self.pos;
  ball_dist_from_self = rel.r();
  ball_angle_from_self_deg = th_deg(rel);
  // SelfObject::updateBallInfo: kickable within the type's kickable area less a buffer of
  // 0.055 for a ball seen this cycle (full state).
  self_kickable = ball_dist_from_self <= kKickableArea - 0.055;
  // WorldModel::updatePlayerStateCache / check_player_kickable: only the player nearest to the
  // ball counts. An opponent is kickable within kickable_area + an error that grows with the
  // distances from self (ball: 2 %, player: 2 %, each at most 0.25); a teammate within
  // kickable_area itself (no error).
  const auto kickable = [&](const PlayerView& p, double error) {
    return !p.tackling && (p.pos - ball_pos).r() < kKickableArea + error;
  };
  exist_kickable_opponent =
      num_opponents > 0 && kickable(opponents[0], std::min(0.25, ball_dist_from_self * 0.02) +
                                                      std::min(0.25, (opponents[0].pos - self.pos).r() * 0.02));
  exist_kickable_teammate = num_teammates > 0 && kickable(teammates[0], 0.0);
}

Command do_dash(const GoalieWorld& w, double power, double dir_deg) {
  const ClientDash c = client_dash(w.self.vel, w.self.body_deg, w.self.stamina, w.self.effort, power, dir_deg);
  return {Command::Kind::kDash, c.power, c.dir_deg};
}

Command do_turn(const GoalieWorld& w, double angle_deg) {
  // ActionEffector::setTurn on an AngleDeg: no wrap of -180 to 180 here.
  const double moment = angle_norm(angle_deg) * (1.0 + kInertiaMoment * w.self.vel.r());
  return {Command::Kind::kTurn, round3(clamp(moment, kMinMoment, kMaxMoment)), 0.0};
}

double safety_dash_power(const GoalieWorld& w, double dash_power) {
  // StaminaModel::getSafetyDashPower.
  const double normalized = clamp(dash_power, kMinDashPower, kMaxDashPower);
  const double required = normalized > 0.0 ? normalized : normalized * -2.0;
  const double threshold = w.self.capacity <= 0.0 ? -kExtraStamina : kRecoverDecThrValue + 1.0;
  const double available = std::max(0.0, w.self.stamina - threshold);
  double result = std::min(required, available);
  if (normalized < 0.0) {
    result *= -0.5;
  }
  return std::fabs(result) > std::fabs(normalized) ? normalized : result;
}

namespace {

// Body_GoToPoint2010::checkGoalPost: steer around the nearer post of the goalie's own goal.
Vec2 check_goal_post(const GoalieWorld& w, Vec2 target) {
  const double collision_dist = kPlayerSize + kGoalPostRadius + 0.2;
  const Vec2 post_l{-kPitchHalfLength + kGoalPostRadius, -kGoalHalfWidth - kGoalPostRadius};
  const Vec2 post_r{-kPitchHalfLength + kGoalPostRadius, kGoalHalfWidth + kGoalPostRadius};
  const double d_l = (w.self.pos - post_l).r2();
  const double d_r = (w.self.pos - post_r).r2();
  const Vec2 post = d_l < d_r ? post_l : post_r;
  // The squared distance is compared with a distance, as librcsc does.
  if (std::min(d_l, d_r) > collision_dist + kRealSpeedMax + 0.5) {
    return target;
  }
  if (segment_circle_points(w.self.pos, target, post, collision_dist) == 0) {
    return target;
  }
  const double post_angle = th_deg(post - w.self.pos);
  const double side = is_left_of(post_angle, w.self.body_deg) ? 90.0 : -90.0;
  return post + polar(collision_dist + 0.1, (post_angle + side) * kDegToRad);
}

// Body_GoToPoint2010::doAdjustDash: a sideways dash when the target is near but off the body axis.
bool adjust_dash(const GoalieWorld& w, Vec2 target, double dist_thr, double max_dash_power, int cycle_n,
                 bool save_recovery, double dir_thr, Command* out) {
  const Vec2 inertia_point = self_inertia_point(w, cycle_n);
  Vec2 target_rel = target - inertia_point;
  if (target_rel.r2() > (dist_thr + kAdjustableDist) * (dist_thr + kAdjustableDist)) {
    return false;
  }
  target_rel = rotate_deg(target_rel, -w.self.body_deg);
  if (std::fabs(target_rel.y) < dist_thr) {
    return false;
  }
  const double target_angle = th_deg(target_rel);
  if (std::fabs(target_angle) < dir_thr) {
    return false;
  }
  const Vec2 rel_vel = rotate_deg(w.self.vel, -w.self.body_deg);
  // dash_angle_step 45, dash angles [-180, 180]: the loop runs over -180 .. 135.
  const double step = std::max(15.0, kDashAngleStep);
  const double min_dir = step * static_cast<int>(-180.0 / step);
  const double max_dir = step * static_cast<int>(180.0 / step) - 1.0;
  double best_dir = -360.0;
  double best_dist = 1000000.0;
  int best_cycle = 1000;
  double best_power = 0.0;
  double best_stamina = 0.0;
  for (double dir = min_dir; dir < max_dir; dir += step) {
    if (std::fabs(dir) < 0.5 || std::fabs(dir) > 100.0) {
      continue;
    }
    const double dash_angle = discretize_dash_dir(clamp(dir, kMinMoment, kMaxMoment));
    if (std::fabs(angle_norm(dash_angle - target_angle)) > 90.0) {
      continue;
    }
    const double rate = dash_rate(w) * dash_dir_rate(dir);
    const int max_cycle = std::min(3, cycle_n);
    Vec2 my_vel = rel_vel;
    StaminaModel stamina = stamina_of(w.self);
    double first_power = kIllegalPower;
    // PlayerType::inertiaPoint from the origin with the relative velocity.
    Vec2 my_pos = rel_vel * ((1.0 - player_decay_pow(cycle_n)) / (1.0 - kPlayerDecay));
    int c = 0;
    for (; c < max_cycle; ++c) {
      const Vec2 required_move = rotate_deg(target_rel - my_pos, -dash_angle);
      const double required_x_accel = first_term_geom_series(required_move.x, kPlayerDecay, cycle_n - c);
      if (required_x_accel < 0.01) {
        break;
      }
      const double required_power = required_x_accel / rate;
      const double available =
          save_recovery ? std::max(0.0, stamina.stamina - kRecoverDecThrValue - 1.0) : stamina.stamina + kExtraStamina;
      double power = std::min({available, max_dash_power, required_power, kMaxDashPower});
      if (c == 0) {
        first_power = power;
      }
      my_vel += polar(power * rate, dash_angle * kDegToRad);
      my_pos += my_vel;
      my_vel *= kPlayerDecay;
      stamina.dash(power);
    }
    if (first_power == kIllegalPower) {
      continue;
    }
    const double last_dist = (my_pos - target_rel).r();
    if (last_dist < dist_thr) {
      bool update = false;
      if (last_dist < 0.1 || std::fabs(last_dist - best_dist) < 0.001) {
        update = c < best_cycle || stamina.stamina > best_stamina;
      } else if (last_dist < best_dist) {
        update = true;
      }
      if (update) {
        best_dir = dir;
        best_dist = last_dist;
        best_cycle = c;
        best_power = first_power;
        best_stamina = stamina.stamina;
      }
    }
  }
  if (best_dir == -360.0) {
    return false;
  }
  *out = do_dash(w, best_power, discretize_dash_dir(clamp(best_dir, kMinMoment, kMaxMoment)));
  return true;
}

}  // namespace

bool body_go_to_point(const GoalieWorld& w, Vec2 point, double dist_thr, double max_dash_power, double dash_speed,
                      int cycle_n, bool save_recovery, double dir_thr, Command* out) {
  max_dash_power = std::fabs(max_dash_power);
  if (max_dash_power < 0.1 || std::fabs(dash_speed) < 0.001) {
    *out = do_turn(w, 0.0);
    return false;
  }
  {
    const Vec2 rel = point - self_inertia_point(w, cycle_n);
    if (rel.r() < dist_thr) {
      *out = do_turn(w, 0.0);  // librcsc's dummy action
      return false;
    }
  }
  const Vec2 target = check_goal_post(w, point);
  if (adjust_dash(w, target, dist_thr, max_dash_power, cycle_n, save_recovery, dir_thr, out)) {
    return true;
  }
  // doTurn.
  const Vec2 inertia_pos = self_inertia_point(w, cycle_n);
  const Vec2 target_rel = target - inertia_pos;
  const double target_dist = target_rel.r();
  const double max_turn = kMaxMoment / (1.0 + kInertiaMoment * w.self.vel.r());
  double turn_moment = angle_norm(th_deg(target_rel) - w.self.body_deg);
  bool back_mode = false;
  if (std::fabs(turn_moment) > max_turn && std::fabs(turn_moment) > 90.0 && target_dist < 2.0 &&
      w.self.stamina > kRecoverDecThrValue + 500.0) {
    const double effective_power = kMaxDashPower * dash_rate(w);
    const double effective_back_power = kMinDashPower * dash_rate(w);
    if (std::fabs(effective_back_power) > std::fabs(effective_power) * 0.75) {
      back_mode = true;
      turn_moment = angle_norm(turn_moment + 180.0);
    }
  }
  double turn_thr = 180.0;
  if (dist_thr < target_dist) {
    turn_thr = std::asin(dist_thr / target_dist) * kRadToDeg;
  }
  turn_thr = std::max(dir_thr, turn_thr);
  if (std::fabs(turn_moment) >= turn_thr) {
    *out = do_turn(w, turn_moment);
    return true;
  }
  // doDash.
  const double accel_angle = w.self.body_deg + (back_mode ? 180.0 : 0.0);
  const Vec2 rel = rotate_deg(target_rel, -accel_angle);
  double first_speed = first_term_geom_series(rel.x, kPlayerDecay, cycle_n);
  first_speed = clamp(first_speed, -kPlayerSpeedMax, kPlayerSpeedMax);
  if (dash_speed > 0.0) {
    first_speed = first_speed > 0.0 ? std::min(first_speed, dash_speed) : std::max(first_speed, -dash_speed);
  }
  const Vec2 rel_vel = rotate_deg(w.self.vel, -accel_angle);
  const double required_accel = first_speed - rel_vel.x;
  if (std::fabs(required_accel) >= 0.05) {
    double dash_power = std::min(required_accel / dash_rate(w), max_dash_power);
    if (back_mode) {
      dash_power = -dash_power;
    }
    dash_power = clamp(dash_power, kMinDashPower, kMaxDashPower);
    if (save_recovery) {
      dash_power = safety_dash_power(w, dash_power);
    }
    *out = do_dash(w, dash_power, 0.0);
    return true;
  }
  *out = do_turn(w, 0.0);  // dummy action
  return false;
}

bool body_turn_to_angle(const GoalieWorld& w, double angle_deg, Command* out) {
  *out = do_turn(w, angle_norm(angle_deg - w.self.body_deg));
  return true;
}

bool body_turn_to_point(const GoalieWorld& w, Vec2 point, int cycle_n, Command* out) {
  const double rel = angle_norm(th_deg(point - self_inertia_point(w, cycle_n)) - w.self.body_deg);
  *out = do_turn(w, rel);
  return std::fabs(rel) >= 1.0;
}

bool body_stop_dash(const GoalieWorld& w, bool save_recovery, Command* out) {
  const double step = std::max(15.0, kDashAngleStep);
  const double min_dir = step * static_cast<int>(-180.0 / step);
  const double max_dir = step * static_cast<int>(180.0 / step) - 1.0;
  double best_dir = -360.0;
  double best_speed = 100.0;
  double best_power = 0.0;
  for (double dir = min_dir; dir < max_dir; dir += step) {
    const double rate = dash_rate(w) * dash_dir_rate(dir);
    const double dash_angle = w.self.body_deg + discretize_dash_dir(clamp(dir, kMinMoment, kMaxMoment));
    const Vec2 rel_vel = rotate_deg(w.self.vel, -dash_angle);
    double power = clamp(-rel_vel.x / rate, kMinDashPower, kMaxDashPower);
    if (save_recovery) {
      power = safety_dash_power(w, power);
    }
    const double speed = (w.self.vel + polar(power * rate, dash_angle * kDegToRad)).r();
    if (speed < best_speed) {
      best_dir = dir;
      best_speed = speed;
      best_power = power;
    }
  }
  if (best_dir == -360.0 || std::fabs(best_power) < 1.0) {
    return false;
  }
  *out = do_dash(w, best_power, best_dir);
  return true;
}

bool neck_body_to_point(const GoalieWorld& w, Vec2 point, double angle_buf, Command* out) {
  // Bhv_NeckBodyToPoint: the body turns only when the neck alone cannot face the point.
  angle_buf = clamp(angle_buf, 0.0, 180.0);
  const Vec2 my_next = w.self.pos + w.self.vel;
  const double rel = angle_norm(th_deg(point - my_next) - w.self.body_deg);
  if (kMinNeckAngle + angle_buf < rel && rel < kMaxNeckAngle - angle_buf) {
    *out = do_turn(w, 0.0);
  } else {
    *out = do_turn(w, rel);
  }
  return true;
}

bool go_to_point_look_ball(const GoalieWorld& w, Vec2 target, double dist_thr, double dash_power,
                           double back_power_rate, Command* out) {
  const Vec2 my_final = self_inertia_final_point(w);
  if ((my_final - target).r2() < dist_thr * dist_thr) {
    *out = do_turn(w, 0.0);  // ball seen this cycle: no body turn to the ball
    return true;
  }
  const Vec2 my_next = w.self.pos + w.self.vel;
  const Vec2 ball_next = w.ball_pos + w.ball_vel;
  const double diff = angle_norm(th_deg(target - my_next) - th_deg(ball_next - my_next));
  if (std::fabs(diff) < kMaxNeckAngle - 5.0) {
    if (body_go_to_point(w, target, dist_thr, dash_power, -1.0, 100, true, 15.0, out)) {
      return true;
    }
    neck_body_to_point(w, ball_next, 5.0, out);  // Bhv_NeckBodyToBall
    return false;
  }
  const double reverse_angle = th_deg(my_next - target);
  const double dir_diff = std::fabs(angle_norm(reverse_angle - w.self.body_deg));
  // The goalie's buffer is the catchable area (ServerParam::catchableArea()).
  const double buf = kCatchableArea;
  const double dir_margin = std::max(6.0, std::fabs(std::atan2(buf, (target - my_next).r()) * kRadToDeg));
  if (dir_diff > dir_margin) {
    body_turn_to_angle(w, reverse_angle, out);
  } else {
    // A goalie always backs up at the full power asked for (back_power_rate is for others).
    (void)back_power_rate;
    *out = do_dash(w, safety_dash_power(w, -dash_power), 0.0);
  }
  return true;
}

}  // namespace pamdp::hfo::agent2d
