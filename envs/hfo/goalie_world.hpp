// The goalie's world model and the librcsc actions it calls, as agent2d's goalie sees them.
//
// HFO's goalie is agent2d's (HFO `src/role_goalie.cpp` and the bhv_goalie_* files) on
// librcsc, with full state: its world model is the exact server state at the start of the
// cycle. agent2d plays the defense as the right side, so the server sends it every position
// mirrored (x -> -x, y -> -y, angles + 180): in its own frame its goal is at x = -52.5 and
// the attackers come from +x. Everything in this header works in that frame, so that the
// rules and constants carried over from agent2d and librcsc read as they do there; the
// goalie's decision (goalie.hpp) converts once, at its boundary.
//
// Nothing here allocates; every call is O(intercept horizon) at most.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

#include "envs/hfo/geometry.hpp"

namespace pamdp::hfo::agent2d {

// librcsc AngleDeg::normalize_angle: [-180, 180], keeping -180 as -180 (unlike wrap_deg).
inline double angle_norm(double deg) {
  if (deg < -360.0 || 360.0 < deg) {
    deg = std::fmod(deg, 360.0);
  }
  if (deg < -180.0) {
    deg += 360.0;
  }
  if (deg > 180.0) {
    deg -= 360.0;
  }
  return deg;
}

// librcsc's small geometry, in degrees: Vector2D::th(), Vector2D::rotatedVector(),
// calc_first_term_geom_series (math_util.h).
inline double th_deg(Vec2 v) {
  return std::atan2(v.y, v.x) * kRadToDeg;
}
inline Vec2 rotate_deg(Vec2 v, double deg) {
  const double c = std::cos(deg * kDegToRad);
  const double s = std::sin(deg * kDegToRad);
  return {v.x * c - v.y * s, v.x * s + v.y * c};
}
inline double first_term_geom_series(double sum, double r, int len) {
  return sum * (1.0 - r) / (1.0 - std::pow(r, len));
}
// rcssserver sends the right side (HFO's defense) every position mirrored through the centre:
// the global frame to a defense player's own, and back.
inline Vec2 mirror(Vec2 v) {
  return {-v.x, -v.y};
}

// PlayerType::realSpeedMax() of type 0: min(100 x 0.006 x 1 / (1 - 0.4), 1.05) = 1.0.
inline constexpr double kRealSpeedMax = kMaxDashPower * kDashPowerRate / (1.0 - kPlayerDecay) < kPlayerSpeedMax
                                            ? kMaxDashPower * kDashPowerRate / (1.0 - kPlayerDecay)
                                            : kPlayerSpeedMax;
// ServerParam::ourPenaltyAreaLineX(): the goal line plus penalty_area_length (16.5).
inline constexpr double kOurPenaltyLineX = -kPitchHalfLength + 16.5;

// ServerParam::catchableArea(): the diagonal of the catchable rectangle, sqrt(1.2^2 + 0.5^2).
inline const double kCatchableArea =
    std::sqrt(kCatchableAreaLength * kCatchableAreaLength + 0.25 * kCatchableAreaWidth * kCatchableAreaWidth);

// A player as the world model holds it (pos, vel as the server stores them: post-decay).
struct PlayerView {
  Vec2 pos;
  Vec2 vel;
  double body_deg = 0.0;
  bool tackling = false;  // frozen after a tackle (librcsc isTackling)
  bool goalie = false;    // a field defender's teammate the goalie (its catchable area counts)
};

// The goalie's own state (librcsc SelfObject with full state).
struct SelfView {
  Vec2 pos;
  Vec2 vel;
  double body_deg = 0.0;
  double stamina = kStaminaMax;
  double effort = 1.0;
  double recovery = 1.0;
  double capacity = kStaminaCapacity;
  bool frozen = false;  // after its own tackle
  // librcsc SelfObject::goalie(): false for a field player (agent2d's field defenders), whose
  // control area in its own intercept is always the kickable area (goalie_self_intercept.cpp).
  bool goalie = true;
};

// Sorts players nearest to `ball` first, the earlier first among equals (WorldModel's
// teammatesFromBall / opponentsFromBall): an insertion sort of a few entries.
inline void sort_from_ball(std::span<PlayerView> players, Vec2 ball) {
  for (size_t i = 1; i < players.size(); ++i) {
    const PlayerView p = players[i];
    const double d = (p.pos - ball).r2();
    size_t j = i;
    for (; j > 0 && (players[j - 1].pos - ball).r2() > d; --j) {
      players[j] = players[j - 1];
    }
    players[j] = p;
  }
}

// librcsc WorldModel, reduced to what the goalie reads, in the goalie's frame.
struct GoalieWorld {
  static constexpr int kMaxOpponents = 3;
  SelfView self;
  Vec2 ball_pos;
  Vec2 ball_vel;
  // Opponents sorted by distance to the ball (WorldModel::opponentsFromBall).
  std::array<PlayerView, kMaxOpponents> opponents{};
  int num_opponents = 0;
  // Teammates sorted by distance to the ball: the goalie's are the field defenders, a field
  // defender's the goalie (flagged) and the other field defenders.
  static constexpr int kMaxTeammates = 3;
  std::array<PlayerView, kMaxTeammates> teammates{};
  int num_teammates = 0;
  // Cycles since the goalie's last catch command; a large value when it has not caught.
  int since_catch = 1000;
  // WorldModel::gameMode() is GoalieCatch_ of its own side. A successful catch makes the
  // server send every player the referee's goalie_catch_ball_r (Stadium::ballCaught); in HFO
  // mode the play mode itself stays play_on (CatchRef::ballCaught returns at once) and the
  // next play-mode message is the reset's before_kick_off / play_on (HFORef::analyse). Until
  // then the goalie plays the set play: Bhv_SetPlay -> Bhv_GoalieFreeKick (PlayerState::caught).
  bool catch_mode = false;
  // The server's noise parameters, which librcsc reads from the server and builds into its
  // intercept margins (player_rand, ball_rand): 0.1 and 0.05 by default, 0 with noise off.
  double player_rand = kPlayerRand;
  double ball_rand = kBallRand;

  // Derived values, as librcsc computes them (set by finish(), which the builder calls).
  double ball_dist_from_self = 0.0;
  double ball_angle_from_self_deg = 0.0;  // global direction of the ball from the goalie
  bool exist_kickable_opponent = false;   // WorldModel::existKickableOpponent()
  bool exist_kickable_teammate = false;   // WorldModel::existKickableTeammate()
  bool self_kickable = false;             // SelfObject::isKickable() (full state: buffer 0.055)

  void finish();
};

// One way for the goalie to reach the ball (librcsc InterceptInfo).
struct InterceptInfo {
  enum class Mode : uint8_t { kNormal, kExhaust };
  Mode mode = Mode::kExhaust;
  int turn_cycle = 10000;
  int dash_cycle = 10000;
  double dash_power = 100000.0;
  double dash_angle_deg = 0.0;  // first dash direction relative to the body (librcsc dashAngle)
  Vec2 self_pos{-10000.0, 0.0};
  double ball_dist = 10000000.0;
  double stamina = 0.0;
  [[nodiscard]] int reach_cycle() const { return turn_cycle + dash_cycle; }
};

// librcsc InterceptTable: ball path cache, the goalie's own ways to the ball, and the
// opponents' and teammates' reach cycles (1000 = cannot within the horizon).
struct InterceptTable {
  static constexpr int kMaxCycle = 30;  // InterceptTable::MAX_CYCLE
  static constexpr int kMaxSelfCache = 3 * (kMaxCycle + 2);
  std::array<Vec2, kMaxCycle + 2> ball_cache{};
  int ball_cache_size = 0;
  std::array<InterceptInfo, kMaxSelfCache> self_cache{};
  int self_cache_size = 0;
  int self_reach_cycle = 1000;
  int self_exhaust_reach_cycle = 1000;
  int opponent_reach_cycle = 1000;
  int teammate_reach_cycle = 1000;  // the field teammates' (the goalie's is goalie_reach_cycle)
  int goalie_reach_cycle = 1000;    // a field defender's goalie teammate's (InterceptTable::goalieReachCycle)
  bool self_predicted = false;      // predict_self() has filled the self_* members
};

// librcsc StaminaModel (common/stamina_model.cpp): simulateWait and simulateDash of player type 0.
struct StaminaModel {
  double stamina = kStaminaMax;
  double effort = 1.0;
  double recovery = 1.0;
  double capacity = kStaminaCapacity;

  void wait() {
    if (stamina <= kRecoverDecThreshold && recovery > kRecoverMin) {
      recovery = std::max(kRecoverMin, recovery - kRecoverDec);
    }
    if (stamina <= kEffortDecThreshold) {
      if (effort > kEffortMin) {
        effort = std::max(kEffortMin, effort - kEffortDec);
      }
    } else if (stamina >= kEffortIncThreshold && effort < kEffortMax) {
      effort = std::min(kEffortMax, effort + kEffortInc);
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
  void dash(double power) {
    stamina = std::max(0.0, stamina - (power >= 0.0 ? power : -2.0 * power));
    wait();
  }
  void dashes(int n, double power) {
    for (int i = 0; i < n; ++i) {
      dash(power);
    }
  }
  [[nodiscard]] bool capacity_is_empty() const { return capacity <= 1.0e-5 && capacity >= 0.0; }
};

inline StaminaModel stamina_of(const SelfView& s) {
  return {s.stamina, s.effort, s.recovery, s.capacity};
}

// InterceptTable::update in two parts (goalie_intercept.cpp, goalie_self_intercept.cpp): the ball's path and the
// opponents' reach (PlayerIntercept), which every cycle needs, and the goalie's own ways to the
// ball (SelfInterceptV13), which only some rules read, so the goalie computes them on demand.
void predict_ball_and_opponents(const GoalieWorld& world, InterceptTable* table);
void predict_self(const GoalieWorld& world, InterceptTable* table);
// PlayerType::cyclesToReachDistance for player type 0 (full dashes from rest).
int cycles_to_reach_distance(double dash_dist);
// FieldAnalyzer::predict_player_turn_cycle for player type 0: the turns a player moving at
// `speed` needs to face a target `target_dist` away at `target_deg` within `dist_thr`; with
// `use_back_dash`, a target within 5 m behind it counts as ahead (HFO's min_dash_power is -100).
int predict_player_turn_cycle(double body_deg, double speed, double target_dist, double target_deg, double dist_thr,
                              bool use_back_dash);
inline void predict_intercepts(const GoalieWorld& world, InterceptTable* table) {
  predict_ball_and_opponents(world, table);
  predict_self(world, table);
}

// --- Commands, in the server's units (what the .rcl logs) -------------------------------

struct Command {
  enum class Kind : uint8_t { kNone, kDash, kTurn, kCatch, kKick, kTackle };
  Kind kind = Kind::kNone;
  double p1 = 0.0;  // dash power, turn moment, catch direction, kick power, tackle direction
  double p2 = 0.0;  // dash direction, kick direction
};

// PlayerAgent::doDash / doTurn through librcsc's ActionEffector: the client's clamping,
// discretizing, stamina and speed conservation and rounding, so the result is the command
// the server receives. `angle_deg` of do_turn is the wanted turn of the body.
Command do_dash(const GoalieWorld& w, double power, double dir_deg);
Command do_turn(const GoalieWorld& w, double angle_deg);

// librcsc body actions. Each returns true and sets *out when it issues a command, false when
// it has nothing to do (as their execute() does).
bool body_go_to_point(const GoalieWorld& w, Vec2 point, double dist_thr, double max_dash_power, double dash_speed,
                      int cycle, bool save_recovery, double dir_thr, Command* out);
bool body_turn_to_angle(const GoalieWorld& w, double angle_deg, Command* out);
bool body_turn_to_point(const GoalieWorld& w, Vec2 point, int cycle, Command* out);
bool body_stop_dash(const GoalieWorld& w, bool save_recovery, Command* out);

// StaminaModel::getSafetyDashPower: the power that keeps stamina above the recovery threshold.
double safety_dash_power(const GoalieWorld& w, double dash_power);
// Bhv_NeckBodyToPoint (the body part): turn to `point` unless the neck alone can face it.
bool neck_body_to_point(const GoalieWorld& w, Vec2 point, double angle_buf, Command* out);
// Bhv_GoToPointLookBall.
bool go_to_point_look_ball(const GoalieWorld& w, Vec2 target, double dist_thr, double dash_power,
                           double back_power_rate, Command* out);

// Body_Intercept2009 (implemented in goalie_intercept.cpp).
bool body_intercept(const GoalieWorld& w, const InterceptTable& table, bool save_recovery, Command* out);

// decay^n for the inertia sums, the same values std::pow gives, looked up for small n.
struct DecayPowers {
  static constexpr int kSize = 128;
  std::array<double, kSize> ball{};
  std::array<double, kSize> player{};
  DecayPowers() {
    for (int n = 0; n < kSize; ++n) {
      ball[static_cast<size_t>(n)] = std::pow(kBallDecay, n);
      player[static_cast<size_t>(n)] = std::pow(kPlayerDecay, n);
    }
  }
};
inline const DecayPowers kDecayPowers;
inline double ball_decay_pow(int n) {
  return n >= 0 && n < DecayPowers::kSize ? kDecayPowers.ball[static_cast<size_t>(n)] : std::pow(kBallDecay, n);
}
inline double player_decay_pow(int n) {
  return n >= 0 && n < DecayPowers::kSize ? kDecayPowers.player[static_cast<size_t>(n)] : std::pow(kPlayerDecay, n);
}

// Ball and player inertia helpers (librcsc inertia_n_step_point and friends).
inline Vec2 ball_inertia_point(const GoalieWorld& w, int n) {
  const double k = (1.0 - ball_decay_pow(n)) / (1.0 - kBallDecay);
  return w.ball_pos + w.ball_vel * k;
}
inline Vec2 self_inertia_point(const GoalieWorld& w, int n) {
  const double k = (1.0 - player_decay_pow(n)) / (1.0 - kPlayerDecay);
  return w.self.pos + w.self.vel * k;
}
inline Vec2 self_inertia_final_point(const GoalieWorld& w) {
  return w.self.pos + w.self.vel * (1.0 / (1.0 - kPlayerDecay));
}

}  // namespace pamdp::hfo::agent2d
