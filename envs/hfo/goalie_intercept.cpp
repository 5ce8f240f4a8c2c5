// librcsc's intercept table and Body_Intercept2009 for agent2d's goalie, in its own frame.
//
// A re-implementation of the same decisions, not a copy: each rule and constant names the
// librcsc file and function it comes from (paths under librcsc rcsc/, commit d222758).
// Full state throughout: every accuracy counter (posCount, seenPosCount, velCount) is 0, the
// goalie's face and position errors are 0, and it is never the last kicker, so librcsc's
// `wm.lastKickerSide() != wm.ourSide()` holds. Server parameters are the values rcssserver
// sends (player_rand 0.1, catchable_area_l 1.2), not librcsc's own defaults.
#include <algorithm>
#include <array>
#include <cmath>

#include "envs/hfo/client_effector.hpp"
#include "envs/hfo/goalie_world.hpp"

namespace pamdp::hfo::agent2d {
namespace {

// --- Parameters ---------------------------------------------------------------------------

// PlayerType's real speed max for type 0 (common/player_type.cpp, initAdditionalParams):
// min(100 x 0.006 x 1 / (1 - 0.4), 1.05) = 1.0.
constexpr double kRealSpeedMax = std::min(kMaxDashPower * kDashPowerRate / (1.0 - kPlayerDecay), kPlayerSpeedMax);
constexpr double kPlayerSpeedMax2 = kPlayerSpeedMax * kPlayerSpeedMax;
// ServerParam::ourPenaltyAreaLineX (-52.5 + 16.5) and penaltyAreaHalfWidth.
constexpr double kOurPenaltyLineX = -kPenaltyBoxX;
constexpr double kPenaltyHalfWidth = kPenaltyBoxHalfWidth;
// ServerParam::recoverDecThrValue: recover_dec_thr x stamina_max.
constexpr double kRecoverDecThrValue = kRecoverDecThreshold;
// rcssserver's default dash range and step (-180, 180, 45): the ServerParam loops in
// SelfInterceptV13::predictOneDash/predictOmniDashShort then run -180, -135, ..., 135.
constexpr double kMinDashAngle = -180.0;
constexpr double kMaxDashAngle = 180.0;

// SelfInterceptV13 constants (player/self_intercept_v13.cpp, file scope).
constexpr int kMaxShortStep = 5;             // MAX_SHORT_STEP
constexpr double kMinTurnThr = 12.5;         // MIN_TURN_THR
constexpr double kBackDashThrAngle = 100.0;  // BACK_DASH_THR_ANGLE
constexpr double kControlAreaBuf = 0.15;     // control_area_buf (2009-07-03)

// --- Small geometry, as librcsc's AngleDeg / Vector2D / Line2D compute it ------------------

double th_deg(Vec2 v) {  // Vector2D::th(): atan2, 0 for the zero vector
  return std::atan2(v.y, v.x) * kRadToDeg;
}

Vec2 rotated(Vec2 v, double deg) {  // Vector2D::rotatedVector
  const double c = std::cos(deg * kDegToRad);
  const double s = std::sin(deg * kDegToRad);
  return {c * v.x - s * v.y, s * v.x + c * v.y};
}

Vec2 polar_deg(double r, double deg) {  // Vector2D::polar2vector
  return {r * std::cos(deg * kDegToRad), r * std::sin(deg * kDegToRad)};
}

double dist(Vec2 a, Vec2 b) {
  return (a - b).r();
}
double dist2(Vec2 a, Vec2 b) {
  return (a - b).r2();
}

double asin_deg(double s) {  // AngleDeg::asin_deg
  return s >= 1.0 ? 90.0 : (s <= -1.0 ? -90.0 : std::asin(s) * kRadToDeg);
}

double bound(double lo, double x, double hi) {  // rcsc::bound / min_max
  return std::min(std::max(lo, x), hi);
}

// Distance from p to the line through `origin` along `dir_deg` (Line2D(origin, angle).dist).
double line_dist(Vec2 origin, double dir_deg, Vec2 p) {
  const Vec2 u = polar_deg(1.0, dir_deg);
  const Vec2 d = p - origin;
  return std::fabs(u.x * d.y - u.y * d.x);
}

// Foot of the perpendicular from p on the line through a and b (Line2D(a, b).projection).
Vec2 line_projection(Vec2 a, Vec2 b, Vec2 p) {
  const Vec2 ab = b - a;
  const double t = ab.dot(p - a) / ab.r2();
  return a + ab * t;
}

// Segment2D::dist(point) (geom/segment_2d.cpp).
double segment_dist(Vec2 a, Vec2 b, Vec2 p) {
  const double len = dist(a, b);
  if (len == 0.0) {
    return dist(a, p);
  }
  const Vec2 vec = b - a;
  const double prod = vec.dot(p - a);
  if (0.0 <= prod && prod <= len * len) {
    const double area2 = (b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y);
    return std::fabs(area2 / len);
  }
  return std::sqrt(std::min(dist2(a, p), dist2(b, p)));
}

// calc_first_term_geom_series (math_util.h).
double first_term_geom_series(double sum, double r, int len) {
  return sum * (1.0 - r) / (1.0 - std::pow(r, len));
}

Vec2 player_inertia_point(Vec2 pos, Vec2 vel, int n) {  // inertia_n_step_point, player decay
  return pos + vel * ((1.0 - std::pow(kPlayerDecay, n)) / (1.0 - kPlayerDecay));
}
Vec2 player_inertia_travel(Vec2 vel, int n) {
  return vel * ((1.0 - std::pow(kPlayerDecay, n)) / (1.0 - kPlayerDecay));
}

// ServerParam::dashDirRate on a direction normalized and discretized first.
double dir_rate(double dir_deg) {
  return std::min(std::max(1.0e-5, dash_dir_rate(discretize_dash_dir(clamp(dir_deg, kMinDashAngle, kMaxDashAngle)))),
                  1.0);
}

// PlayerType::normalizeAccel(velocity, accel*) (common/player_type.cpp).
void normalize_accel(Vec2 vel, Vec2* accel) {
  if ((vel + *accel).r2() > kPlayerSpeedMax2 + 0.0001) {
    const Vec2 rel_vel = rotated(vel, -th_deg(*accel));
    const double max_dash_x = std::sqrt(kPlayerSpeedMax2 - rel_vel.y * rel_vel.y);
    const double mag = accel->r();
    if (mag > 1.0e-6) {  // Vector2D::setLength
      *accel *= (max_dash_x - rel_vel.x) / mag;
    }
  }
}

// PlayerType::canOverSpeedMax.
bool can_over_speed_max(double dash_power, double effort) {
  return std::fabs(dash_power) * kDashPowerRate * effort > kPlayerSpeedMax * (1.0 - kPlayerDecay);
}

// PlayerType::kickRate.
double kick_rate(double ball_dist, double dir_diff_deg) {
  return kKickPowerRate * (1.0 - 0.25 * std::fabs(dir_diff_deg) / 180.0 -
                           0.25 * (ball_dist - kBallSize - kPlayerSize) / kKickableMargin);
}

// PlayerType's dash distance table (player_type.cpp, initAdditionalParams): the distance of n
// full dashes from rest, n = 1..50. Type 0 never reaches its speed cap nor runs out of
// stamina within 50 dashes, so the accel stays 0.6.
struct DashDistanceTable {
  std::array<double, 50> d{};
  DashDistanceTable() {
    const double accel = kMaxDashPower * kDashPowerRate * kEffortMax;
    double speed = 0.0;
    double reach = 0.0;
    for (double& x : d) {
      speed += accel;
      reach += speed;
      x = reach;
      speed *= kPlayerDecay;
    }
  }
};
const DashDistanceTable kDashDistances;

// PlayerType::cyclesToReachDistance.
int cycles_to_reach_distance(double dash_dist) {
  if (dash_dist <= 0.001) {
    return 0;
  }
  const auto& t = kDashDistances.d;
  const auto* it = std::lower_bound(t.begin(), t.end(), dash_dist - 0.001);
  if (it != t.end()) {
    return static_cast<int>(it - t.begin()) + 1;
  }
  return static_cast<int>(t.size()) + static_cast<int>(std::ceil((dash_dist - t.back()) / kRealSpeedMax));
}

// --- StaminaModel (common/stamina_model.cpp) ----------------------------------------------

struct Stamina {
  double stamina;
  double effort;
  double recovery;
  double capacity;

  explicit Stamina(const SelfView& s)
      : stamina(s.stamina), effort(s.effort), recovery(s.recovery), capacity(s.capacity) {}

  [[nodiscard]] bool capacity_is_empty() const { return capacity <= 1.0e-5 && capacity >= 0.0; }
  [[nodiscard]] double dash_rate() const { return effort * kDashPowerRate; }  // PlayerType::dashRate(effort)

  // simulateWait (stamina_capacity >= 0 on the server: the capacity branch).
  void wait() {
    if (stamina <= kRecoverDecThrValue && recovery > kRecoverMin) {
      recovery = std::max(recovery - kRecoverDec, kRecoverMin);
    }
    if (stamina <= kEffortDecThreshold) {
      if (effort > kEffortMin) {
        effort = std::max(effort - kEffortDec, kEffortMin);
      }
    } else if (stamina >= kEffortIncThreshold) {
      if (effort < kEffortMax) {
        effort = std::min(effort + kEffortInc, kEffortMax);
      }
    }
    const double inc = std::min(kStaminaIncMax * recovery, kStaminaMax - stamina);
    stamina += std::min(inc, capacity);
    capacity = std::max(0.0, capacity - inc);
    stamina = std::min(stamina, kStaminaMax);
  }
  void waits(int n) {
    for (int i = 0; i < n; ++i) {
      wait();
    }
  }
  // simulateDash / simulateDashes.
  void dash(double power) {
    stamina = std::max(0.0, stamina - (power >= 0.0 ? power : power * -2.0));
    wait();
  }
  void dashes(int n, double power) {
    for (int i = 0; i < n; ++i) {
      dash(power);
    }
  }
};

using Mode = InterceptInfo::Mode;

InterceptInfo make_info(Mode mode, int n_turn, int n_dash, double power, double dir, Vec2 pos, double ball_dist,
                        double stamina) {
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

// A fixed-capacity list of candidates (librcsc's static tmp_cache vectors).
template <int N>
struct Candidates {
  std::array<InterceptInfo, N> v{};
  int n = 0;
  void push(const InterceptInfo& i) {
    if (n < N) {
      v[static_cast<size_t>(n++)] = i;
    }
  }
};

// --- SelfInterceptV13 (player/self_intercept_v13.cpp) -------------------------------------

class SelfIntercept {
 public:
  SelfIntercept(const GoalieWorld& w, InterceptTable* t) : w_(w), s_(w.self), t_(t) {}

  // SelfInterceptV13::predict.
  void predict(int max_cycle) {
    if (t_->ball_cache_size < 2) {
      return;
    }
    const bool save_recovery = s_.capacity != 0.0;
    predict_one_step();
    predict_short_step(max_cycle, save_recovery);
    predict_long_step(max_cycle, save_recovery);
    predict_long_step(max_cycle, false);
    // std::sort as librcsc (InterceptInfo::Cmp): reach cycle, then turn cycle.
    std::sort(t_->self_cache.begin(), t_->self_cache.begin() + t_->self_cache_size,
              [](const InterceptInfo& a, const InterceptInfo& b) {
                return a.reach_cycle() < b.reach_cycle() ||
                       (a.reach_cycle() == b.reach_cycle() && a.turn_cycle < b.turn_cycle);
              });
  }

 private:
  void push(const InterceptInfo& i) {
    if (t_->self_cache_size < InterceptTable::kMaxSelfCache) {
      t_->self_cache[static_cast<size_t>(t_->self_cache_size++)] = i;
    }
  }

  // The goalie's catch reach applies while the ball is inside its penalty area (the
  // goalie_mode tests repeated in each predictor).
  static bool goalie_mode(Vec2 ball, double x_line, double y_line) {
    return ball.x < x_line && std::fabs(ball.y) < y_line;
  }
  static double control_area_for(bool goalie) { return goalie ? kCatchableArea : kKickableArea; }

  Vec2 ball_inertia(int n) const { return ball_inertia_point(w_, n); }
  Vec2 self_inertia(int n) const { return self_inertia_point(w_, n); }

  // predictOneStep.
  void predict_one_step() {
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const double control_area = control_area_for(goalie_mode(ball_next, kOurPenaltyLineX, kPenaltyHalfWidth));
    if (w_.ball_dist_from_self > kBallSpeedMax + kRealSpeedMax + control_area) {
      return;
    }
    if (predict_no_dash()) {
      return;
    }
    predict_one_dash();
  }

  // predictNoDash: the ball comes into reach with no dash at all (a turn is spent instead).
  bool predict_no_dash() {
    const Vec2 my_next = s_.pos + s_.vel;
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const bool goalie = goalie_mode(ball_next, kOurPenaltyLineX, kPenaltyHalfWidth);
    const double control_area = control_area_for(goalie);
    const Vec2 next_ball_rel = rotated(ball_next - my_next, -s_.body_deg);
    const double ball_noise = w_.ball_vel.r() * w_.ball_rand;
    const double next_ball_dist = next_ball_rel.r();
    if (next_ball_dist > control_area - 0.15 - ball_noise) {
      return false;
    }
    if (!goalie && next_ball_dist > kPlayerSize + kBallSize) {
      // Not worth it when even a full kick cannot stop the ball there.
      const double rate = kick_rate(next_ball_dist, th_deg(next_ball_rel));
      const Vec2 next_ball_vel = w_.ball_vel * kBallDecay;
      if (kMaxKickPower * rate <= next_ball_vel.r() * kBallDecay * 1.1) {
        return false;
      }
    }
    Stamina st(s_);
    st.wait();
    push(make_info(Mode::kNormal, 1, 0, 0.0, 0.0, my_next, next_ball_dist, st.stamina));
    return true;
  }

  // predictOneDash: one dash in each of the eight directions, the best kept.
  void predict_one_dash() {
    Candidates<16> tmp;
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const double control_area = control_area_for(goalie_mode(ball_next, kOurPenaltyLineX, kPenaltyHalfWidth));
    const double step = std::max(5.0, kDashAngleStep);
    const double min_dir = step * static_cast<int>(-180.0 / step);
    const double max_dir = step * static_cast<int>(180.0 / step) - 1.0;
    for (double dir = min_dir; dir < max_dir; dir += step) {
      const double dash_angle = angle_norm(s_.body_deg + discretize_dash_dir(clamp(dir, kMinDashAngle, kMaxDashAngle)));
      const double dash_rate = s_.effort * kDashPowerRate * dir_rate(dir);
      const double forward_power = bound(0.0, s_.stamina - kRecoverDecThrValue - 1.0, kMaxDashPower);
      const double back_power = bound(kMinDashPower, (s_.stamina - kRecoverDecThrValue - 1.0) * -0.5, 0.0);
      Vec2 fwd = polar_deg(forward_power * dash_rate, dash_angle);
      Vec2 back = polar_deg(back_power * dash_rate, dash_angle);
      normalize_accel(s_.vel, &fwd);
      normalize_accel(s_.vel, &back);
      InterceptInfo info;
      if (predict_one_dash_adjust(dash_angle, fwd, back, control_area, &info)) {
        tmp.push(info);
        continue;
      }
      // Stamina allowed less than full power: try full power (recovery spent).
      if (std::fabs(forward_power - kMaxDashPower) < 1.0 && std::fabs(back_power - kMinDashPower) < 1.0) {
        continue;
      }
      fwd = polar_deg(kMaxDashPower * dash_rate, dash_angle);
      back = polar_deg(kMinDashPower * dash_rate, dash_angle);
      normalize_accel(s_.vel, &fwd);
      normalize_accel(s_.vel, &back);
      if (predict_one_dash_adjust(dash_angle, fwd, back, control_area, &info)) {
        tmp.push(info);
      }
    }
    if (tmp.n == 0) {
      return;
    }
    const double safety_ball_dist =
        std::max(control_area - 0.2 - w_.ball_vel.r() * w_.ball_rand, kPlayerSize + kBallSize + kKickableMargin * 0.4);
    const InterceptInfo* best = &tmp.v[0];
    for (int k = 1; k < tmp.n; ++k) {
      const InterceptInfo& it = tmp.v[static_cast<size_t>(k)];
      if (best->ball_dist < safety_ball_dist && it.ball_dist < safety_ball_dist) {
        if (best->stamina < it.stamina) {
          best = &it;
        }
      } else if (best->ball_dist > it.ball_dist ||
                 (std::fabs(best->ball_dist - it.ball_dist) < 0.001 && best->stamina < it.stamina)) {
        best = &it;
      }
    }
    push(*best);
  }

  // predictOneDashAdjust: the dash power along `dash_angle` that brings the ball into reach.
  bool predict_one_dash_adjust(double dash_angle, Vec2 max_forward_accel, Vec2 max_back_accel, double control_area,
                               InterceptInfo* info) const {
    const double control_buf = control_area - 0.075;
    const double dash_dir = angle_norm(dash_angle - s_.body_deg);
    const Vec2 ball_next = w_.ball_pos + w_.ball_vel;
    const Vec2 self_next = s_.pos + s_.vel;
    const Vec2 ball_rel = rotated(ball_next - self_next, -dash_angle);
    const Vec2 forward_rel = rotated(max_forward_accel, -dash_angle);
    const Vec2 back_rel = rotated(max_back_accel, -dash_angle);
    const double dash_rate = s_.effort * kDashPowerRate * dir_rate(dash_dir);
    if (std::fabs(ball_rel.y) > control_buf || segment_dist(forward_rel, back_rel, ball_rel) > control_buf) {
      return false;
    }
    double dash_power = -1000.0;
    if (back_rel.x < ball_rel.x && ball_rel.x < forward_rel.x) {
      dash_power = one_step_dash_power(ball_rel, dash_angle, forward_rel.x, back_rel.x);
    }
    if (dash_power < -999.0 && forward_rel.x < ball_rel.x && dist(ball_rel, forward_rel) < control_buf) {
      dash_power = forward_rel.x / dash_rate;
    }
    if (dash_power < -999.0 && ball_rel.x < back_rel.x && dist(ball_rel, back_rel) < control_buf) {
      dash_power = back_rel.x / dash_rate;
    }
    if (dash_power < -999.0 && back_rel.x < ball_rel.x && ball_rel.x < forward_rel.x) {
      dash_power = ball_rel.x / dash_rate;
    }
    if (dash_power < -999.0) {
      return false;
    }
    const Vec2 accel = polar_deg(dash_power * dash_rate, dash_angle);
    const Vec2 my_vel = s_.vel + accel;
    const Vec2 my_pos = s_.pos + my_vel;
    Stamina st(s_);
    st.dash(dash_power);
    const Mode mode = st.stamina < kRecoverDecThrValue && !st.capacity_is_empty() ? Mode::kExhaust : Mode::kNormal;
    *info = make_info(mode, 0, 1, dash_power, dash_dir, my_pos, dist(my_pos, ball_next), st.stamina);
    return true;
  }

  // getOneStepDashPower: the least power that puts the ball at a comfortable control
  // distance. librcsc passes the global dash angle to dashDirRate here; kept as it is.
  double one_step_dash_power(Vec2 next_ball_rel, double dash_angle, double max_forward_accel_x,
                             double max_back_accel_x) const {
    const double dash_rate = s_.effort * kDashPowerRate * dir_rate(dash_angle);
    const double best_forward = kPlayerSize + 0.5 * kKickableMargin + kBallSize;
    const double best_backward = kPlayerSize + 0.3 * kKickableMargin + kBallSize;
    if (std::fabs(next_ball_rel.y) > best_forward) {
      return next_ball_rel.x / dash_rate;
    }
    // NaN when |y| lies between the two distances: the loop below then never runs.
    const double forward_trap = next_ball_rel.x - std::sqrt(std::pow(best_forward, 2) - std::pow(next_ball_rel.y, 2));
    const double backward_trap = next_ball_rel.x + std::sqrt(std::pow(best_backward, 2) - std::pow(next_ball_rel.y, 2));
    double min_power = 10000.0;
    const double x_step = (backward_trap - forward_trap) / 5.0;
    for (double accel_x = forward_trap; accel_x < backward_trap + 0.01; accel_x += x_step) {
      if ((accel_x >= 0.0 && max_forward_accel_x > accel_x) || (accel_x < 0.0 && max_back_accel_x < accel_x)) {
        const double power = accel_x / dash_rate;
        if (std::fabs(power) < std::fabs(min_power)) {
          min_power = power;
        }
      }
    }
    return min_power < 1000.0 ? min_power : -1000.0;
  }

  // predictShortStep: cycles 2..5 by turn-then-dash (forward and back) and omni dash.
  void predict_short_step(int max_cycle, bool save_recovery) {
    const int max_loop = std::min(kMaxShortStep, max_cycle);
    const double pen_x = kOurPenaltyLineX - 0.5;
    const double pen_y = kPenaltyHalfWidth - 0.5;
    const Vec2 ball_to_self = rotated(s_.pos - w_.ball_pos, -th_deg(w_.ball_vel));
    int min_cycle = static_cast<int>(std::ceil((std::fabs(ball_to_self.y) - kKickableArea) / kRealSpeedMax));
    if (min_cycle >= max_loop) {
      return;
    }
    min_cycle = std::max(min_cycle, 2);
    Vec2 ball_pos = ball_inertia(min_cycle - 1);
    Vec2 ball_vel = w_.ball_vel * std::pow(kBallDecay, min_cycle - 1);
    for (int cycle = min_cycle; cycle <= max_loop; ++cycle) {
      Candidates<32> tmp;
      ball_pos += ball_vel;
      ball_vel *= kBallDecay;
      const double control_area = control_area_for(goalie_mode(ball_pos, pen_x, pen_y));
      if (std::pow(control_area + kRealSpeedMax * cycle, 2) < dist2(s_.pos, ball_pos)) {
        continue;
      }
      turn_dash_short(cycle, ball_pos, control_area, save_recovery, false, std::max(0.1, control_area - 0.4), &tmp);
      turn_dash_short(cycle, ball_pos, control_area, save_recovery, false,
                      std::max(0.1, control_area - kControlAreaBuf), &tmp);
      turn_dash_short(cycle, ball_pos, control_area, save_recovery, true, std::max(0.1, control_area - 0.4), &tmp);
      turn_dash_short(cycle, ball_pos, control_area, save_recovery, true, control_area - kControlAreaBuf, &tmp);
      if (cycle <= 2) {
        omni_dash_short(cycle, ball_pos, control_area, save_recovery, false, &tmp);
      }
      if (tmp.n == 0) {
        continue;
      }
      const double safety_ball_dist = std::max(control_area - 0.2 - dist(w_.ball_pos, ball_pos) * w_.ball_rand,
                                               kPlayerSize + kBallSize + kKickableMargin * 0.4);
      const InterceptInfo* best = &tmp.v[0];
      for (int k = 1; k < tmp.n; ++k) {
        const InterceptInfo& it = tmp.v[static_cast<size_t>(k)];
        if (best->ball_dist < safety_ball_dist && it.ball_dist < safety_ball_dist) {
          if (best->turn_cycle > it.turn_cycle || (best->turn_cycle == it.turn_cycle && best->stamina < it.stamina)) {
            best = &it;
          }
        } else if (best->turn_cycle >= it.turn_cycle &&
                   (best->ball_dist > it.ball_dist ||
                    (std::fabs(best->ball_dist - it.ball_dist) < 0.001 && best->stamina < it.stamina))) {
          best = &it;
        }
      }
      push(*best);
    }
  }

  // predictTurnDashShort.
  template <int N>
  void turn_dash_short(int cycle, Vec2 ball_pos, double control_area, bool save_recovery, bool back_dash,
                       double turn_margin_area, Candidates<N>* out) const {
    double dash_angle = s_.body_deg;
    const int n_turn = turn_cycle_short(cycle, ball_pos, back_dash, turn_margin_area, &dash_angle);
    if (n_turn > cycle) {
      return;
    }
    dash_cycle_short(cycle, n_turn, ball_pos, dash_angle, control_area, save_recovery, back_dash, out);
  }

  // predictTurnCycleShort: full-moment turns until the ball lies within the margin.
  int turn_cycle_short(int cycle, Vec2 ball_pos, bool back_dash, double dist_thr, double* result_dash_angle) const {
    const Vec2 inertia_pos = self_inertia(cycle);
    const double target_dist = dist(ball_pos, inertia_pos);
    const double target_angle = th_deg(ball_pos - inertia_pos);
    const double body_angle = back_dash ? angle_norm(s_.body_deg + 180.0) : s_.body_deg;
    double angle_diff = std::fabs(angle_norm(target_angle - body_angle));
    double turn_margin = 180.0;
    if (dist_thr < target_dist) {
      turn_margin = std::max(kMinTurnThr, asin_deg(dist_thr / target_dist));
    }
    int n_turn = 0;
    double speed = s_.vel.r();
    while (angle_diff > turn_margin) {
      angle_diff -= kMaxMoment / (1.0 + kInertiaMoment * speed);  // PlayerType::effectiveTurn
      speed *= kPlayerDecay;
      ++n_turn;
    }
    *result_dash_angle = body_angle;
    if (n_turn > 0) {
      angle_diff = std::max(0.0, angle_diff);
      *result_dash_angle = angle_norm(angle_norm(target_angle - body_angle) > 0.0 ? target_angle - angle_diff
                                                                                  : target_angle + angle_diff);
    }
    return n_turn;
  }

  // predictDashCycleShort: dashes sized to end on the ball, or waiting when it comes to us.
  template <int N>
  void dash_cycle_short(int cycle, int n_turn, Vec2 ball_pos, double dash_angle, double control_area,
                        bool save_recovery, bool back_dash, Candidates<N>* out) const {
    const double recover_dec_thr = kRecoverDecThrValue + 1.0;
    const int max_dash = cycle - n_turn;
    const Vec2 my_inertia = self_inertia(cycle);
    Vec2 my_pos = self_inertia(n_turn);
    Vec2 my_vel = s_.vel * std::pow(kPlayerDecay, n_turn);
    Stamina st(s_);
    st.waits(n_turn);
    if (dist2(my_inertia, ball_pos) < std::pow(control_area - kControlAreaBuf, 2)) {
      Stamina tmp_st = st;
      tmp_st.waits(cycle - n_turn);
      out->push(make_info(Mode::kNormal, n_turn, cycle - n_turn, 0.0, 0.0, my_inertia, dist(my_inertia, ball_pos),
                          tmp_st.stamina));
    }
    const double target_angle = th_deg(ball_pos - my_inertia);
    if (std::fabs(angle_norm(target_angle - dash_angle)) > 90.0) {
      return;
    }
    const Vec2 accel_unit = polar_deg(1.0, dash_angle);
    double first_dash_power = 0.0;
    for (int n_dash = 1; n_dash <= max_dash; ++n_dash) {
      const Vec2 ball_rel = rotated(ball_pos - my_pos, -dash_angle);
      const double first_speed = first_term_geom_series(ball_rel.x, kPlayerDecay, max_dash - n_dash + 1);
      const Vec2 rel_vel = rotated(my_vel, -dash_angle);
      const double required_accel = first_speed - rel_vel.x;
      double dash_power = required_accel / st.dash_rate();
      if (back_dash) {
        dash_power = -dash_power;
      }
      const double available = save_recovery ? std::max(0.0, st.stamina - recover_dec_thr) : st.stamina + kExtraStamina;
      if (back_dash) {
        dash_power = std::max(bound(kMinDashPower, dash_power, 0.0), available * -0.5);
      } else {
        dash_power = std::min(bound(0.0, dash_power, kMaxDashPower), available);
      }
      if (n_dash == 1) {
        first_dash_power = dash_power;
      }
      my_vel += accel_unit * std::fabs(dash_power * st.dash_rate());
      my_pos += my_vel;
      my_vel *= kPlayerDecay;
      st.dash(dash_power);
    }
    if (dist2(my_pos, ball_pos) < std::pow(control_area - kControlAreaBuf, 2) ||
        dist2(s_.pos, my_pos) > dist2(s_.pos, ball_pos)) {
      const Mode mode = st.stamina < kRecoverDecThrValue && !st.capacity_is_empty() ? Mode::kExhaust : Mode::kNormal;
      out->push(
          make_info(mode, n_turn, cycle - n_turn, first_dash_power, 0.0, my_pos, dist(my_pos, ball_pos), st.stamina));
    }
  }

  // predictOmniDashShort: a side dash onto the ball's line, then dashes along the body.
  template <int N>
  void omni_dash_short(int cycle, Vec2 ball_pos, double control_area, bool save_recovery, bool back_dash,
                       Candidates<N>* out) const {
    const double body_angle = back_dash ? angle_norm(s_.body_deg + 180.0) : s_.body_deg;
    const Vec2 my_inertia = self_inertia(cycle);
    if (line_dist(ball_pos, body_angle, my_inertia) < control_area - 0.4) {
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
      const double dash_angle = angle_norm(body_angle + discretize_dash_dir(clamp(dir, kMinDashAngle, kMaxDashAngle)));
      if (std::fabs(angle_norm(dash_angle - target_angle)) > 91.0) {
        continue;
      }
      double first_dash_power = 0.0;
      Vec2 my_pos = s_.pos;
      Vec2 my_vel = s_.vel;
      Stamina st(s_);
      const int n_omni = adjust_omni_dash(cycle, ball_pos, control_area, save_recovery, back_dash, dir, &my_pos,
                                          &my_vel, &st, &first_dash_power);
      if (n_omni <= 0) {
        continue;
      }
      {
        const Vec2 inertia_pos = player_inertia_point(my_pos, my_vel, cycle - n_omni);
        const Vec2 target_rel = rotated(ball_pos - inertia_pos, -body_angle);
        if ((back_dash && target_rel.x > 0.0) || (!back_dash && target_rel.x < 0.0)) {
          continue;
        }
      }
      const Vec2 body_unit = polar_deg(1.0, body_angle);
      for (int n_dash = n_omni + 1; n_dash <= cycle; ++n_dash) {
        const double first_speed =
            first_term_geom_series(rotated(ball_pos - my_pos, -body_angle).x, kPlayerDecay, cycle - n_dash + 1);
        const Vec2 rel_vel = rotated(my_vel, -body_angle);
        double dash_power = (first_speed - rel_vel.x) / st.dash_rate();
        if (back_dash) {
          dash_power = -dash_power;
        }
        const double available =
            save_recovery ? std::max(0.0, st.stamina - recover_dec_thr) : st.stamina + kExtraStamina;
        if (back_dash) {
          dash_power = std::max(bound(kMinDashPower, dash_power, 0.0), available * -0.5);
        } else {
          dash_power = std::min(bound(0.0, dash_power, kMaxDashPower), available);
        }
        my_vel += body_unit * (std::fabs(dash_power) * st.dash_rate());
        my_pos += my_vel;
        my_vel *= kPlayerDecay;
        st.dash(dash_power);
      }
      const Vec2 my_move = my_pos - s_.pos;
      if (dist2(my_pos, ball_pos) < std::pow(control_area - kControlAreaBuf, 2) ||
          my_move.r() > std::fabs(rotated(ball_pos - s_.pos, -th_deg(my_move)).x)) {
        const Mode mode = st.recovery < s_.recovery && !st.capacity_is_empty() ? Mode::kExhaust : Mode::kNormal;
        out->push(make_info(mode, 0, cycle, first_dash_power, dir, my_pos, dist(my_pos, ball_pos), st.stamina));
      }
    }
  }

  // predictAdjustOmniDash: up to two dashes in direction `dir` (relative to the body) until
  // the final point lies on the ball's line; returns their count, 0 when none is needed, -1
  // when two do not suffice.
  int adjust_omni_dash(int cycle, Vec2 ball_pos, double control_area, bool save_recovery, bool back_dash, double dir,
                       Vec2* my_pos, Vec2* my_vel, Stamina* st, double* first_dash_power) const {
    const double recover_dec_thr = kRecoverDecThrValue + 1.0;
    const int max_omni_dash = std::min(2, cycle);
    const double body_angle = back_dash ? angle_norm(s_.body_deg + 180.0) : s_.body_deg;
    const Vec2 my_inertia = self_inertia(cycle);
    if (line_dist(ball_pos, body_angle, my_inertia) < control_area - 0.4) {
      *first_dash_power = 0.0;
      return 0;
    }
    const double dash_angle = angle_norm(body_angle + discretize_dash_dir(clamp(dir, kMinDashAngle, kMaxDashAngle)));
    const Vec2 accel_unit = polar_deg(1.0, dash_angle);
    const double dash_dir_rate_v = dir_rate(dir);
    for (int n = 1; n <= max_omni_dash; ++n) {
      const double first_speed =
          first_term_geom_series(std::max(0.0, line_dist(ball_pos, body_angle, *my_pos)), kPlayerDecay, cycle - n + 1);
      const Vec2 rel_vel = rotated(*my_vel, -dash_angle);
      const double required_accel = first_speed - rel_vel.x;
      if (std::fabs(required_accel) < 0.01) {
        return n - 1;
      }
      double dash_power = required_accel / (st->dash_rate() * dash_dir_rate_v);
      const double available =
          save_recovery ? std::max(0.0, st->stamina - recover_dec_thr) : st->stamina + kExtraStamina;
      if (back_dash) {
        dash_power = std::max(bound(kMinDashPower, dash_power, 0.0), available * -0.5);
      } else {
        dash_power = std::min(bound(0.0, dash_power, kMaxDashPower), available);
      }
      if (n == 1) {
        *first_dash_power = dash_power;
      }
      *my_vel += accel_unit * (std::fabs(dash_power) * st->dash_rate() * dash_dir_rate_v);
      *my_pos += *my_vel;
      *my_vel *= kPlayerDecay;
      st->dash(dash_power);
      const Vec2 inertia_pos = player_inertia_point(*my_pos, *my_vel, cycle - n);
      if (line_dist(ball_pos, body_angle, inertia_pos) < control_area - kControlAreaBuf) {
        return n;
      }
    }
    return -1;
  }

  // predictLongStep: from cycle 6 on, turns then full dashes (forward, or back when close).
  void predict_long_step(int max_cycle, bool save_recovery) {
    const Vec2 ball_to_self = rotated(s_.pos - w_.ball_pos, -th_deg(w_.ball_vel));
    int start_cycle = static_cast<int>(std::ceil((std::fabs(ball_to_self.y) - kKickableArea - 0.2) / kRealSpeedMax));
    if (start_cycle <= kMaxShortStep) {
      start_cycle = kMaxShortStep + 1;
    }
    Vec2 ball_pos = ball_inertia(start_cycle - 1);
    Vec2 ball_vel = w_.ball_vel * std::pow(kBallDecay, start_cycle - 1);
    bool found = false;
    int max_loop = max_cycle;
    for (int cycle = start_cycle; cycle < max_loop; ++cycle) {
      ball_pos += ball_vel;
      ball_vel *= kBallDecay;
      if (std::fabs(ball_pos.x) > kPitchHalfLength + 10.0 || std::fabs(ball_pos.y) > kPitchHalfWidth + 10.0) {
        break;
      }
      const double control_area = control_area_for(goalie_mode(ball_pos, kOurPenaltyLineX, kPenaltyHalfWidth));
      if (control_area + kRealSpeedMax * cycle < dist(s_.pos, ball_pos)) {
        continue;
      }
      if (can_reach_after_turn_dash(cycle, ball_pos, control_area, save_recovery)) {
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

  // predictFinal: where the ball stops, reached by turns and full dashes.
  void predict_final(int max_cycle) {
    const Vec2 my_final = self_inertia(100);
    const Vec2 ball_final = ball_inertia(100);
    const bool goalie = goalie_mode(ball_final, kOurPenaltyLineX, kPenaltyHalfWidth);
    const double control_area = goalie ? kCatchableArea - 0.15 : kKickableArea;
    double dash_angle = s_.body_deg;
    bool back_dash = false;
    const int n_turn = turn_cycle(100, ball_final, control_area, &dash_angle, &back_dash);
    const double dash_dist = dist(my_final, ball_final) - control_area;
    int n_dash = cycles_to_reach_distance(dash_dist);
    if (max_cycle > n_turn + n_dash) {
      n_dash = max_cycle - n_turn;
    }
    Stamina st(s_);
    st.waits(n_turn);
    st.dashes(n_dash, kMaxDashPower);
    push(make_info(Mode::kNormal, n_turn, n_dash, kMaxDashPower, 0.0, ball_final, 0.0, st.stamina));
  }

  // canReachAfterTurnDash.
  bool can_reach_after_turn_dash(int cycle, Vec2 ball_pos, double control_area, bool save_recovery) {
    double dash_angle = s_.body_deg;
    bool back_dash = false;
    const int n_turn = turn_cycle(cycle, ball_pos, control_area, &dash_angle, &back_dash);
    if (n_turn > cycle) {
      return false;
    }
    return can_reach_after_dash(n_turn, std::max(0, cycle - n_turn), ball_pos, control_area, save_recovery, dash_angle,
                                back_dash);
  }

  // predictTurnCycle: turns with the noise-reduced moment 180 x (1 - player_rand).
  int turn_cycle(int cycle, Vec2 ball_pos, double control_area, double* dash_angle, bool* back_dash) const {
    const Vec2 inertia_pos = self_inertia(cycle);
    const Vec2 target_rel = ball_pos - inertia_pos;
    const double target_angle = th_deg(target_rel);
    double angle_diff = angle_norm(target_angle - *dash_angle);
    const bool diff_is_positive = angle_diff > 0.0;
    angle_diff = std::fabs(angle_diff);
    const double target_dist = target_rel.r();
    double turn_margin = 180.0;
    const double control_buf = std::max(0.5, control_area - 0.25);
    if (control_buf < target_dist) {
      turn_margin = asin_deg(control_buf / target_dist);
    }
    turn_margin = std::max(turn_margin, kMinTurnThr);
    if (can_back_dash_chase(cycle, angle_diff)) {
      *back_dash = true;
      *dash_angle = angle_norm(*dash_angle + 180.0);
      angle_diff = 180.0 - angle_diff;
    }
    const double max_moment = kMaxMoment * (1.0 - w_.player_rand);
    double speed = s_.vel.r();
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

  // canBackDashChase, goalie branch: back dashes up to 14 cycles while the ball ends within
  // 21 m of the goal and stamina allows.
  bool can_back_dash_chase(int cycle, double angle_diff) const {
    if (angle_diff < kBackDashThrAngle) {
      return false;
    }
    if (cycle >= 5) {
      if (cycle >= 15) {
        return false;
      }
      const Vec2 goal{-kPitchHalfLength, 0.0};
      if (dist(goal, ball_inertia(cycle)) > 21.0) {
        return false;
      }
    }
    const double total_consume = -kMinDashPower * 2.0 * cycle;
    const double total_recover = kStaminaIncMax * s_.recovery * (cycle - 1);
    return s_.stamina - total_consume + total_recover >= kRecoverDecThrValue + 205.0;
  }

  // canReachAfterDash: full-power dashes (less when stamina runs short) along `dash_angle`.
  bool can_reach_after_dash(int n_turn, int n_dash, Vec2 ball_pos, double control_area, bool save_recovery,
                            double dash_angle, bool back_dash) {
    const double player_noise_rate = 1.0 - w_.player_rand * 0.01;
    const double max_power = kMaxDashPower;
    const Vec2 my_inertia = self_inertia(n_turn + n_dash);
    const double recover_dec_thr = kRecoverDecThrValue;
    const Vec2 ball_rel = rotated(ball_pos - s_.pos, -dash_angle);
    const double ball_noise = dist(w_.ball_pos, ball_pos) * w_.ball_rand * 0.5;
    const double noised_ball_x = ball_rel.x + ball_noise;
    Vec2 tmp_pos = rotated(player_inertia_travel(s_.vel, n_turn), -dash_angle);
    Vec2 tmp_vel = rotated(s_.vel * std::pow(kPlayerDecay, n_turn), -dash_angle);
    Stamina st(s_);
    st.waits(n_turn);
    const double prev_effort = st.effort;  // librcsc never updates it in the loop
    double dash_power_abs = max_power;
    double dash_accel_x = dash_power_abs * st.dash_rate();
    bool over_speed = can_over_speed_max(dash_power_abs, st.effort);
    double first_dash_power = dash_power_abs * (back_dash ? -1.0 : 1.0);
    const auto mode_now = [&] {
      return st.recovery < s_.recovery && !st.capacity_is_empty() ? Mode::kExhaust : Mode::kNormal;
    };
    for (int i = 0; i < n_dash; ++i) {
      double available = save_recovery ? std::max(0.0, st.stamina - recover_dec_thr) : st.stamina + kExtraStamina;
      if (back_dash) {
        available *= 0.5;
      }
      available = bound(0.0, available, max_power);
      if (available < dash_power_abs || st.effort < prev_effort || (!over_speed && dash_power_abs < available)) {
        dash_power_abs = available;
        dash_accel_x = dash_power_abs * st.dash_rate();
        over_speed = can_over_speed_max(dash_power_abs, st.effort);
        if (i == 0) {
          first_dash_power = dash_power_abs * (back_dash ? -1.0 : 1.0);
        }
      }
      tmp_vel.x += dash_accel_x;
      if (over_speed && tmp_vel.r2() > kPlayerSpeedMax2) {
        tmp_vel.x -= dash_accel_x;
        const double max_dash_x = std::sqrt(kPlayerSpeedMax2 - tmp_vel.y * tmp_vel.y);
        dash_accel_x = max_dash_x - tmp_vel.x;
        dash_power_abs = std::fabs(dash_accel_x / st.dash_rate());
        tmp_vel.x += dash_accel_x;
        over_speed = can_over_speed_max(dash_power_abs, st.effort);
      }
      tmp_pos += tmp_vel;
      tmp_vel *= kPlayerDecay;
      st.dash(dash_power_abs * (back_dash ? -1.0 : 1.0));
      if (tmp_pos.x * player_noise_rate + 0.1 > noised_ball_x) {
        // Run past the ball's point: the final position is projected onto the ball.
        Vec2 my_final = s_.pos + rotated(tmp_pos, dash_angle);
        if (dist2(my_inertia, my_final) > 0.01) {
          my_final = line_projection(my_inertia, my_final, ball_pos);
        }
        st.waits(n_dash - (i + 1));
        push(make_info(mode_now(), n_turn, n_dash, first_dash_power, 0.0, my_final, dist(my_final, ball_pos),
                       st.stamina));
        return true;
      }
    }
    const double player_travel = tmp_pos.r();
    const double player_noise = player_travel * w_.player_rand * 0.5;
    const double last_ball_dist = dist(ball_rel, tmp_pos);
    const double buf = 0.2 + player_noise + ball_noise;
    if (last_ball_dist < std::max(control_area - 0.225, control_area - buf)) {
      const Vec2 my_final = s_.pos + rotated(tmp_pos, dash_angle);
      push(
          make_info(mode_now(), n_turn, n_dash, first_dash_power, 0.0, my_final, dist(my_final, ball_pos), st.stamina));
      return true;
    }
    return false;
  }

  const GoalieWorld& w_;
  const SelfView& s_;
  InterceptTable* t_;
};

// --- PlayerIntercept (player/player_intercept.cpp), for the attackers ---------------------

// predictTurnCycle: one turn at most. An attacker is no goalie, so its reach is kickable.
int opponent_turn_cycle(const PlayerView& p, int cycle, double control_area, Vec2 ball_pos) {
  const Vec2 target_rel = ball_pos - player_inertia_point(p.pos, p.vel, cycle);
  const double target_dist = target_rel.r();
  double turn_margin = 180.0;
  if (control_area < target_dist) {
    turn_margin = asin_deg(control_area / target_dist);
  }
  turn_margin = std::max(turn_margin, 12.0);
  double angle_diff = std::fabs(angle_norm(th_deg(target_rel) - p.body_deg));
  if (target_dist < 5.0 && angle_diff > 90.0) {  // librcsc: "XXX magic number XXX"
    angle_diff = 180.0 - angle_diff;
  }
  return angle_diff > turn_margin ? 1 : 0;
}

// The extra cycles of a tackling player (tackle_cycles - tackleCount - 2; the count is 0).
int tackle_wait(const PlayerView& p) {
  return p.tackling ? std::max(0, kTackleCycles - 2) : 0;
}

// canReachAfterDash with every accuracy count 0 (the pos_count corrections vanish).
bool opponent_can_reach_after_dash(const PlayerView& p, int n_turn, int max_dash, double control_area, Vec2 ball_pos) {
  const Vec2 player_pos = player_inertia_point(p.pos, p.vel, n_turn + max_dash);
  const double d = dist(ball_pos, player_pos) - control_area;
  if (d < 0.0) {
    return true;
  }
  return cycles_to_reach_distance(d) + tackle_wait(p) <= max_dash;
}

// predictFinal.
int opponent_final(const GoalieWorld& w, const InterceptTable& t, const PlayerView& p) {
  const Vec2 ball_pos = t.ball_cache[static_cast<size_t>(t.ball_cache_size - 1)];
  const int ball_step = t.ball_cache_size;
  const double control_area = kKickableArea;
  const int n_turn = opponent_turn_cycle(p, 100, control_area, ball_pos);
  double dash_dist = dist(player_inertia_point(p.pos, p.vel, 100), ball_pos) - control_area;
  dash_dist -= dist(p.pos, w.self.pos) * 0.03;  // an opponent: distFromSelf x 0.03
  if (dash_dist < 0.0) {
    return ball_step;
  }
  const int n_dash = std::max(1, cycles_to_reach_distance(dash_dist));
  return std::max(ball_step, n_turn + n_dash);
}

// PlayerIntercept::predict.
int predict_opponent(const GoalieWorld& w, const InterceptTable& t, const PlayerView& p, int max_cycle) {
  const Vec2 ball_to_player = rotated(p.pos - w.ball_pos, -th_deg(w.ball_vel));
  int min_cycle = static_cast<int>(std::floor(std::fabs(ball_to_player.y) / kRealSpeedMax));
  min_cycle = std::max(0, min_cycle + tackle_wait(p));
  if (min_cycle > max_cycle) {
    return opponent_final(w, t, p);
  }
  const double control_area = kKickableArea;
  const int max_loop = std::min(max_cycle, t.ball_cache_size);
  for (int cycle = min_cycle; cycle < max_loop; ++cycle) {
    const Vec2 ball_pos = t.ball_cache[static_cast<size_t>(cycle)];
    if (control_area + kRealSpeedMax * cycle + 0.5 < dist(p.pos, ball_pos)) {
      continue;
    }
    const int n_turn = opponent_turn_cycle(p, cycle, control_area, ball_pos);
    const int n_dash = cycle - n_turn;
    if (n_dash >= 0 && opponent_can_reach_after_dash(p, n_turn, n_dash, control_area, ball_pos)) {
      return cycle;
    }
  }
  return opponent_final(w, t, p);
}

// InterceptTable::createBallCache.
void create_ball_cache(const GoalieWorld& w, InterceptTable* t) {
  constexpr double kPitchXMax = kPitchHalfLength + 5.0;
  constexpr double kPitchYMax = kPitchHalfWidth + 5.0;
  Vec2 bpos = w.ball_pos;
  Vec2 bvel = w.ball_vel;
  t->ball_cache[0] = bpos;
  t->ball_cache_size = 1;
  if (w.self_kickable) {
    return;
  }
  for (int i = 1; i <= InterceptTable::kMaxCycle; ++i) {
    bpos += bvel;
    bvel *= kBallDecay;
    t->ball_cache[static_cast<size_t>(t->ball_cache_size++)] = bpos;
    if (i >= 5 && bvel.r2() < 0.01 * 0.01) {
      break;
    }
    if (std::fabs(bpos.x) > kPitchXMax || std::fabs(bpos.y) > kPitchYMax) {
      break;
    }
  }
  if (t->ball_cache_size == 1) {
    t->ball_cache[static_cast<size_t>(t->ball_cache_size++)] = bpos;
  }
}

}  // namespace

void predict_intercepts(const GoalieWorld& w, InterceptTable* t) {
  *t = InterceptTable{};
  create_ball_cache(w, t);

  // InterceptTable::predictSelf.
  if (w.self_kickable) {
    t->self_reach_cycle = 0;
  } else {
    SelfIntercept(w, t).predict(std::min(InterceptTable::kMaxCycle, t->ball_cache_size));
    // librcsc stops at the first entry of the sorted cache whatever its mode: a first entry
    // in exhaust mode leaves the normal reach at 1000.
    for (int i = 0; i < t->self_cache_size; ++i) {
      const InterceptInfo& info = t->self_cache[static_cast<size_t>(i)];
      if (info.mode == Mode::kNormal && info.reach_cycle() < t->self_reach_cycle) {
        t->self_reach_cycle = info.reach_cycle();
        break;
      }
      if (info.mode == Mode::kExhaust && info.reach_cycle() < t->self_exhaust_reach_cycle) {
        t->self_exhaust_reach_cycle = info.reach_cycle();
        break;
      }
    }
  }

  // InterceptTable::predictOpponent: 0 with a kickable opponent; else each opponent (sorted by
  // distance to the ball) searched up to the second-best reach so far.
  if (w.exist_kickable_opponent) {
    t->opponent_reach_cycle = 0;
    return;
  }
  int min_cycle = 1000;
  int second_min_cycle = 1000;
  for (int i = 0; i < w.num_opponents; ++i) {
    const int cycle = predict_opponent(w, *t, w.opponents[static_cast<size_t>(i)], second_min_cycle);
    if (cycle < second_min_cycle) {
      second_min_cycle = cycle;
      if (second_min_cycle < min_cycle) {
        std::swap(min_cycle, second_min_cycle);
      }
    }
  }
  if (min_cycle < 1000) {
    t->opponent_reach_cycle = min_cycle;
  }
}

// --- Body_Intercept2009 (action/body_intercept2009.cpp) -----------------------------------

namespace {

// Body_Intercept2009 with no face point given (M_face_point invalid): the default face point.
Vec2 default_face_point(const GoalieWorld& w, double y_rate) {
  return {50.5, w.self.pos.y * y_rate};
}

// WorldModel::offsideLineX for the goalie's opponents: the second-deepest opponent's x, no
// lower than 0 (WorldModel::updateTheirDefenseLine with every count 0). librcsc smooths the
// line over past cycles and corrects it near their penalty area; that history is not here.
double offside_line_x(const GoalieWorld& w) {
  double first = 0.0;
  double second = 0.0;
  for (int i = 0; i < w.num_opponents; ++i) {
    const PlayerView& p = w.opponents[static_cast<size_t>(i)];
    double x = p.pos.x;
    if (p.vel.x > 0.0) {
      x += std::min(0.8, p.vel.x / kPlayerDecay);
    }
    if (x > second) {
      second = x;
      if (second > first) {
        std::swap(first, second);
      }
    }
  }
  return second;
}

// Body_Intercept2009::doKickableOpponentCheck: an opponent controls the ball close by and
// stands no nearer to the goal than the goalie: go at its next position.
bool kickable_opponent_check(const GoalieWorld& w, Command* out) {
  if (w.ball_dist_from_self < 2.0 && w.exist_kickable_opponent && w.num_opponents > 0) {
    const PlayerView& opp = w.opponents[0];
    const Vec2 goal{-kPitchHalfLength, 0.0};
    const Vec2 my_next = w.self.pos + w.self.vel;
    const Vec2 attack_pos = opp.pos + opp.vel;
    if (dist2(attack_pos, goal) > dist2(my_next, goal)) {
      body_go_to_point(w, attack_pos, 0.1, kMaxDashPower, -1.0, 1, true, 15.0, out);
      return true;
    }
  }
  return false;
}

// Body_Intercept2009::getBestIntercept, the goalie's branches included.
const InterceptInfo* best_intercept(const GoalieWorld& w, const InterceptTable& t, bool save_recovery) {
  static const InterceptInfo kNone{};
  if (t.self_cache_size == 0) {
    return &kNone;
  }
  const Vec2 goal_pos{65.0, 0.0};
  const Vec2 our_goal_pos{-kPitchHalfLength, 0.0};
  const double max_pitch_x = kPitchHalfLength - 1.0;
  const double max_pitch_y = kPitchHalfWidth - 1.0;
  const double penalty_x = kOurPenaltyLineX;
  const double penalty_y = kPenaltyHalfWidth;
  const double speed_max = kRealSpeedMax * 0.9;
  const int opp_min = t.opponent_reach_cycle;
  const int mate_min = t.teammate_reach_cycle;
  const double offside_x = offside_line_x(w);

  const InterceptInfo* attacker_best = nullptr;
  double attacker_score = 0.0;
  const InterceptInfo* forward_best = nullptr;
  double forward_score = 0.0;
  const InterceptInfo* noturn_best = nullptr;
  double noturn_score = 10000.0;
  const InterceptInfo* nearest_best = nullptr;
  double nearest_score = 10000.0;
  const InterceptInfo* goalie_best = nullptr;
  double goalie_score = -10000.0;
  const InterceptInfo* goalie_aggressive_best = nullptr;
  double goalie_aggressive_score = -10000.0;

  for (int i = 0; i < t.self_cache_size; ++i) {
    const InterceptInfo& c = t.self_cache[static_cast<size_t>(i)];
    if (save_recovery && c.mode != Mode::kNormal) {
      continue;
    }
    const int cycle = c.reach_cycle();
    const Vec2 self_pos = self_inertia_point(w, cycle);
    const Vec2 ball_pos = ball_inertia_point(w, cycle);
    const Vec2 ball_vel = w.ball_vel * std::pow(kBallDecay, cycle);
    if (std::fabs(ball_pos.x) > max_pitch_x || std::fabs(ball_pos.y) > max_pitch_y) {
      continue;
    }
    // Inside its penalty area, before the opponent: the catch farthest from the goal.
    if (ball_pos.x < penalty_x - 1.0 && std::fabs(ball_pos.y) < penalty_y - 1.0 && cycle < opp_min - 1) {
      if ((c.turn_cycle == 0 && c.ball_dist < kCatchableArea * 0.5) || c.ball_dist < 0.01) {
        const double d = dist2(ball_pos, our_goal_pos);
        if (d > goalie_score) {
          goalie_score = d;
          goalie_best = &c;
        }
      }
    }
    // Outside it, well before everyone: the kick point farthest up the field.
    if (cycle < mate_min - 3 && cycle < opp_min - 5 &&
        (ball_pos.x > penalty_x - 1.0 || std::fabs(ball_pos.y) > penalty_y - 1.0)) {
      if ((c.turn_cycle == 0 && c.ball_dist < kKickableArea * 0.5) || c.ball_dist < 0.01) {
        if (ball_pos.x > goalie_aggressive_score) {
          goalie_aggressive_score = ball_pos.x;
          goalie_aggressive_best = &c;
        }
      }
    }
    const bool attacker = ball_vel.x > 0.5 && ball_vel.r2() > std::pow(speed_max, 2) && c.dash_power >= 0.0 &&
                          ball_pos.x < 47.0 && (ball_pos.x > 35.0 || ball_pos.x > offside_x);
    const double opp_rate = attacker ? 0.95 : 0.7;
    if (cycle >= opp_min * opp_rate) {
      continue;
    }
    if (attacker) {
      const double goal_dist = 100.0 - std::min(100.0, dist(ball_pos, goal_pos));
      const double x_diff = 47.0 - ball_pos.x;
      const double score = (goal_dist / 100.0) * std::exp(-(x_diff * x_diff) / (2.0 * 100.0));
      if (score > attacker_score) {
        attacker_best = &c;
        attacker_score = score;
      }
      continue;
    }
    if (c.turn_cycle == 0) {
      const double score = cycle;
      if (score < noturn_score) {
        noturn_best = &c;
        noturn_score = score;
      }
      continue;
    }
    if (ball_vel.x > 0.1 && cycle <= opp_min - 5 && ball_vel.r2() > std::pow(0.6, 2)) {
      const double score = 100.0 * 100.0 - std::min(100.0 * 100.0, dist2(ball_pos, goal_pos));
      if (score > forward_score) {
        forward_best = &c;
        forward_score = score;
      }
      continue;
    }
    const double d = dist2(self_pos, ball_pos);
    if (d < nearest_score) {
      nearest_best = &c;
      nearest_score = d;
    }
  }

  if (goalie_aggressive_best != nullptr) {
    return goalie_aggressive_best;
  }
  if (goalie_best != nullptr) {
    return goalie_best;
  }
  if (attacker_best != nullptr) {
    return attacker_best;
  }
  if (noturn_best != nullptr && forward_best != nullptr) {
    const Vec2 noturn_ball_vel = w.ball_vel * std::pow(kBallDecay, noturn_best->reach_cycle());
    const double noturn_ball_speed = noturn_ball_vel.r();
    if (noturn_ball_vel.x > 0.1 &&
        (noturn_ball_speed > speed_max || noturn_best->reach_cycle() <= forward_best->reach_cycle() + 2)) {
      return noturn_best;
    }
  }
  if (forward_best != nullptr) {
    return forward_best;
  }
  const InterceptInfo& fastest = t.self_cache[0];
  const Vec2 fastest_pos = ball_inertia_point(w, fastest.reach_cycle());
  const Vec2 fastest_vel = w.ball_vel * std::pow(kBallDecay, fastest.reach_cycle());
  if ((fastest_pos.x > -33.0 || std::fabs(fastest_pos.y) > 20.0) &&
      (fastest.reach_cycle() >= 10 || fastest_vel.r() < 1.2)) {
    return &fastest;
  }
  if (noturn_best != nullptr && nearest_best != nullptr) {
    const Vec2 noturn_self_pos = self_inertia_point(w, noturn_best->reach_cycle());
    const Vec2 noturn_ball_pos = ball_inertia_point(w, noturn_best->reach_cycle());
    const Vec2 nearest_self_pos = self_inertia_point(w, nearest_best->reach_cycle());
    const Vec2 nearest_ball_pos = ball_inertia_point(w, nearest_best->reach_cycle());
    if (dist2(noturn_self_pos, noturn_ball_pos) < dist2(nearest_self_pos, nearest_ball_pos)) {
      return noturn_best;
    }
    if (nearest_best->reach_cycle() <= noturn_best->reach_cycle() + 2) {
      const Vec2 nearest_ball_vel = w.ball_vel * std::pow(kBallDecay, nearest_best->reach_cycle());
      const double nearest_ball_speed = nearest_ball_vel.r();
      if (nearest_ball_speed < 0.7) {
        return nearest_best;
      }
      const Vec2 noturn_ball_vel = w.ball_vel * std::pow(kBallDecay, noturn_best->reach_cycle());
      if (nearest_best->ball_dist < kKickableArea - 0.4 && nearest_best->ball_dist < noturn_best->ball_dist &&
          noturn_ball_vel.x < 0.5 && noturn_ball_vel.r2() > std::pow(1.0, 2) &&
          noturn_ball_pos.x > nearest_ball_pos.x) {
        return nearest_best;
      }
      if (nearest_ball_speed > 0.7 && dist(nearest_self_pos, nearest_ball_pos) < kKickableArea) {
        return nearest_best;
      }
    }
    return noturn_best;
  }
  if (noturn_best != nullptr) {
    return noturn_best;
  }
  if (nearest_best != nullptr) {
    return nearest_best;
  }
  if (w.self.pos.x > 40.0 && w.ball_vel.r() > 1.8 && std::fabs(th_deg(w.ball_vel)) < 100.0 &&
      fastest.reach_cycle() > 1) {
    const InterceptInfo* chance_best = nullptr;
    for (int i = 0; i < t.self_cache_size; ++i) {
      const InterceptInfo& c = t.self_cache[static_cast<size_t>(i)];
      if (c.reach_cycle() <= fastest.reach_cycle() + 3 && c.reach_cycle() <= opp_min - 2) {
        chance_best = &c;
      }
    }
    if (chance_best != nullptr) {
      return chance_best;
    }
  }
  return &fastest;
}

// Body_Intercept2009::doWaitTurn: the ball will come into reach on the body's side line
// anyway: turn to face a useful direction instead of dashing.
bool wait_turn(const GoalieWorld& w, const InterceptTable& t, Vec2 target_point, const InterceptInfo& info,
               Command* out) {
  // WorldModel::getOpponentNearestToSelf(5): every opponent is seen this cycle.
  for (int i = 0; i < w.num_opponents; ++i) {
    if (dist(w.opponents[static_cast<size_t>(i)].pos, w.self.pos) < 3.0) {
      return false;
    }
  }
  if (info.reach_cycle() > t.opponent_reach_cycle - 5) {
    return false;
  }
  const Vec2 my_inertia = self_inertia_point(w, info.reach_cycle());
  const Vec2 target_rel = rotated(target_point - my_inertia, -w.self.body_deg);
  const double target_dist = target_rel.r();
  // inertia_n_step_distance of the ball.
  const double ball_travel = w.ball_vel.r() * (1.0 - std::pow(kBallDecay, info.reach_cycle())) / (1.0 - kBallDecay);
  const double ball_noise = ball_travel * w.ball_rand;
  if (info.reach_cycle() == 1 && info.turn_cycle == 1) {
    body_turn_to_point(w, default_face_point(w, 0.9), 1, out);
    return true;
  }
  double extra_buf = 0.1 * bound(0, info.reach_cycle() - 1, 4);
  {
    const double angle_diff = std::fabs(angle_norm(th_deg(w.ball_vel) - w.self.body_deg));
    if (angle_diff < 10.0 || 170.0 < angle_diff) {
      extra_buf = 0.0;
    }
  }
  const double dist_buf = kKickableArea - 0.3 + extra_buf;  // less 0.1 x the ball's count (0)
  if (target_dist > dist_buf) {
    return false;
  }
  Vec2 face_point = default_face_point(w, 0.9);
  if (info.reach_cycle() > 2) {
    face_point = my_inertia + rotated(w.ball_pos - my_inertia, 90.0);
    if (face_point.x < my_inertia.x) {
      face_point = my_inertia + rotated(w.ball_pos - my_inertia, -90.0);
    }
  }
  const double face_angle = th_deg(face_point - my_inertia);
  // librcsc rotates by +face_angle here (not -face_angle); kept as it is.
  const Vec2 faced_rel = rotated(target_point - my_inertia, face_angle);
  if (std::fabs(faced_rel.y) > kKickableArea - ball_noise - 0.2) {
    return false;
  }
  body_turn_to_point(w, face_point, 1, out);
  return true;
}

// Body_Intercept2009::doInertiaDash (the goalie skips the field player's target buffer).
bool inertia_dash(const GoalieWorld& w, Vec2 target_point, const InterceptInfo& info, bool save_recovery,
                  Command* out) {
  if (info.reach_cycle() == 1) {
    *out = do_dash(w, info.dash_power, info.dash_angle_deg);
    return true;
  }
  const Vec2 target_rel = rotated(target_point - w.self.pos, -w.self.body_deg);
  double used_power = info.dash_power;
  const double ball_speed_then = w.ball_vel.r() * std::pow(kBallDecay, info.reach_cycle());
  if (ball_speed_then < kKickableArea * 1.5 && std::fabs(info.dash_angle_deg) < 5.0 &&
      std::fabs(target_rel.x) < kKickableArea + w.self.effort * kDashPowerRate * kMaxDashPower * 0.8) {
    // Dash just enough to stop on the target when the ball arrives.
    double first_speed = first_term_geom_series(target_rel.x, kPlayerDecay, info.reach_cycle());
    first_speed = bound(-kPlayerSpeedMax, first_speed, kPlayerSpeedMax);
    const Vec2 rel_vel = rotated(w.self.vel, -w.self.body_deg);
    used_power = (first_speed - rel_vel.x) / (w.self.effort * kDashPowerRate);
    used_power /= dir_rate(info.dash_angle_deg);
    used_power = clamp(used_power, kMinDashPower, kMaxDashPower);  // normalizeDashPower
    if (save_recovery) {
      used_power = safety_dash_power(w, used_power);
    }
  }
  if (info.reach_cycle() >= 4 && (std::fabs(target_rel.x) < 0.5 || std::fabs(used_power) < 5.0)) {
    // Nearly there early: turn to the face point, or across when the ball would leave the view.
    const Vec2 my_inertia = self_inertia_point(w, info.reach_cycle());
    Vec2 face_point = default_face_point(w, 0.75);
    const double face_angle = th_deg(face_point - my_inertia);
    const Vec2 ball_next = w.ball_pos + w.ball_vel;
    const double ball_angle = th_deg(ball_next - my_inertia);
    // ServerParam::maxNeckAngle (90) + ViewWidth::width(NORMAL) - 10. HFO's players run with
    // synch_see (bin/teams/base/config/player.conf), where the normal width is
    // visible_angle x 2 x simulator_step / send_step = 90 x 2 x 100 / 150 = 120.
    constexpr double kViewLimitDeg = 90.0 + 120.0 - 10.0;
    if (std::fabs(angle_norm(ball_angle - face_angle)) > kViewLimitDeg) {
      face_point.x = my_inertia.x;
      if (ball_next.y > my_inertia.y + 1.0) {
        face_point.y = 50.0;
      } else if (ball_next.y < my_inertia.y - 1.0) {
        face_point.y = -50.0;
      } else {
        face_point = ball_next;
      }
    }
    body_turn_to_point(w, face_point, 1, out);
    return true;
  }
  *out = do_dash(w, used_power, info.dash_angle_deg);
  return true;
}

}  // namespace

bool body_intercept(const GoalieWorld& w, const InterceptTable& t, bool save_recovery, Command* out) {
  *out = Command{};
  if (kickable_opponent_check(w, out)) {
    return true;
  }
  if (t.self_reach_cycle > 100) {
    // No way to the ball: go where it stops (Body_GoToPoint's defaults).
    const Vec2 final_point = w.ball_pos + w.ball_vel * (1.0 / (1.0 - kBallDecay));
    body_go_to_point(w, final_point, 2.0, kMaxDashPower, -1.0, 100, true, 15.0, out);
    return true;
  }
  const InterceptInfo& best = *best_intercept(w, t, save_recovery);
  const Vec2 target_point = ball_inertia_point(w, best.reach_cycle());
  if (best.dash_cycle == 0) {
    body_turn_to_point(w, default_face_point(w, 0.75), best.reach_cycle(), out);
    return true;
  }
  if (best.turn_cycle > 0) {
    const Vec2 my_inertia = self_inertia_point(w, best.reach_cycle());
    double target_angle = th_deg(target_point - my_inertia);
    if (best.dash_power < 0.0) {
      target_angle = angle_norm(target_angle - 180.0);
    }
    *out = do_turn(w, angle_norm(target_angle - w.self.body_deg));
    return true;
  }
  if (wait_turn(w, t, target_point, best, out)) {
    return true;
  }
  if (save_recovery && !(w.self.capacity <= 1.0e-5 && w.self.capacity >= 0.0)) {
    const double consumed = best.dash_power < 0.0 ? best.dash_power * -2.0 : best.dash_power;
    if (w.self.stamina - consumed < kRecoverDecThrValue + 1.0) {
      // librcsc issues a zero turn and reports failure.
      *out = do_turn(w, 0.0);
      return false;
    }
  }
  return inertia_dash(w, target_point, best, save_recovery, out);
}

}  // namespace pamdp::hfo::agent2d
