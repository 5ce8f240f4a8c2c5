#include "envs/hfo/goalie.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace pamdp::hfo {
namespace {

// Cycles of ball path the goalie looks ahead, and the speed below which it counts the ball as
// stopped (it then rolls less than 2 mm more).
constexpr int kHorizon = 40;
constexpr double kBallAtRest = 1e-4;
// Distance at which the goalie counts the ball as won at the end of a cycle: a little inside
// the referee's 1.085 m (and the 1.2 m catch), as a margin for movement and kick noise.
constexpr double kGoalieReach = 0.9;
// The attacker's reach, a little generous: the client kickable distance 1.03.
constexpr double kAttackerReach = 1.1;
// Dashing straight is worth a turn first when the target lies this far off the body axis.
constexpr double kTurnThresholdDeg = 22.5;
// Guarding: how far out from the goal line the goalie stands on the bisector toward the ball,
// as a fraction of the ball's distance along it, clamped (12 m stays inside the penalty
// area); and how far in front of the goal line it stays at least. Tuned so that the scripted offense
// scores about as often as agent2d's does against agent2d's goalie (docs/results.md).
constexpr double kGuardFraction = 0.7;
constexpr double kGuardMin = 1.0;
constexpr double kGuardMax = 12.0;
constexpr double kGuardMaxX = kPitchHalfLength - 0.5;
// Position tolerance when guarding, and the ball bearing beyond which it turns to face it.
constexpr double kGuardTolerance = 0.3;
constexpr double kFaceBallDeg = 20.0;

constexpr Vec2 kGoalCentre{kPitchHalfLength, 0.0};

// Distance covered by n full forward dashes from rest (type 0, effort 1): 0.6, 1.44, ...
constexpr std::array<double, kHorizon + 1> make_dash_reach() {
  std::array<double, kHorizon + 1> reach{};
  double v = 0.0;
  double d = 0.0;
  for (int n = 1; n <= kHorizon; ++n) {
    v += kMaxDashPower * kDashPowerRate;
    v = v > kPlayerSpeedMax ? kPlayerSpeedMax : v;
    d += v;
    v *= kPlayerDecay;
    reach[n] = d;
  }
  return reach;
}
constexpr std::array<double, kHorizon + 1> kDashReach = make_dash_reach();

Vec2 unit(Vec2 v) {
  const double r = v.r();
  return r > 0.0 ? v * (1.0 / r) : Vec2{1.0, 0.0};
}

bool in_penalty_area(Vec2 p) {
  return p.x >= kPenaltyBoxX && p.x <= kPitchHalfLength && std::fabs(p.y) <= kPenaltyBoxHalfWidth;
}

// Bearing of `d` relative to the body, degrees in (-180, 180].
double relative_deg(Vec2 d, double body_deg) {
  return wrap_deg(std::atan2(d.y, d.x) * kRadToDeg - body_deg);
}

// A player as the reach estimate sees it: position and body direction.
struct Mover {
  Vec2 pos;
  Vec2 body;  // unit vector of the body angle
  explicit Mover(const PlayerState& p)
      : pos(p.pos), body{std::cos(p.body_deg * kDegToRad), std::sin(p.body_deg * kDegToRad)} {}
};

// Cycles `m` needs to get within `reach` of `target`: a turn if the target is off the body axis,
// then full dashes. kHorizon + 1 if it cannot within the horizon.
int cycles_to_reach(const Mover& m, Vec2 target, double reach) {
  static const double kCosTurnThreshold = std::cos(kTurnThresholdDeg * kDegToRad);
  const Vec2 d = target - m.pos;
  const double dist = d.r();
  const double need = dist - reach;
  if (need <= 0.0) {
    return 0;
  }
  const int turn = d.dot(m.body) < kCosTurnThreshold * dist ? 1 : 0;
  const auto* it = std::lower_bound(kDashReach.begin() + 1, kDashReach.end(), need);
  const int n = static_cast<int>(it - kDashReach.begin()) + turn;
  return n <= kHorizon ? n : kHorizon + 1;
}

// One command that brings `p` toward `target`, stopping there: turn first when the target is
// far off the body axis, else dash in the nearest of the 45-degree directions with the power
// that, with the player's decay, ends the motion at the target.
GoalieCommand go_to(const PlayerState& p, Vec2 target) {
  const Vec2 d = target - p.pos;
  const double dist = d.r();
  const double rel = relative_deg(d, p.body_deg);
  if (dist > 1.0 && std::fabs(rel) > kTurnThresholdDeg) {
    return {GoalieCommand::Kind::kTurn, 0.0, rel};
  }
  const double dash_dir = kDashAngleStep * std::nearbyint(rel / kDashAngleStep);
  const double a = (p.body_deg + dash_dir) * kDegToRad;
  const Vec2 u{std::cos(a), std::sin(a)};
  // A push a moves the player a / (1 - decay) in all; the current velocity adds v / (1 - decay).
  const double wanted = (d * (1.0 - kPlayerDecay) - p.vel).dot(u);
  const double abs_dir = std::fabs(dash_dir);
  const double rate = abs_dir <= 90.0
                          ? kSideDashRate + (1.0 - kSideDashRate) * (1.0 - abs_dir / 90.0)
                          : kBackDashRate - (kBackDashRate - kSideDashRate) * (1.0 - (abs_dir - 90.0) / 90.0);
  const double power = clamp(wanted / (kDashPowerRate * p.effort * rate), 0.0, kMaxDashPower);
  return {GoalieCommand::Kind::kDash, power, dash_dir};
}

}  // namespace

GoalieCommand decide_goalie(const SoccerState& s, int goalie) {
  const PlayerState& me = s.players[goalie];
  const BallState& ball = s.ball;
  const Vec2 to_ball = ball.pos - me.pos;

  // 1. Catch.
  if (me.catch_ban == 0 && in_penalty_area(ball.pos) && to_ball.r() < kCatchableAreaLength) {
    return {GoalieCommand::Kind::kCatch, 0.0, relative_deg(to_ball, me.body_deg)};
  }

  // 2. Intercept. The nearest attacker is the opponent that matters.
  const PlayerState* attacker = nullptr;
  for (int i = 0; i < s.num_players; ++i) {
    const PlayerState& p = s.players[i];
    if (p.team != me.team && (attacker == nullptr || (p.pos - ball.pos).r2() < (attacker->pos - ball.pos).r2())) {
      attacker = &p;
    }
  }
  const Mover keeper(me);
  const Mover opponent(attacker != nullptr ? *attacker : me);
  Vec2 bp = ball.pos;
  Vec2 bv = ball.vel;
  bool into_goal = false;
  int attacker_cycles = kHorizon + 1;
  for (int k = 1; k <= kHorizon; ++k) {
    const Vec2 next = bp + bv;
    if (next.x > kPitchHalfLength) {
      const double t = (kPitchHalfLength - bp.x) / (next.x - bp.x);
      into_goal = std::fabs(bp.y + t * (next.y - bp.y)) <= kGoalHalfWidth + kGoalPostRadius;
      break;
    }
    bp = next;
    bv *= kBallDecay;
    if (bv.r2() < kBallAtRest * kBallAtRest) {
      // The ball has (all but) stopped at bp: the first cycle each player can be there.
      if (attacker != nullptr && attacker_cycles > kHorizon) {
        attacker_cycles = std::max(k, cycles_to_reach(opponent, bp, kAttackerReach));
      }
      const int mine = std::max(k, cycles_to_reach(keeper, bp, kGoalieReach));
      if (in_penalty_area(bp) && mine <= kHorizon && mine < attacker_cycles) {
        return go_to(me, bp);
      }
      break;
    }
    if (attacker != nullptr && attacker_cycles > kHorizon && cycles_to_reach(opponent, bp, kAttackerReach) <= k) {
      attacker_cycles = k;
    }
    if (!in_penalty_area(bp) || cycles_to_reach(keeper, bp, kGoalieReach) > k) {
      continue;
    }
    // First reachable point of the path: worth going if the attacker is not there first.
    if (k < attacker_cycles) {
      return go_to(me, bp);
    }
    break;
  }
  if (into_goal) {
    // A shot the goalie cannot reach in time: the best it can do is the nearest point of the
    // path to the goal line, which the search above ended at.
    return go_to(me, bp);
  }

  // 3. Guard: stand on the bisector of the angle the goal mouth makes at the ball, which
  // leaves the same margin to both posts, at kGuardFraction of the way out toward the ball.
  Vec2 target = kGoalCentre;
  if (ball.pos.x < kPitchHalfLength - 0.5) {
    const Vec2 to_top = unit(Vec2{kPitchHalfLength, -kGoalHalfWidth} - ball.pos);
    const Vec2 to_bottom = unit(Vec2{kPitchHalfLength, kGoalHalfWidth} - ball.pos);
    const Vec2 bisector = unit(to_top + to_bottom);
    const double t = (kPitchHalfLength - ball.pos.x) / bisector.x;  // ball to the goal line
    const double out = std::min(t, clamp(kGuardFraction * t, kGuardMin, kGuardMax));
    target = ball.pos + bisector * (t - out);
  }
  target.x = std::min(target.x, kGuardMaxX);
  if ((target - me.pos).r() > kGuardTolerance) {
    return go_to(me, target);
  }
  const double ball_rel = relative_deg(to_ball, me.body_deg);
  if (std::fabs(ball_rel) > kFaceBallDeg) {
    return {GoalieCommand::Kind::kTurn, 0.0, ball_rel};
  }
  return {};
}

}  // namespace pamdp::hfo
