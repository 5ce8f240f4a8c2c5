#include "envs/hfo/scripted_offense.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "envs/hfo/features.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/hfo_env.hpp"

namespace pamdp::hfo {
namespace {

// Against a goalie: shoot along the best course when its margin (the goalie's cycles to reach
// the line, at kGoalieSpeed after one turning cycle, minus the ball's cycles to pass it) is at
// least kShootMargin, or whatever the margin once the goal centre is within kMustShootRange;
// otherwise dribble with the ball rolling at kDribbleSpeed. The goalie model is pessimistic
// (the referee looks at the ball once per cycle, and the ball is noisy), so a course counts
// down to a margin of -1.5 cycles; the values were tuned for the highest scoring rate.
constexpr double kShootMargin = -1.5;
constexpr double kMustShootRange = 10.0;
constexpr double kGoalieSpeed = 0.8;
constexpr int kShotCourses = 9;
constexpr double kDribbleSpeed = 0.9;
// Aim this far inside a post (ball radius, post radius and a margin for the kick noise).
constexpr double kAimInsidePost = 1.6;
// When to shoot and where to dribble. A shot needs a margin of at least `margin` at
// kRuleDistance from the goal centre, growing by `slope` per metre farther out; the dribble
// rolls the ball at `dribble_speed` toward the point `dribble_offset` of the half mouth from the
// goal centre toward the bottom post. kBestCourse and kBottomPost keep the fixed rule above;
// kBottomSide's was tuned for the highest scoring rate on 10,000-episode sets of starts and
// checked on others (docs/results.md).
// Within `must_shoot_range` of the goal centre it shoots whatever the margin.
struct ShootingRule {
  double margin;
  double slope;
  double dribble_offset;
  double dribble_speed;
  double must_shoot_range = kMustShootRange;
};
constexpr double kRuleDistance = 20.0;
constexpr ShootingRule kFixedRule{kShootMargin, 0.0, 0.0, kDribbleSpeed};
constexpr ShootingRule kBottomSideRule{-1.9, 0.4, 0.25, 0.85};
// kCloseIn and kCloseInPost never shoot on the margin: they dribble at the goal centre with the
// ball rolling at 0.34 m/cycle, a step ahead of the agent, and shoot once within 8 m. Tuned
// against agent2d's goalie (docs/results.md, "A teacher for agent2d's goalie"): a ball rolled
// faster is the goalie's to intercept, and a shot from farther out is its to catch.
constexpr ShootingRule kCloseInRule{std::numeric_limits<double>::infinity(), 0.0, 0.0, 0.34, 8.0};

const ShootingRule& rule_for(ShotAim aim) {
  switch (aim) {
    case ShotAim::kBottomSide: return kBottomSideRule;
    case ShotAim::kCloseIn:
    case ShotAim::kCloseInPost: return kCloseInRule;
    default: return kFixedRule;
  }
}

// Position of a landmark triple (sin, cos, proximity) in the agent's body frame.
Vec2 body_frame(std::span<const float> f, int index) {
  return body_frame_position(f, static_cast<size_t>(index));
}

Vec2 unit(Vec2 v) {
  const double r = v.r();
  return r > 0.0 ? v * (1.0 / r) : Vec2{1.0, 0.0};
}

}  // namespace

ParamAction ScriptedOffense::act(std::span<const float> f) {
  params_.fill(0.0F);
  const double ball_deg = std::atan2(f[feat::kBallAngleSin], f[feat::kBallAngleCos]) * kRadToDeg;
  if (f[feat::kKickable] > 0.0F) {
    // A goalie block is present when its slot is not the all-zero "missing" block.
    const bool goalie = f.size() >= static_cast<size_t>(feature_count(2)) &&
                        (f[kNumAgentFeatures] != 0.0F || f[kNumAgentFeatures + 1] != 0.0F);
    if (goalie) {
      return kick_against_goalie(f);
    }
    const double goal_deg = std::atan2(f[feat::kGoalCentre], f[feat::kGoalCentre + 1]) * kRadToDeg;
    return shot(100.0, goal_deg);
  }
  if (std::fabs(ball_deg) > 10.0) {
    params_[param::kTurnDir] = static_cast<float>(ball_deg);
    return {kTurn, view()};
  }
  params_[param::kDashPower] = 100.0F;
  return {kDash, view()};
}

ParamAction ScriptedOffense::shot(double power, double dir_deg) {
  const bool own = shoot_action_;
  params_[own ? param::kShootPower : param::kKickPower] = static_cast<float>(power);
  params_[own ? param::kShootDir : param::kKickDir] = static_cast<float>(dir_deg);
  return {own ? kShoot : kKick, view()};
}

ParamAction ScriptedOffense::kick_against_goalie(std::span<const float> f) {
  // Everything in the body frame (x ahead, y to the right), from the egocentric features.
  const Vec2 ball = body_frame(f, feat::kBallAngleSin);
  const Vec2 goal = body_frame(f, feat::kGoalCentre);
  const Vec2 post_top = body_frame(f, feat::kGoalPostTop);
  const Vec2 post_bottom = body_frame(f, feat::kGoalPostBottom);
  const Vec2 keeper = body_frame(f, kNumAgentFeatures);
  const Vec2 vb = ball_velocity_in_body_frame(f);

  // Kick acceleration available here (reference §2.7, without noise).
  const double dist = ball.r();
  const double phi = std::fabs(std::atan2(ball.y, ball.x));
  const double gap = std::max(0.0, dist - kPlayerSize - kBallSize);
  const double rate = kKickPowerRate * (1.0 - 0.25 * phi / std::numbers::pi - 0.25 * gap / kKickableMargin);
  const double max_accel = std::min(kBallAccelMax, kMaxKickPower * rate);

  // Shot courses across the mouth: the ball leaves along the course at the largest speed a
  // full-power kick gives (the kick direction corrects for the ball's velocity); the course's
  // margin is the goalie's cycles to reach the line minus the ball's cycles to pass it.
  const Vec2 across = unit(post_bottom - post_top);
  const double mouth = (post_bottom - post_top).r();
  // kBottomPost, kBottomSide and kCloseInPost walk the courses from the bottom post and stop at
  // the first the ball reaches.
  const bool first_reachable =
      aim_ == ShotAim::kBottomPost || aim_ == ShotAim::kBottomSide || aim_ == ShotAim::kCloseInPost;
  const ShootingRule& rule = rule_for(aim_);
  double best_margin = -1e9;
  Vec2 best_accel;
  for (int n = 0; n < kShotCourses; ++n) {
    const int i = first_reachable ? kShotCourses - 1 - n : n;
    const double along_mouth = kAimInsidePost + (mouth - 2.0 * kAimInsidePost) * i / (kShotCourses - 1);
    const Vec2 aim = post_top + across * along_mouth;
    const Vec2 u = unit(aim - ball);
    const double vu = u.dot(vb);
    const double disc = max_accel * max_accel - vb.r2() + vu * vu;
    if (disc < 0.0) {
      continue;
    }
    const double v0 = std::min(kBallSpeedMax, vu + std::sqrt(disc));
    const double travel = (aim - ball).r();
    if (v0 <= 0.0 || travel >= 0.9 * v0 / (1.0 - kBallDecay)) {
      continue;  // the ball would not reach the goal line
    }
    const Vec2 k = keeper - ball;
    const double k_along = clamp(k.dot(u), 0.0, travel);
    const double k_across = std::fabs(k.x * u.y - k.y * u.x);
    // Cycles the ball needs to pass the goalie: v0 (1 - decay^n) / (1 - decay) >= k_along.
    const double fill = 1.0 - k_along * (1.0 - kBallDecay) / v0;
    const double ball_cycles = fill > 0.0 ? std::log(fill) / std::log(kBallDecay) : 1e9;
    // The goalie: one cycle to turn, then about kGoalieSpeed per cycle, to within its reach.
    const double keeper_cycles = 1.0 + std::max(0.0, k_across - kKickableArea) / kGoalieSpeed;
    const double margin = keeper_cycles - ball_cycles;
    if (margin > best_margin) {
      best_margin = margin;
      best_accel = u * v0 - vb;
    }
    if (first_reachable) {
      break;
    }
  }
  const double to_goal = (goal - ball).r();
  const bool close = to_goal <= rule.must_shoot_range;
  const double needed = rule.margin + rule.slope * (to_goal - kRuleDistance);
  if (best_margin >= needed || (close && best_margin > -1e9)) {
    return shot(kMaxKickPower, std::atan2(best_accel.y, best_accel.x) * kRadToDeg);
  }
  // Dribble: the ball rolls toward the goal centre, or the rule's point toward the bottom post.
  const Vec2 target = goal + across * (rule.dribble_offset * 0.5 * mouth);
  const Vec2 accel = unit(target - ball) * rule.dribble_speed - vb;
  params_[param::kKickPower] = static_cast<float>(std::min(kMaxKickPower, accel.r() / rate));
  params_[param::kKickDir] = static_cast<float>(std::atan2(accel.y, accel.x) * kRadToDeg);
  return {kKick, view()};
}

}  // namespace pamdp::hfo
