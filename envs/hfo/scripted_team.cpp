#include "envs/hfo/scripted_team.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "envs/hfo/geometry.hpp"

namespace pamdp::hfo {
namespace {

// A block of another player is all zeros when HFO has no player for the slot (§3.3).
bool block_present(std::span<const float> f, size_t index) {
  return f[index] != 0.0F || f[index + 1] != 0.0F || f[index + 2] != 0.0F;
}

Vec2 unit(Vec2 v) {
  const double r = v.r();
  return r > 0.0 ? v * (1.0 / r) : Vec2{1.0, 0.0};
}

// Distance from p to the segment a-b.
double segment_distance(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 ab = b - a;
  const double len2 = ab.r2();
  const double t = len2 > 0.0 ? clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + ab * t)).r();
}

}  // namespace

ScriptedTeamPlayer::ScriptedTeamPlayer(int teammates, int opponents, bool shoot_action, double pass_within,
                                       double pass_overrun)
    : teammates_(teammates),
      opponents_(opponents),
      shoot_action_(shoot_action),
      offense_(ShotAim::kCloseIn, shoot_action),
      pass_within_(pass_within),
      pass_overrun_(pass_overrun) {
  if (teammates < 0 || opponents < 0 || teammates + opponents + 1 > SoccerState::kMaxPlayers) {
    std::fprintf(stderr, "ScriptedTeamPlayer: %d teammates and %d opponents do not fit a game\n", teammates, opponents);
    std::abort();
  }
}

ParamAction ScriptedTeamPlayer::go_to(Vec2 target, Vec2 face) {
  params_.fill(0.0F);
  const Vec2 aim = target.r() > 1.0 ? target : face;
  const double angle = std::atan2(aim.y, aim.x) * kRadToDeg;
  if (std::fabs(angle) > 15.0 || target.r() <= 1.0) {
    params_[param::kTurnDir] = static_cast<float>(angle);
    return {kTurn, view()};
  }
  params_[param::kDashPower] = static_cast<float>(std::min(100.0, 20.0 + 20.0 * target.r()));
  return {kDash, view()};
}

ParamAction ScriptedTeamPlayer::act(std::span<const float> f) {
  const size_t expected = static_cast<size_t>(feature_count(1 + teammates_ + opponents_));
  if (f.size() != expected) {
    std::fprintf(stderr, "ScriptedTeamPlayer: %zu features, expected %zu for %d teammates and %d opponents\n", f.size(),
                 expected, teammates_, opponents_);
    std::abort();
  }
  const Vec2 ball = body_frame_position(f, feat::kBallAngleSin);
  const Vec2 goal = body_frame_position(f, feat::kGoalCentre);
  const size_t first_opponent = kNumAgentFeatures + static_cast<size_t>(kFeaturesPerPlayer * teammates_);

  // The nearest opponent (blocks come nearest first).
  const bool opponent = opponents_ > 0 && block_present(f, first_opponent);
  const Vec2 keeper = opponent ? body_frame_position(f, first_opponent) : Vec2{};

  const Vec2 vb = ball_velocity_in_body_frame(f);
  // Who goes for the ball: this player unless a teammate is nearer to where the ball will be
  // kChaseLookahead cycles from now (so a passer leaves a pass to its receiver).
  const Vec2 ahead = ball + vb * ((1.0 - std::pow(kBallDecay, kChaseLookahead)) / (1.0 - kBallDecay));
  bool chase = true;
  for (int k = 0; k < teammates_; ++k) {
    const size_t block = kNumAgentFeatures + static_cast<size_t>(kFeaturesPerPlayer * k);
    if (block_present(f, block) && (body_frame_position(f, block) - ahead).r() < ahead.r() - 0.05) {
      chase = false;
    }
  }

  if (f[feat::kKickable] > 0.0F && opponent && (keeper - ball).r() < pass_within_) {
    // Pass to the most open teammate, if one is open.
    double best = -1.0;
    Vec2 receiver;
    for (int k = 0; k < teammates_; ++k) {
      const size_t block = kNumAgentFeatures + static_cast<size_t>(kFeaturesPerPlayer * k);
      if (!block_present(f, block)) {
        continue;
      }
      const Vec2 m = body_frame_position(f, block);
      const double free = (keeper - m).r() - (keeper - ball).r();
      if (free >= kOpenMargin && segment_distance(keeper, ball, m) >= kLaneClearance && free > best) {
        best = free;
        receiver = m;
      }
    }
    if (best >= 0.0) {
      // The ball rolls d = v0 / (1 - decay) in all, so v0 = (1 - decay) (distance + overrun).
      const double v0 = std::min(kBallSpeedMax, (1.0 - kBallDecay) * ((receiver - ball).r() + pass_overrun_));
      const Vec2 accel = unit(receiver - ball) * v0 - vb;
      const double dist = ball.r();
      const double phi = std::fabs(std::atan2(ball.y, ball.x));
      const double gap = std::max(0.0, dist - kPlayerSize - kBallSize);
      const double rate = kKickPowerRate * (1.0 - 0.25 * phi / std::numbers::pi - 0.25 * gap / kKickableMargin);
      params_.fill(0.0F);
      params_[param::kKickPower] = static_cast<float>(std::min(kMaxKickPower, accel.r() / rate));
      params_[param::kKickDir] = static_cast<float>(std::atan2(accel.y, accel.x) * kRadToDeg);
      ++passes_;
      return {kKick, view()};
    }
  }

  if (chase || f[feat::kKickable] > 0.0F) {
    // The close-in offense against the nearest opponent, or the 1v0 offense with none.
    std::copy_n(f.begin(), kNumAgentFeatures, offense_view_.begin());
    if (opponent) {
      std::copy_n(f.begin() + static_cast<ptrdiff_t>(first_opponent), kFeaturesPerPlayer,
                  offense_view_.begin() + kNumAgentFeatures);
      return offense_.act(offense_view_);
    }
    return offense_.act(std::span<const float>(offense_view_).first(kNumAgentFeatures));
  }

  // Support: ahead of the ball toward the goal and to this player's side of that line.
  const Vec2 forward = unit(goal - ball);
  Vec2 side{-forward.y, forward.x};
  if (side.dot(Vec2{} - ball) < 0.0) {
    side = side * -1.0;  // the side this player (the origin of its frame) is on
  }
  const Vec2 spot = ball + forward * kSupportAhead + side * kSupportAside;
  return go_to(spot, ball);
}

}  // namespace pamdp::hfo
