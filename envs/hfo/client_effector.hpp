// What librcsc's ActionEffector does to a dash or a turn before it leaves the client
// (librcsc player/action_effector.cpp: setDash with conserve_dash_power, setTurn), for any
// player on librcsc: the HFO agent and agent2d's goalie alike. Pure functions, no allocation.
#pragma once

#include <algorithm>
#include <cmath>

#include "envs/hfo/geometry.hpp"

namespace pamdp::hfo {

// ServerParam::dashDirRate (librcsc common/server_param.cpp): side rate at 90 degrees,
// back rate at 180, linear in between.
inline double dash_dir_rate(double dir_deg) {
  const double a = std::fabs(dir_deg);
  const double rate = a <= 90.0 ? kSideDashRate + (1.0 - kSideDashRate) * (1.0 - a / 90.0)
                                : kBackDashRate - (kBackDashRate - kSideDashRate) * (1.0 - (a - 90.0) / 90.0);
  return clamp(rate, 0.0, 1.0);
}

inline double discretize_dash_dir(double dir_deg) {
  return kDashAngleStep * std::nearbyint(dir_deg / kDashAngleStep);
}

inline double round3(double x) {
  return std::nearbyint(x * 1000.0) / 1000.0;
}

struct ClientDash {
  double power = 0.0;
  double dir_deg = 0.0;
};

// setDash(power, dir): clamp and discretize the direction, keep the power within the stamina
// (plus extra stamina) and the acceleration within the player's speed max, round to 1e-3.
inline ClientDash client_dash(Vec2 vel, double body_deg, double stamina, double effort, double power, double dir_deg) {
  const double dir = discretize_dash_dir(wrap_deg(dir_deg));
  power = clamp(power, kMinDashPower, kMaxDashPower);
  const bool back = power < 0.0;
  const double need = back ? -2.0 * power : power;
  if (stamina + kExtraStamina < need) {
    power = back ? -(stamina + kExtraStamina) / 2.0 : stamina + kExtraStamina;
  }
  const double rate = dash_dir_rate(dir);
  double acc = std::fabs(power * rate * effort * kDashPowerRate);
  const double ang = (body_deg + dir + (back ? 180.0 : 0.0)) * kDegToRad;
  const Vec2 unit{std::cos(ang), std::sin(ang)};
  if ((vel + unit * acc).r2() > kPlayerSpeedMax * kPlayerSpeedMax + 1e-4 && rate * effort > 0.0) {
    const double v_par = vel.dot(unit);
    const double v_perp2 = std::max(0.0, vel.r2() - v_par * v_par);
    acc = std::max(0.0, std::sqrt(std::max(0.0, kPlayerSpeedMax * kPlayerSpeedMax - v_perp2)) - v_par);
    power = (back ? -acc : acc) / (kDashPowerRate * effort * rate);
    power = clamp(power, kMinDashPower, kMaxDashPower);
  }
  return {round3(power), dir};
}

// setTurn(angle): the moment that turns the body by `angle_deg` at this speed (inertia
// compensated), clamped to the moment range and rounded to 1e-3.
inline double client_turn_moment(Vec2 vel, double angle_deg) {
  const double inertia = 1.0 + kInertiaMoment * vel.r();
  return round3(clamp(wrap_deg(angle_deg) * inertia, kMinMoment, kMaxMoment));
}

}  // namespace pamdp::hfo
