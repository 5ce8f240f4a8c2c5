#include "envs/hfo_server/server_action.hpp"

#include <algorithm>

#include "envs/hfo/geometry.hpp"
#include "envs/hfo/hfo_env.hpp"

namespace pamdp::hfo_server {
namespace {

double power_within(double power, double lo, double hi, int64_t& count) {
  if (power < lo || power > hi) {
    ++count;
    return std::clamp(power, lo, hi);
  }
  return power;
}

// Wrapped as librcsc's AngleDeg does; 180 itself is in range (the server's bound is inclusive).
double direction_within(double dir_deg, int64_t& count) {
  if (dir_deg < hfo::kMinMoment || dir_deg > hfo::kMaxMoment) {
    ++count;
    return hfo::wrap_deg(dir_deg);
  }
  return dir_deg;
}

}  // namespace

ServerCommandArgs server_command_args(const ParamAction& action, ActionClampCounts& counts) {
  const auto p = [&](int i) { return static_cast<double>(action.params[static_cast<size_t>(i)]); };
  switch (action.id) {
    case hfo::kDash:
      return {power_within(p(hfo::param::kDashPower), hfo::kMinDashPower, hfo::kMaxDashPower, counts.dash_power),
              direction_within(p(hfo::param::kDashDir), counts.direction)};
    case hfo::kTurn: return {direction_within(p(hfo::param::kTurnDir), counts.direction), 0.0};
    case hfo::kTackle: return {direction_within(p(hfo::param::kTackleDir), counts.direction), 0.0};
    case hfo::kKick:
      return {power_within(p(hfo::param::kKickPower), 0.0, hfo::kMaxKickPower, counts.kick_power),
              direction_within(p(hfo::param::kKickDir), counts.direction)};
    case hfo::kShoot:  // env.shoot_action: a KICK with SHOOT's own parameters
      return {power_within(p(hfo::param::kShootPower), 0.0, hfo::kMaxKickPower, counts.kick_power),
              direction_within(p(hfo::param::kShootDir), counts.direction)};
    default: return {};
  }
}

}  // namespace pamdp::hfo_server
