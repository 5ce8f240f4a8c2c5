#include "envs/hfo/scripted_offense.hpp"

#include <cmath>

#include "envs/hfo/features.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/hfo_env.hpp"

namespace pamdp::hfo {

ParamAction ScriptedOffense::act(std::span<const float> f) {
  params_.fill(0.0F);
  const double ball_deg = std::atan2(f[feat::kBallAngleSin], f[feat::kBallAngleCos]) * kRadToDeg;
  if (f[feat::kKickable] > 0.0F) {
    const double goal_deg = std::atan2(f[feat::kGoalCentre], f[feat::kGoalCentre + 1]) * kRadToDeg;
    params_[param::kKickPower] = 100.0F;
    params_[param::kKickDir] = static_cast<float>(goal_deg);
    return {kKick, params_};
  }
  if (std::fabs(ball_deg) > 10.0) {
    params_[param::kTurnDir] = static_cast<float>(ball_deg);
    return {kTurn, params_};
  }
  params_[param::kDashPower] = 100.0F;
  return {kDash, params_};
}

}  // namespace pamdp::hfo
