// Sources cited below by file and function: gym-goal = github.com/cycraig/gym-goal at 8e142be,
// gym_goal/envs/{goal_env.py, config.py, util.py}; MP-DQN = github.com/cycraig/MP-DQN,
// common/goal_domain.py and common/wrappers.py. The arithmetic keeps gym-goal's order of
// operations, so that the same noise draws give the same trajectory up to libm rounding.
#include "envs/goal/goal_env.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

namespace pamdp::goal {
namespace {

constexpr double kPi = std::numbers::pi;

// config.py: the pitch (a half pitch: x in [0, kPitchLength / 2]) and the goal.
constexpr double kPitchLength = 40.0;
constexpr double kPitchWidth = 30.0;
constexpr double kGoalWidth = 14.02;
constexpr double kGoalDepth = 2.44;
constexpr double kGoalAreaLength = 5.5;
constexpr double kGoalAreaWidth = 18.32;
constexpr double kGoalLineX = kPitchLength / 2;
constexpr double kMinPower = -100.0;
constexpr double kMaxPower = 100.0;
constexpr double kCatchable = 2.0;
constexpr double kInertiaMoment = 5.0;

// config.py PLAYER_CONFIG and BALL_CONFIG (MASS is unused there too).
struct EntityKind {
  double power_rate;
  double size;
  double rand;
  double accel_max;
  double speed_max;
  double decay;
};
constexpr EntityKind kPlayer{0.006, 0.9, 0.1, 1.0, 1.0, 0.4};
constexpr EntityKind kBall{0.027, 0.4, 0.05, 2.7, 2.7, 0.94};
// config.py KICKABLE, written as there so that the sum rounds the same way.
constexpr double kKickable = kPlayer.size + 0.7;

// goal_env.py GoalEnv.step: a kick-to decision ends once the ball is this slow and kickable.
constexpr double kSettledBallSpeed = 0.1;
// goal_env.py Player.to_ball dashes with this power.
constexpr double kChasePower = 10.0;
// goal_env.py Goalie.move: powers for intercepting a shot and for chasing the ball's rest point.
constexpr double kKeeperInterceptPower = 20.0;
constexpr double kKeeperChasePower = 8.0;
// goal_env.py GoalEnv.reset: the ball starts this far inside the kick range.
constexpr double kStartInset = 1e-12;

// goal_env.py PARAMETERS_MIN / PARAMETERS_MAX.
constexpr double kKickToXLo = 0.0;
constexpr double kKickToXHi = kPitchLength;
constexpr double kKickToYLo = -kPitchWidth / 2;
constexpr double kKickToYHi = kPitchWidth / 2;
constexpr double kShootYLo = -kGoalWidth / 2;
constexpr double kShootYHi = kGoalWidth / 2;

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "GoalEnv: %s\n", what);
  std::abort();
}

Vec2 operator+(Vec2 a, Vec2 b) {
  return {a.x + b.x, a.y + b.y};
}
Vec2 operator-(Vec2 a, Vec2 b) {
  return {a.x - b.x, a.y - b.y};
}
Vec2 operator*(double s, Vec2 v) {
  return {s * v.x, s * v.y};
}
double norm(Vec2 v) {
  return std::sqrt(v.x * v.x + v.y * v.y);
}
double distance(const Body& a, const Body& b) {
  return norm(a.position - b.position);
}
// util.py angle_between and angle_position.
double angle_between(Vec2 from, Vec2 to) {
  const Vec2 d = to - from;
  return std::atan2(d.y, d.x);
}
Vec2 unit(double theta) {
  return {std::cos(theta), std::sin(theta)};
}
// util.py norm_angle: into [-pi, pi] by whole turns.
double norm_angle(double angle) {
  while (angle > kPi) {
    angle -= 2 * kPi;
  }
  while (angle < -kPi) {
    angle += 2 * kPi;
  }
  return angle;
}
// util.py angle_close.
bool angle_close(double a, double b) {
  return std::fabs(norm_angle(a - b)) < kPi / 8;
}
// util.py bound and bound_vector (per component).
double bound(double v, double lo, double hi) {
  return v < lo ? lo : (v > hi ? hi : v);
}
Vec2 bound_vector(Vec2 v, double max) {
  return {bound(v.x, -max, max), bound(v.y, -max, max)};
}
// A parameter clamped to its range; NaN becomes the midpoint so the state stays finite.
double clamp_param(float value, double lo, double hi) {
  return std::isnan(value) ? (lo + hi) / 2 : bound(static_cast<double>(value), lo, hi);
}

// Everything the rules need to move bodies: the bodies and the noise source.
struct World {
  GoalState& s;
  Rng& rng;
  bool noise;

  // goal_env.py Entity.accelerate.
  void accelerate(Body& body, const EntityKind& kind, double power, double theta) const {
    Vec2 noise_vec;
    if (noise) {
      theta = (1 + rng.uniform(-kind.rand, kind.rand)) * theta;
      const double rmax = kind.rand * norm(body.velocity);
      noise_vec.x = rng.uniform(-rmax, rmax);
      noise_vec.y = rng.uniform(-rmax, rmax);
    }
    const double rate = power * kind.power_rate;
    const Vec2 accel = bound_vector(rate * unit(theta) + noise_vec, kind.accel_max);
    body.velocity = bound_vector(body.velocity + accel, kind.speed_max);
  }

  // goal_env.py Player.can_kick and Player.kick_power.
  [[nodiscard]] bool can_kick() const { return distance(s.striker, s.ball) <= kKickable; }
  [[nodiscard]] double kick_power() const {
    const double angle = angle_between(s.striker.position, s.ball.position);
    const double dir_diff = std::fabs(norm_angle(angle - s.striker.orientation_rad));
    return 1 - 0.25 * dir_diff / kPi - 0.25 * distance(s.striker, s.ball) / kKickable;
  }

  // goal_env.py Player.turn, face_angle, dash, to_ball.
  void face(double angle) const {
    Body& p = s.striker;
    const double moment = norm_angle(angle - p.orientation_rad);
    p.orientation_rad = p.orientation_rad + moment / (1 + kInertiaMoment * norm(p.velocity));
  }
  void to_ball() const {
    const double angle = angle_between(s.striker.position, s.ball.position);
    if (!angle_close(s.striker.orientation_rad, angle)) {
      face(angle);
    } else if (!can_kick()) {
      accelerate(s.striker, kPlayer, bound(kChasePower, kMinPower, kMaxPower), s.striker.orientation_rad);
    }
  }

  // goal_env.py Player.kick_to, kick_towards and kick_ball: the kick that would bring the ball
  // to rest at `target` measured from the striker's position (as there, not the ball's).
  void kick_to(Vec2 target) const {
    if (!can_kick()) {
      to_ball();
      return;
    }
    const Vec2 accel = (1 - kBall.decay) * (target - s.striker.position) - s.ball.velocity;
    const double weight = kick_power();  // gym-goal computes it twice, from the same state
    const double power = norm(accel) / (weight * kBall.power_rate);
    const double theta = std::atan2(accel.y, accel.x);
    const double direction = theta - s.striker.orientation_rad;
    const double applied = bound(power, kMinPower, kMaxPower) * weight;
    accelerate(s.ball, kBall, applied, s.striker.orientation_rad + direction);
  }

  // goal_env.py Goalie.move and move_towards: intercept a shot heading for the goal, else chase
  // the point where the ball will come to rest.
  void move_keeper() const {
    Body& k = s.keeper;
    const Body& b = s.ball;
    const double rest_factor = 1 - kBall.decay;
    const Vec2 ball_end{b.position.x + b.velocity.x / rest_factor, b.position.y + b.velocity.y / rest_factor};
    const Vec2 diff = ball_end - b.position;
    const double grad = diff.x != 0.0 ? diff.y / diff.x : 0.0;
    const double yint = b.position.y - grad * b.position.x;
    const double goal_y = grad * kGoalLineX + yint;
    const double reach = kGoalWidth / 2 + kCatchable;
    if (ball_end.x > kGoalLineX && -reach <= goal_y && goal_y <= reach && grad != 0.0) {
      const double grad2 = -1 / grad;
      const double yint2 = k.position.y - grad2 * k.position.x;
      const double ballx = (yint2 - yint) / (grad - grad2);
      // Accelerating leaves the position, so the bearing serves for both.
      const double bearing = angle_between(k.position, {ballx, grad * ballx + yint});
      accelerate(k, kPlayer, kKeeperInterceptPower, bearing);
      k.orientation_rad = bearing;
    } else {
      const double bearing = angle_between(k.position, ball_end);
      k.orientation_rad = bearing;
      accelerate(k, kPlayer, kKeeperChasePower, bearing);
    }
  }
};

// goal_env.py Entity.update.
void advance(Body& body, const EntityKind& kind) {
  body.position = body.position + body.velocity;
  body.velocity = kind.decay * body.velocity;
}

// goal_env.py Entity.colliding and Entity.decollide: push overlapping bodies apart along the
// line between them and reverse both velocities.
void decollide(Body& a, double size_a, Body& b, double size_b) {
  const double dist = distance(a, b);
  if (!(dist < size_a + size_b)) {
    return;
  }
  const double overlap = (size_a + size_b - dist) / 2;
  const double theta_ab = angle_between(a.position, b.position);
  const double theta_ba = angle_between(b.position, a.position);
  a.position = a.position + overlap * unit(theta_ba);
  b.position = b.position + overlap * unit(theta_ab);
  a.velocity = -1.0 * a.velocity;
  b.velocity = -1.0 * b.velocity;
}

// goal_env.py Ball.goal_distance: distance to the goal mouth, 0 inside it.
double goal_distance(Vec2 ball) {
  const double half = kGoalWidth / 2;
  if (ball.x < kGoalLineX) {
    if (ball.y < -half) {
      return norm(ball - Vec2{kGoalLineX, -half});
    }
    if (ball.y > half) {
      return norm(ball - Vec2{kGoalLineX, half});
    }
    return kGoalLineX - ball.x;
  }
  if (ball.y < -half) {
    return half - ball.y;
  }
  if (ball.y > half) {
    return ball.y - half;
  }
  return 0.0;
}

bool in_area(Vec2 p, double left, double right, double bottom, double top) {
  return left <= p.x && p.x <= right && bottom <= p.y && p.y <= top;
}

// goal_env.py GoalEnv._keeper_target: where the keeper stands to guard against a ball at rest.
Vec2 keeper_target(Vec2 ball) {
  const double grad = -ball.y / (kGoalLineX - ball.x);
  const double yint = ball.y - grad * ball.x;
  double xval = ball.x;
  if (ball.x >= kGoalLineX - kGoalAreaLength) {
    xval = ball.y < -kGoalAreaWidth / 2 ? (-kGoalAreaWidth / 2 - yint) / grad : (kGoalAreaWidth / 2 - yint) / grad;
  }
  xval = bound(xval, kGoalLineX - kGoalAreaLength, kGoalLineX);
  const double yval = bound(grad * xval + yint, -kGoalAreaWidth / 2, kGoalAreaWidth / 2);
  return {xval, yval};
}

// MP-DQN GoalObservationWrapper.keeper_projection: where the line through keeper and ball meets
// the goal line, clipped to [-GOAL_WIDTH / 2, GOAL_WIDTH] as there.
double keeper_projection(Vec2 keeper, Vec2 ball) {
  if (keeper.x == ball.x) {
    return keeper.y < ball.y ? -kGoalWidth / 2 : kGoalWidth / 2;
  }
  const double grad = (keeper.y - ball.y) / (keeper.x - ball.x);
  const double yint = ball.y - grad * ball.x;
  return bound(grad * kGoalLineX + yint, -kGoalWidth / 2, kGoalWidth);
}

}  // namespace

GoalEnv::GoalEnv(const GoalConfig& config, uint64_t seed) : config_(config), rng_(seed) {}

const ActionSpace& GoalEnv::action_space() const {
  static const ActionSpace kSpace{
      .actions = {{"KICK_TO", {kKickToX, kKickToY}},
                  {"SHOOT_GOAL_LEFT", {kShootLeftY}},
                  {"SHOOT_GOAL_RIGHT", {kShootRightY}}},
      .params = {{"kick_to_x", static_cast<float>(kKickToXLo), static_cast<float>(kKickToXHi)},
                 {"kick_to_y", static_cast<float>(kKickToYLo), static_cast<float>(kKickToYHi)},
                 {"shoot_left_y", static_cast<float>(kShootYLo), static_cast<float>(kShootYHi)},
                 {"shoot_right_y", static_cast<float>(kShootYLo), static_cast<float>(kShootYHi)}},
  };
  return kSpace;
}

std::string_view GoalEnv::status_name(int status) const {
  switch (status) {
    case kInProgress: return "IN_PROGRESS";
    case kGoal: return "GOAL";
    case kCaught: return "CAUGHT_BY_KEEPER";
    case kOutOfBounds: return "OUT_OF_BOUNDS";
    case kOutOfTime: return "OUT_OF_TIME";
    default: return "UNKNOWN";
  }
}

std::span<const int> GoalEnv::outcomes() const {
  static constexpr std::array<int, 5> kOutcomes{kInProgress, kGoal, kCaught, kOutOfBounds, kOutOfTime};
  return kOutcomes;
}

void GoalEnv::reset(uint64_t seed, std::span<float> obs) {
  rng_.reseed(seed);
  reset(obs);
}

// goal_env.py GoalEnv.reset.
void GoalEnv::reset(std::span<float> obs) {
  GoalState s;
  s.striker.position = {0.0, rng_.uniform(-kPitchWidth / 2, kPitchWidth / 2)};
  s.striker.orientation_rad = angle_between(s.striker.position, {kGoalLineX, 0.0});
  s.ball.position = s.striker.position + (kKickable - kStartInset) * unit(s.striker.orientation_rad);
  s.keeper.position = keeper_target(s.ball.position);
  s.keeper.orientation_rad = angle_between(s.keeper.position, s.ball.position);
  set_state(s, obs);
}

void GoalEnv::set_state(const GoalState& state, std::span<float> obs) {
  state_ = state;
  steps_ = 0;
  last_sim_steps_ = 0;
  write_obs(obs);
}

StepResult GoalEnv::step(const ParamAction& action, std::span<float> obs) {
  if (steps_ < 0) {
    misuse("step() after a terminal status; call reset() first");
  }
  if (action.params.size() < 4) {
    misuse("step(): the parameter vector must hold the 4 Goal parameters");
  }
  Vec2 target;
  switch (action.id) {
    case kKickTo: {
      // goal_env.py GoalEnv._perform_action passes parameters[0], the clipped x alone, as
      // kick_to's target, and numpy broadcasts it against the striker's position: the target is
      // (x, x). Masson's aaai-goal simulator.py does the same. Kept, so that results compare with
      // the published ones: params[kKickToY] is never read.
      const double x = clamp_param(action.params[kKickToX], kKickToXLo, kKickToXHi);
      target = {x, x};
      break;
    }
    case kShootGoalLeft:
    case kShootGoalRight: {
      // goal_env.py Player.shoot_goal: aim one ball radius behind the goal line.
      const int param = action.id == kShootGoalLeft ? kShootLeftY : kShootRightY;
      target = {kGoalLineX + kBall.size, clamp_param(action.params[static_cast<size_t>(param)], kShootYLo, kShootYHi)};
      break;
    }
    default: misuse("step(): action id out of range (0 KICK_TO, 1 SHOOT_GOAL_LEFT, 2 SHOOT_GOAL_RIGHT)");
  }

  StepResult r;
  ++steps_;
  last_sim_steps_ = 0;
  // goal_env.py GoalEnv.step: the step that reaches max_time ends the episode unsimulated.
  if (steps_ == kMaxSteps) {
    r.status = kOutOfTime;
  } else {
    const World w{state_, rng_, config_.noise};
    while (true) {
      ++last_sim_steps_;
      simulate(target);
      r.status = outcome();
      if (r.status != kInProgress) {
        break;
      }
      // A kick-to is done once the striker can kick a settled ball; a shot plays to the end.
      const bool settled = norm(state_.ball.velocity) <= kSettledBallSpeed;
      if (action.id == kKickTo && w.can_kick() && settled) {
        break;
      }
      if (last_sim_steps_ >= kMaxSimStepsPerDecision) {
        r.status = kOutOfTime;
        break;
      }
    }
  }
  // goal_env.py GoalEnv._terminal_check: +50 for a goal, else minus the distance to the goal.
  if (r.status == kGoal) {
    r.reward = 50.0F;
  } else if (r.status != kInProgress) {
    r.reward = static_cast<float>(-goal_distance(state_.ball.position));
  }
  write_obs(obs);
  if (r.status != kInProgress) {
    steps_ = -1;
  }
  return r;
}

// goal_env.py GoalEnv._update: the striker acts, the keeper moves, every body moves and decays,
// then one pass of collisions in the order striker-keeper, striker-ball, keeper-ball.
void GoalEnv::simulate(Vec2 target) {
  const World w{state_, rng_, config_.noise};
  w.kick_to(target);  // KICK_TO and both shots (goal_env.py Player.shoot_goal kicks to a target)
  w.move_keeper();
  advance(state_.striker, kPlayer);
  advance(state_.keeper, kPlayer);
  advance(state_.ball, kBall);
  decollide(state_.striker, kPlayer.size, state_.keeper, kPlayer.size);
  decollide(state_.striker, kPlayer.size, state_.ball, kBall.size);
  decollide(state_.keeper, kPlayer.size, state_.ball, kBall.size);
}

// goal_env.py GoalEnv._terminal_check, Ball.in_net, Ball.in_field, Goalie.can_catch. The catch
// succeeds with CATCH_PROBABILITY = 1.0 (config.py), so no draw is taken for it.
int GoalEnv::outcome() {
  const Vec2 ball = state_.ball.position;
  if (in_area(ball, kGoalLineX, kGoalLineX + kGoalDepth, -kGoalWidth / 2, kGoalWidth / 2)) {
    return kGoal;
  }
  if (distance(state_.keeper, state_.ball) < kCatchable) {
    return kCaught;
  }
  if (!in_area(ball, 0.0, kGoalLineX, -kPitchWidth / 2, kPitchWidth / 2)) {
    return kOutOfBounds;
  }
  return kInProgress;
}

// MP-DQN GoalObservationWrapper (features 14-16) and ScaledStateWrapper (2 (v - low) /
// (high - low) - 1), with low and high from config.py SHIFT_VECTOR and SCALE_VECTOR. One change:
// the striker's orientation is wrapped into [-pi, pi], the range that scaling assumes; gym-goal
// never wraps it (Player.turn), and random play winds it past 2 pi.
void GoalEnv::write_obs(std::span<float> obs) const {
  if (obs.size() != static_cast<size_t>(kObservationSize)) {
    misuse("observation span must hold exactly observation_size() floats");
  }
  const GoalState& s = state_;
  const Vec2 to_ball = s.ball.position - s.keeper.position;
  const double to_ball_norm = norm(to_ball);
  const Vec2 to_ball_unit = to_ball_norm > 0.0 ? (1 / to_ball_norm) * to_ball : Vec2{};
  struct Feature {
    double value;
    double lo;
    double hi;
  };
  const double half_width = kPitchWidth / 2;
  const std::array<Feature, kObservationSize> features{{
      {s.striker.position.x, 0.0, kGoalLineX},
      {s.striker.position.y, -half_width, half_width},
      {s.striker.velocity.x, -1.0, 1.0},
      {s.striker.velocity.y, -1.0, 1.0},
      {norm_angle(s.striker.orientation_rad), -kPi, kPi},  // turning can wind it past +-pi
      {s.keeper.position.x, 0.0, kGoalLineX},
      {s.keeper.position.y, -half_width, half_width},
      {s.keeper.velocity.x, -1.0, 1.0},
      {s.keeper.velocity.y, -1.0, 1.0},
      {s.keeper.orientation_rad, -kPi, kPi},
      {s.ball.position.x, 0.0, kGoalLineX},
      {s.ball.position.y, -half_width, half_width},
      {s.ball.velocity.x, -3.0, 3.0},
      {s.ball.velocity.y, -3.0, 3.0},
      {to_ball_unit.x, -1.0, 1.0},
      {to_ball_unit.y, -1.0, 1.0},
      {keeper_projection(s.keeper.position, s.ball.position), -kGoalWidth / 2, kGoalWidth},
  }};
  constexpr auto kBound = static_cast<double>(kObservationBound);
  for (size_t i = 0; i < features.size(); ++i) {
    const Feature& f = features[i];
    obs[i] = static_cast<float>(std::clamp(2 * (f.value - f.lo) / (f.hi - f.lo) - 1, -kBound, kBound));
  }
}

}  // namespace pamdp::goal
