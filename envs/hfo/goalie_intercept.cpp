// librcsc's intercept table for the goalie (rcsc/player/intercept_table.cpp, player_intercept.cpp).
// PROVISIONAL: the goalie's own intercept (SelfInterceptV13) and Body_Intercept2009 below are
// estimates until their port lands; the ball cache and the opponent's reach are librcsc's.
#include <algorithm>
#include <array>
#include <cmath>

#include "envs/hfo/goalie_world.hpp"

namespace pamdp::hfo::agent2d {
namespace {

// PlayerType's real speed max for type 0: min(100 x 0.006 x 1 / (1 - 0.4), 1.05) = 1.0.
constexpr double kRealSpeedMax = std::min(kMaxDashPower * kDashPowerRate / (1.0 - kPlayerDecay), kPlayerSpeedMax);

// PlayerType's dash distance table (common/player_type.cpp, PlayerType::initAdditionalParams):
// distance covered by n full dashes from rest, n = 1..50 (type 0 never reaches the speed cap
// and never runs out of stamina within 50 dashes).
struct DashDistanceTable {
  std::array<double, 50> d{};
  DashDistanceTable() {
    const double accel = kMaxDashPower * kDashPowerRate * kEffortMax;
    double speed = 0.0;
    double reach = 0.0;
    for (int i = 0; i < 50; ++i) {
      speed += accel;
      reach += speed;
      d[static_cast<size_t>(i)] = reach;
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
  const double rest = dash_dist - t.back();
  return static_cast<int>(t.size()) + static_cast<int>(std::ceil(rest / kRealSpeedMax));
}

Vec2 inertia_point(Vec2 pos, Vec2 vel, int n) {
  return pos + vel * ((1.0 - player_decay_pow(n)) / (1.0 - kPlayerDecay));
}

double th_deg(Vec2 v) {
  return std::atan2(v.y, v.x) * kRadToDeg;
}

// PlayerIntercept::predictTurnCycle: one turn at most.
int predict_turn_cycle(const PlayerView& p, int cycle, double control_area, Vec2 ball_pos) {
  const Vec2 target_rel = ball_pos - inertia_point(p.pos, p.vel, cycle);
  const double target_dist = target_rel.r();
  double turn_margin = 180.0;
  if (control_area < target_dist) {
    turn_margin = std::asin(control_area / target_dist) * kRadToDeg;
  }
  turn_margin = std::max(turn_margin, 12.0);
  double angle_diff = std::fabs(angle_norm(th_deg(target_rel) - p.body_deg));
  if (target_dist < 5.0 && angle_diff > 90.0) {
    angle_diff = 180.0 - angle_diff;
  }
  return angle_diff > turn_margin ? 1 : 0;
}

// PlayerIntercept::canReachAfterDash, for an opponent seen this cycle (position counts 0).
bool can_reach_after_dash(const PlayerView& p, int n_turn, int max_dash, double control_area, Vec2 ball_pos) {
  const Vec2 player_pos = inertia_point(p.pos, p.vel, n_turn + max_dash);
  const double dist = (ball_pos - player_pos).r() - control_area;
  if (dist < 0.0) {
    return true;
  }
  int n_dash = cycles_to_reach_distance(dist);
  if (p.tackling) {
    n_dash += std::max(0, kTackleCycles - 2);  // tackle count unknown with full state: 0
  }
  return n_dash <= max_dash;
}

// PlayerIntercept::predictFinal.
int predict_final(const GoalieWorld& w, const InterceptTable& t, const PlayerView& p) {
  const Vec2 ball_pos = t.ball_cache[static_cast<size_t>(t.ball_cache_size - 1)];
  const int ball_step = t.ball_cache_size;
  const double control_area = kKickableArea;  // an attacker is no goalie
  const int n_turn = predict_turn_cycle(p, 100, control_area, ball_pos);
  double dash_dist = (inertia_point(p.pos, p.vel, 100) - ball_pos).r() - control_area;
  dash_dist -= (p.pos - w.self.pos).r() * 0.03;  // an opponent's distance from the goalie
  if (dash_dist < 0.0) {
    return ball_step;
  }
  const int n_dash = std::max(1, cycles_to_reach_distance(dash_dist));
  return std::max(ball_step, n_turn + n_dash);
}

// PlayerIntercept::predict for an opponent with full state.
int predict_opponent(const GoalieWorld& w, const InterceptTable& t, const PlayerView& p) {
  Vec2 ball_to_player = p.pos - w.ball_pos;
  {
    const double a = -th_deg(w.ball_vel) * kDegToRad;
    ball_to_player = {ball_to_player.x * std::cos(a) - ball_to_player.y * std::sin(a),
                      ball_to_player.x * std::sin(a) + ball_to_player.y * std::cos(a)};
  }
  int min_cycle = static_cast<int>(std::floor(std::fabs(ball_to_player.y) / kRealSpeedMax));
  if (p.tackling) {
    min_cycle += std::max(0, kTackleCycles - 2);
  }
  min_cycle = std::max(0, min_cycle);
  const double control_area = kKickableArea;
  for (int cycle = min_cycle; cycle < t.ball_cache_size; ++cycle) {
    const Vec2 ball_pos = t.ball_cache[static_cast<size_t>(cycle)];
    if (control_area + kRealSpeedMax * cycle + 0.5 < (p.pos - ball_pos).r()) {
      continue;
    }
    const int n_turn = predict_turn_cycle(p, cycle, control_area, ball_pos);
    const int n_dash = cycle - n_turn;
    if (n_dash >= 0 && can_reach_after_dash(p, n_turn, n_dash, control_area, ball_pos)) {
      return cycle;
    }
  }
  return predict_final(w, t, p);
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

// PROVISIONAL self reach: a turn when the ball is off the body axis, then full dashes.
int provisional_self_reach(const GoalieWorld& w, const InterceptTable& t) {
  for (int k = 0; k < t.ball_cache_size; ++k) {
    const Vec2 b = t.ball_cache[static_cast<size_t>(k)];
    const Vec2 me = self_inertia_point(w, k);
    const Vec2 d = b - me;
    const double control = (std::fabs(b.x) > kPitchHalfLength - 16.5 && std::fabs(b.y) < kPenaltyBoxHalfWidth)
                               ? kCatchableArea
                               : kKickableArea;
    const double need = d.r() - control;
    if (need <= 0.0) {
      return k;
    }
    const int turn = std::fabs(angle_norm(th_deg(d) - w.self.body_deg)) > 20.0 ? 1 : 0;
    if (k - turn > 0 && cycles_to_reach_distance(need) <= k - turn) {
      return k;
    }
  }
  return 1000;
}

}  // namespace

void predict_ball_and_opponents(const GoalieWorld& w, InterceptTable* t) {
  t->ball_cache_size = 0;
  t->self_cache_size = 0;
  t->self_reach_cycle = 1000;
  t->self_exhaust_reach_cycle = 1000;
  t->opponent_reach_cycle = 1000;
  t->teammate_reach_cycle = 1000;
  t->self_predicted = false;
  create_ball_cache(w, t);
  // InterceptTable::predictOpponent: 0 with a kickable opponent, else the fastest one.
  if (w.exist_kickable_opponent) {
    t->opponent_reach_cycle = 0;
  } else {
    for (int i = 0; i < w.num_opponents; ++i) {
      t->opponent_reach_cycle = std::min(t->opponent_reach_cycle, predict_opponent(w, *t, w.opponents[i]));
    }
  }
}

void predict_self(const GoalieWorld& w, InterceptTable* t) {
  t->self_predicted = true;
  t->self_reach_cycle = w.self_kickable ? 0 : provisional_self_reach(w, *t);
}

bool body_intercept(const GoalieWorld& w, const InterceptTable& t, bool, Command* out) {
  const Vec2 p = ball_inertia_point(w, std::min(t.self_reach_cycle, 30));
  return body_go_to_point(w, p, 0.5, 100.0, -1.0, 1, false, 15.0, out);
}

}  // namespace pamdp::hfo::agent2d
