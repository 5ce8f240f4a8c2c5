// Field geometry, server constants and small vector helpers for the HFO simulator.
// Every number is a server default from shared/hfo-reference.md §1–§2 (player type 0).
#pragma once

#include <cmath>
#include <numbers>

namespace pamdp::hfo {

struct Vec2 {
  double x = 0.0;
  double y = 0.0;

  Vec2 operator+(Vec2 o) const { return {x + o.x, y + o.y}; }
  Vec2 operator-(Vec2 o) const { return {x - o.x, y - o.y}; }
  Vec2 operator*(double s) const { return {x * s, y * s}; }
  Vec2& operator+=(Vec2 o) {
    x += o.x;
    y += o.y;
    return *this;
  }
  Vec2& operator*=(double s) {
    x *= s;
    y *= s;
    return *this;
  }
  [[nodiscard]] double dot(Vec2 o) const { return x * o.x + y * o.y; }
  [[nodiscard]] double r2() const { return x * x + y * y; }
  [[nodiscard]] double r() const { return std::sqrt(r2()); }
  [[nodiscard]] bool is_zero() const { return x == 0.0 && y == 0.0; }
  bool operator==(const Vec2&) const = default;
};

inline constexpr double kDegToRad = std::numbers::pi / 180.0;
inline constexpr double kRadToDeg = 180.0 / std::numbers::pi;

inline Vec2 polar(double r, double angle_rad) {
  return {r * std::cos(angle_rad), r * std::sin(angle_rad)};
}

// Maps an angle in degrees to (-180, 180].
inline double wrap_deg(double a) {
  if (a > -180.0 && a <= 180.0) {
    return a;
  }
  a = std::fmod(a, 360.0);
  if (a > 180.0) {
    a -= 360.0;
  } else if (a <= -180.0) {
    a += 360.0;
  }
  return a;
}

// Maps an angle in radians to (-pi, pi].
inline double wrap_rad(double a) {
  constexpr double kPi = std::numbers::pi;
  if (a > -kPi && a <= kPi) {
    return a;
  }
  a = std::fmod(a, 2.0 * kPi);
  if (a > kPi) {
    a -= 2.0 * kPi;
  } else if (a <= -kPi) {
    a += 2.0 * kPi;
  }
  return a;
}

inline double clamp(double x, double lo, double hi) {
  return x < lo ? lo : (x > hi ? hi : x);
}

// --- Field (reference §1) ---
inline constexpr double kPitchHalfLength = 52.5;
inline constexpr double kPitchHalfWidth = 34.0;
inline constexpr double kGoalHalfWidth = 7.01;
inline constexpr double kGoalPostRadius = 0.06;
inline constexpr double kPenaltyBoxX = 36.0;
inline constexpr double kPenaltyBoxHalfWidth = 20.16;
// Proximity normalizer of the E1/E2 features: sqrt(52.5^2 + 34^2).
inline const double kMaxDistance = std::sqrt(52.5 * 52.5 + 34.0 * 34.0);

// --- Ball ---
inline constexpr double kBallSize = 0.085;
inline constexpr double kBallDecay = 0.94;
inline constexpr double kBallRand = 0.05;
inline constexpr double kBallSpeedMax = 3.0;
inline constexpr double kBallAccelMax = 2.7;

// --- Player type 0 ---
inline constexpr double kPlayerSize = 0.3;
inline constexpr double kPlayerDecay = 0.4;
inline constexpr double kPlayerRand = 0.1;
inline constexpr double kPlayerSpeedMax = 1.05;
inline constexpr double kPlayerAccelMax = 1.0;
inline constexpr double kInertiaMoment = 5.0;
inline constexpr double kDashPowerRate = 0.006;
inline constexpr double kKickPowerRate = 0.027;
inline constexpr double kKickableMargin = 0.7;
inline constexpr double kKickableArea = kPlayerSize + kKickableMargin + kBallSize;  // 1.085
inline constexpr double kClientKickableArea = kKickableArea - 0.055;                // 1.03
inline constexpr double kKickRand = 0.1;
inline constexpr double kExtraStamina = 50.0;
inline constexpr double kEffortMax = 1.0;
inline constexpr double kEffortMin = 0.6;
inline constexpr double kStaminaIncMax = 45.0;

// --- Stamina ---
inline constexpr double kStaminaMax = 8000.0;
inline constexpr double kStaminaCapacity = 130600.0;
inline constexpr double kRecoverDecThreshold = 0.3 * kStaminaMax;
inline constexpr double kRecoverDec = 0.002;
inline constexpr double kRecoverMin = 0.5;
inline constexpr double kEffortDecThreshold = 0.3 * kStaminaMax;
inline constexpr double kEffortDec = 0.005;
inline constexpr double kEffortIncThreshold = 0.6 * kStaminaMax;
inline constexpr double kEffortInc = 0.01;

// --- Commands ---
inline constexpr double kMinDashPower = -100.0;
inline constexpr double kMaxDashPower = 100.0;
inline constexpr double kDashAngleStep = 45.0;
inline constexpr double kSideDashRate = 0.4;
inline constexpr double kBackDashRate = 0.6;
inline constexpr double kMaxKickPower = 100.0;
inline constexpr double kMinMoment = -180.0;
inline constexpr double kMaxMoment = 180.0;

// --- Tackle ---
inline constexpr double kTackleDist = 2.0;
inline constexpr double kTackleBackDist = 0.0;
inline constexpr double kTackleWidth = 1.25;
inline constexpr double kTackleExponent = 6.0;
inline constexpr double kFoulExponent = 10.0;  // rcssserver serverparam.cpp FOUL_EXPONENT
inline constexpr int kTackleCycles = 10;
inline constexpr double kTacklePowerRate = 0.027;
inline constexpr double kMaxTacklePower = 100.0;
inline constexpr double kMaxBackTacklePower = 0.0;
inline constexpr double kTackleRandFactor = 2.0;

// --- Goalie catch (rcssserver defaults; the reference gives none): catchable_area_l,
// catchable_area_w, catch_probability, catch_ban_cycle. Player type 0 has no catch stretch. ---
inline constexpr double kCatchableAreaLength = 1.2;
inline constexpr double kCatchableAreaWidth = 1.0;
inline constexpr double kCatchProbability = 1.0;
inline constexpr int kCatchBanCycles = 5;

}  // namespace pamdp::hfo
