// librcsc's intercept table for the goalie (rcsc/player/intercept_table.cpp, player_intercept.cpp).
// The ball's path and the attacker's reach (InterceptTable::createBallCache, PlayerIntercept)
// and the goalie's intercept action (Body_Intercept2009); its own ways to the ball are in
// goalie_self_intercept.cpp. Our own code; rules and constants librcsc's, cited where used.
#include <algorithm>
#include <array>
#include <cmath>

#include "envs/hfo/client_effector.hpp"
#include "envs/hfo/goalie_world.hpp"

namespace pamdp::hfo::agent2d {
namespace {

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

}  // namespace

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

int predict_player_turn_cycle(double body_deg, double speed, double target_dist, double target_deg, double dist_thr,
                              bool use_back_dash) {
  double angle_diff = std::fabs(angle_norm(target_deg - body_deg));
  if (use_back_dash && target_dist < 5.0 && angle_diff > 90.0 && kMinDashPower < -kMaxDashPower + 1.0) {
    angle_diff = std::fabs(angle_diff - 180.0);  // a backward dash
  }
  double turn_margin = 180.0;
  if (dist_thr < target_dist) {
    turn_margin = std::max(15.0, std::asin(dist_thr / target_dist) * kRadToDeg);
  }
  int n_turn = 0;
  while (angle_diff > turn_margin) {
    angle_diff -= kMaxMoment / (1.0 + kInertiaMoment * speed);
    speed *= kPlayerDecay;
    ++n_turn;
  }
  return n_turn;
}

namespace {

Vec2 inertia_point(Vec2 pos, Vec2 vel, int n) {
  return pos + vel * ((1.0 - player_decay_pow(n)) / (1.0 - kPlayerDecay));
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
  const double control_area = kKickableArea;  // PlayerIntercept::predictFinal: the kickable area
  const int n_turn = predict_turn_cycle(p, 100, control_area, ball_pos);
  double dash_dist = (inertia_point(p.pos, p.vel, 100) - ball_pos).r() - control_area;
  dash_dist -= (p.pos - w.self.pos).r() * 0.03;  // the player's distance from self
  if (dash_dist < 0.0) {
    return ball_step;
  }
  const int n_dash = std::max(1, cycles_to_reach_distance(dash_dist));
  return std::max(ball_step, n_turn + n_dash);
}

// PlayerIntercept::predict for a player with full state (an opponent, or a field defender's
// teammate).
int predict_player(const GoalieWorld& w, const InterceptTable& t, const PlayerView& p) {
  Vec2 ball_to_player = p.pos - w.ball_pos;
  { ball_to_player = rotate_deg(ball_to_player, -th_deg(w.ball_vel)); }
  int min_cycle = static_cast<int>(std::floor(std::fabs(ball_to_player.y) / kRealSpeedMax));
  if (p.tackling) {
    min_cycle += std::max(0, kTackleCycles - 2);
  }
  min_cycle = std::max(0, min_cycle);
  for (int cycle = min_cycle; cycle < t.ball_cache_size; ++cycle) {
    const Vec2 ball_pos = t.ball_cache[static_cast<size_t>(cycle)];
    // A goalie (a field defender's teammate) controls the ball in its catchable area inside
    // either penalty area (PlayerIntercept::predict).
    const double control_area =
        (p.goalie && std::fabs(ball_pos.x) > kPitchHalfLength - 16.5 && std::fabs(ball_pos.y) < kPenaltyBoxHalfWidth)
            ? kCatchableArea
            : kKickableArea;
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

}  // namespace

void predict_ball_and_opponents(const GoalieWorld& w, InterceptTable* t) {
  t->ball_cache_size = 0;
  t->self_cache_size = 0;
  t->self_reach_cycle = 1000;
  t->self_exhaust_reach_cycle = 1000;
  t->opponent_reach_cycle = 1000;
  t->teammate_reach_cycle = 1000;
  t->goalie_reach_cycle = 1000;
  t->self_predicted = false;
  create_ball_cache(w, t);
  // InterceptTable::predictOpponent: 0 with a kickable opponent, else the fastest one.
  if (w.exist_kickable_opponent) {
    t->opponent_reach_cycle = 0;
  } else {
    for (int i = 0; i < w.num_opponents; ++i) {
      t->opponent_reach_cycle = std::min(t->opponent_reach_cycle, predict_player(w, *t, w.opponents[i]));
    }
  }
  // InterceptTable::predictTeammate: 0 with a kickable teammate, else the fastest one but the
  // goalie, whose cycle librcsc keeps apart (goalieReachCycle).
  if (w.exist_kickable_teammate) {
    t->teammate_reach_cycle = 0;
  } else {
    for (int i = 0; i < w.num_teammates; ++i) {
      const int cycle = predict_player(w, *t, w.teammates[i]);
      if (w.teammates[i].goalie) {
        t->goalie_reach_cycle = cycle;
      } else {
        t->teammate_reach_cycle = std::min(t->teammate_reach_cycle, cycle);
      }
    }
  }
}

namespace {

// Body_Intercept2009::getBestIntercept with USE_GOALIE_MODE (librcsc action/body_intercept2009.cpp).
const InterceptInfo* best_intercept(const GoalieWorld& w, const InterceptTable& t, bool save_recovery) {
  if (t.self_cache_size == 0) {
    return nullptr;
  }
  const Vec2 goal_pos{65.0, 0.0};
  const Vec2 our_goal_pos{-kPitchHalfLength, 0.0};
  const double max_pitch_x = kPitchHalfLength - 1.0;
  const double max_pitch_y = kPitchHalfWidth - 1.0;
  const double penalty_x = kOurPenaltyLineX;
  const double penalty_y = kPenaltyBoxHalfWidth;
  const double speed_max = kRealSpeedMax * 0.9;
  const int opp_min = t.opponent_reach_cycle;
  const int mate_min = t.teammate_reach_cycle;
  // WorldModel::offsideLineX with offside on: their defense line, here the attacker's x.
  double offside_line_x = 0.0;
  for (int i = 0; i < w.num_opponents; ++i) {
    offside_line_x = std::max(offside_line_x, w.opponents[i].pos.x);
  }
  const InterceptInfo* attacker_best = nullptr;
  double attacker_score = 0.0;
  const InterceptInfo* forward_best = nullptr;
  double forward_score = 0.0;
  const InterceptInfo* noturn_best = nullptr;
  double noturn_score = 10000.0;
  const InterceptInfo* nearest_best = nullptr;
  double nearest_score = 10000.0;
  const InterceptInfo* goalie_best = nullptr;
  double goalie_score = -10000.0;
  const InterceptInfo* goalie_aggressive_best = nullptr;
  double goalie_aggressive_score = -10000.0;
  const InterceptInfo* cache = t.self_cache.data();
  const int n = t.self_cache_size;
  for (int i = 0; i < n; ++i) {
    const InterceptInfo& c = cache[i];
    if (save_recovery && c.mode != InterceptInfo::Mode::kNormal) {
      continue;
    }
    const int cycle = c.reach_cycle();
    const Vec2 self_pos = self_inertia_point(w, cycle);
    const Vec2 ball_pos = ball_inertia_point(w, cycle);
    const Vec2 ball_vel = w.ball_vel * ball_decay_pow(cycle);
    if (std::fabs(ball_pos.x) > max_pitch_x || std::fabs(ball_pos.y) > max_pitch_y) {
      continue;
    }
    if (w.self.goalie && ball_pos.x < penalty_x - 1.0 && std::fabs(ball_pos.y) < penalty_y - 1.0 &&
        cycle < opp_min - 1) {
      if ((c.turn_cycle == 0 && c.ball_dist < kCatchableArea * 0.5) || c.ball_dist < 0.01) {
        const double d = (ball_pos - our_goal_pos).r2();
        if (d > goalie_score) {
          goalie_score = d;
          goalie_best = &c;
        }
      }
    }
    if (w.self.goalie && cycle < mate_min - 3 && cycle < opp_min - 5 &&
        (ball_pos.x > penalty_x - 1.0 || std::fabs(ball_pos.y) > penalty_y - 1.0)) {
      if ((c.turn_cycle == 0 && c.ball_dist < kKickableArea * 0.5) || c.ball_dist < 0.01) {
        if (ball_pos.x > goalie_aggressive_score) {
          goalie_aggressive_score = ball_pos.x;
          goalie_aggressive_best = &c;
        }
      }
    }
    const bool attacker = ball_vel.x > 0.5 && ball_vel.r2() > speed_max * speed_max && c.dash_power >= 0.0 &&
                          ball_pos.x < 47.0 && (ball_pos.x > 35.0 || ball_pos.x > offside_line_x);
    const double opp_rate = attacker ? 0.95 : 0.7;
    if (cycle >= opp_min * opp_rate) {
      continue;
    }
    if (attacker) {
      const double goal_dist = 100.0 - std::min(100.0, (ball_pos - goal_pos).r());
      const double x_diff = 47.0 - ball_pos.x;
      const double score = (goal_dist / 100.0) * std::exp(-(x_diff * x_diff) / (2.0 * 100.0));
      if (score > attacker_score) {
        attacker_best = &c;
        attacker_score = score;
      }
      continue;
    }
    if (c.turn_cycle == 0) {
      const double score = cycle;
      if (score < noturn_score) {
        noturn_best = &c;
        noturn_score = score;
      }
      continue;
    }
    if (ball_vel.x > 0.1 && cycle <= opp_min - 5 && ball_vel.r2() > 0.6 * 0.6) {
      const double score = 100.0 * 100.0 - std::min(100.0 * 100.0, (ball_pos - goal_pos).r2());
      if (score > forward_score) {
        forward_best = &c;
        forward_score = score;
      }
      continue;
    }
    const double d = (self_pos - ball_pos).r2();
    if (d < nearest_score) {
      nearest_best = &c;
      nearest_score = d;
    }
  }
  if (goalie_aggressive_best != nullptr) {
    return goalie_aggressive_best;
  }
  if (goalie_best != nullptr) {
    return goalie_best;
  }
  if (attacker_best != nullptr) {
    return attacker_best;
  }
  if (noturn_best != nullptr && forward_best != nullptr) {
    const Vec2 v = w.ball_vel * ball_decay_pow(noturn_best->reach_cycle());
    if (v.x > 0.1 && (v.r() > speed_max || noturn_best->reach_cycle() <= forward_best->reach_cycle() + 2)) {
      return noturn_best;
    }
  }
  if (forward_best != nullptr) {
    return forward_best;
  }
  const Vec2 fastest_pos = ball_inertia_point(w, cache[0].reach_cycle());
  const Vec2 fastest_vel = w.ball_vel * ball_decay_pow(cache[0].reach_cycle());
  if ((fastest_pos.x > -33.0 || std::fabs(fastest_pos.y) > 20.0) &&
      (cache[0].reach_cycle() >= 10 || fastest_vel.r() < 1.2)) {
    return &cache[0];
  }
  if (noturn_best != nullptr && nearest_best != nullptr) {
    const Vec2 noturn_self = self_inertia_point(w, noturn_best->reach_cycle());
    const Vec2 noturn_ball = ball_inertia_point(w, noturn_best->reach_cycle());
    const Vec2 nearest_self = self_inertia_point(w, nearest_best->reach_cycle());
    const Vec2 nearest_ball = ball_inertia_point(w, nearest_best->reach_cycle());
    if ((noturn_self - noturn_ball).r2() < (nearest_self - nearest_ball).r2()) {
      return noturn_best;
    }
    if (nearest_best->reach_cycle() <= noturn_best->reach_cycle() + 2) {
      const Vec2 nearest_vel = w.ball_vel * ball_decay_pow(nearest_best->reach_cycle());
      const double nearest_speed = nearest_vel.r();
      if (nearest_speed < 0.7) {
        return nearest_best;
      }
      const Vec2 noturn_vel = w.ball_vel * ball_decay_pow(noturn_best->reach_cycle());
      if (nearest_best->ball_dist < kKickableArea - 0.4 && nearest_best->ball_dist < noturn_best->ball_dist &&
          noturn_vel.x < 0.5 && noturn_vel.r2() > 1.0 && noturn_ball.x > nearest_ball.x) {
        return nearest_best;
      }
      if (nearest_speed > 0.7 && (nearest_self - nearest_ball).r() < kKickableArea) {
        return nearest_best;
      }
    }
    return noturn_best;
  }
  if (noturn_best != nullptr) {
    return noturn_best;
  }
  if (nearest_best != nullptr) {
    return nearest_best;
  }
  if (w.self.pos.x > 40.0 && w.ball_vel.r() > 1.8 && std::fabs(th_deg(w.ball_vel)) < 100.0 &&
      cache[0].reach_cycle() > 1) {
    const InterceptInfo* chance_best = nullptr;
    for (int i = 0; i < n; ++i) {
      if (cache[i].reach_cycle() <= cache[0].reach_cycle() + 3 && cache[i].reach_cycle() <= opp_min - 2) {
        chance_best = &cache[i];
      }
    }
    if (chance_best != nullptr) {
      return chance_best;
    }
  }
  return &cache[0];
}

// Body_Intercept2009::doWaitTurn. The default face point (M_face_point invalid) is (50.5, y x 0.9).
bool wait_turn(const GoalieWorld& w, const InterceptTable& t, Vec2 target_point, const InterceptInfo& info,
               Command* out) {
  {
    // getOpponentNearestToSelf(5): the nearest opponent.
    double nearest = 1e9;
    for (int i = 0; i < w.num_opponents; ++i) {
      nearest = std::min(nearest, (w.opponents[i].pos - w.self.pos).r());
    }
    if (nearest < 3.0) {
      return false;
    }
    if (info.reach_cycle() > t.opponent_reach_cycle - 5) {
      return false;
    }
  }
  const Vec2 my_inertia = self_inertia_point(w, info.reach_cycle());
  const Vec2 target_rel = rotate_deg(target_point - my_inertia, -w.self.body_deg);
  const double target_dist = target_rel.r();
  const double ball_travel = w.ball_vel.r() * (1.0 - ball_decay_pow(info.reach_cycle())) / (1.0 - kBallDecay);
  const double ball_noise = ball_travel * w.ball_rand;
  if (info.reach_cycle() == 1 && info.turn_cycle == 1) {
    body_turn_to_point(w, Vec2{50.5, w.self.pos.y * 0.9}, 1, out);
    return true;
  }
  double extra_buf = 0.1 * clamp(info.reach_cycle() - 1, 0, 4);
  {
    const double angle_diff = std::fabs(angle_norm(th_deg(w.ball_vel) - w.self.body_deg));
    if (angle_diff < 10.0 || 170.0 < angle_diff) {
      extra_buf = 0.0;
    }
  }
  const double dist_buf = kKickableArea - 0.3 + extra_buf;  // the ball is seen this cycle
  if (target_dist > dist_buf) {
    return false;
  }
  Vec2 face_point{50.5, w.self.pos.y * 0.9};
  if (info.reach_cycle() > 2) {
    face_point = my_inertia + rotate_deg(w.ball_pos - my_inertia, 90.0);
    if (face_point.x < my_inertia.x) {
      face_point = my_inertia + rotate_deg(w.ball_pos - my_inertia, -90.0);
    }
  }
  const double face_angle = th_deg(face_point - my_inertia);
  // librcsc rotates by +face_angle here (Vector2D::rotate), which we keep.
  const Vec2 faced_rel = rotate_deg(target_point - my_inertia, face_angle);
  if (std::fabs(faced_rel.y) > kKickableArea - ball_noise - 0.2) {
    return false;
  }
  body_turn_to_point(w, face_point, 1, out);
  return true;
}

// Body_Intercept2009::doInertiaDash for the goalie (its body-angle buffer applies to field
// players only).
bool inertia_dash(const GoalieWorld& w, Vec2 target_point, const InterceptInfo& info, bool save_recovery,
                  Command* out) {
  if (info.reach_cycle() == 1) {
    *out = do_dash(w, info.dash_power, info.dash_angle_deg);
    return true;
  }
  Vec2 target_rel = rotate_deg(target_point - w.self.pos, -w.self.body_deg);
  if (!w.self.goalie && std::fabs(w.self.body_deg) < 50.0) {
    // A field player facing the opponents' side stops slightly short of the ball (the goalie,
    // whose opponents kicked last, never does).
    const Vec2 ball_vel = w.ball_vel * ball_decay_pow(info.reach_cycle());
    const int n = info.reach_cycle();
    double buf = 0.3;
    if (n >= 8) {
      buf = 0.0;
    } else if (std::fabs(target_rel.y) > kKickableArea - 0.25) {
      buf = 0.0;
    } else if (target_rel.x < 0.0 || target_rel.x < 0.3) {
      buf = n >= 3 ? 0.5 : buf;
    } else if (std::fabs(target_rel.y) < 0.5) {
      buf = n >= 3 ? 0.5 : (n == 2 ? std::min(target_rel.x, 0.5) : buf);
    } else if (ball_vel.r() < 1.6) {
      buf = 0.4;
    } else if (n == 2) {
      buf = std::min(target_rel.x, 0.3);
    }
    target_rel.x -= buf;
  }
  double used_power = info.dash_power;
  const double dash_rate = w.self.effort * kDashPowerRate;
  if (w.ball_vel.r() * ball_decay_pow(info.reach_cycle()) < kKickableArea * 1.5 &&
      std::fabs(info.dash_angle_deg) < 5.0 &&
      std::fabs(target_rel.x) < kKickableArea + dash_rate * kMaxDashPower * 0.8) {
    double first_speed = first_term_geom_series(target_rel.x, kPlayerDecay, info.reach_cycle());
    first_speed = clamp(first_speed, -kPlayerSpeedMax, kPlayerSpeedMax);
    const Vec2 rel_vel = rotate_deg(w.self.vel, -w.self.body_deg);
    const double required_accel = first_speed - rel_vel.x;
    used_power = required_accel / dash_rate;
    used_power /= dash_dir_rate(info.dash_angle_deg);
    used_power = clamp(used_power, kMinDashPower, kMaxDashPower);
    if (save_recovery) {
      used_power = safety_dash_power(w, used_power);
    }
  }
  if (info.reach_cycle() >= 4 && (std::fabs(target_rel.x) < 0.5 || std::fabs(used_power) < 5.0)) {
    const Vec2 my_inertia = self_inertia_point(w, info.reach_cycle());
    Vec2 face_point{50.5, w.self.pos.y * 0.75};
    const double face_angle = th_deg(face_point - my_inertia);
    const Vec2 ball_next = w.ball_pos + w.ball_vel;
    const double ball_angle = th_deg(ball_next - my_inertia);
    // ViewWidth::width(NORMAL) in synch_see mode (agent2d's player.conf): visible_angle x 2 x
    // simulator_step / send_step = 90 x 2 x 100 / 150.
    const double normal_half_width = 90.0 * 2.0 * 100.0 / 150.0;
    if (std::fabs(angle_norm(ball_angle - face_angle)) > 90.0 + normal_half_width - 10.0) {
      face_point.x = my_inertia.x;
      if (ball_next.y > my_inertia.y + 1.0) {
        face_point.y = 50.0;
      } else if (ball_next.y < my_inertia.y - 1.0) {
        face_point.y = -50.0;
      } else {
        face_point = ball_next;
      }
    }
    body_turn_to_point(w, face_point, 1, out);
    return true;
  }
  *out = do_dash(w, used_power, info.dash_angle_deg);
  return true;
}

}  // namespace

bool body_intercept(const GoalieWorld& w, const InterceptTable& t, bool save_recovery, Command* out) {
  // doKickableOpponentCheck.
  if (w.ball_dist_from_self < 2.0 && w.exist_kickable_opponent && w.num_opponents > 0) {
    const PlayerView& opp = w.opponents[0];
    const Vec2 goal_pos{-kPitchHalfLength, 0.0};
    const Vec2 my_next = w.self.pos + w.self.vel;
    const Vec2 attack_pos = opp.pos + opp.vel;
    if ((attack_pos - goal_pos).r2() > (my_next - goal_pos).r2()) {
      body_go_to_point(w, attack_pos, 0.1, kMaxDashPower, -1.0, 1, true, 15.0, out);
      return true;
    }
  }
  if (t.self_reach_cycle > 100) {
    const Vec2 final_point = w.ball_pos + w.ball_vel * (1.0 / (1.0 - kBallDecay));
    body_go_to_point(w, final_point, 2.0, kMaxDashPower, -1.0, 100, true, 15.0, out);
    return true;
  }
  const InterceptInfo* best = best_intercept(w, t, save_recovery);
  if (best == nullptr) {
    // An empty cache: librcsc goes on with an invalid InterceptInfo (reach 20000), whose dash
    // cycle is not 0 and turn cycle not 0: a turn toward the ball's final point.
    const Vec2 final_point = w.ball_pos + w.ball_vel * (1.0 / (1.0 - kBallDecay));
    *out = do_turn(w, angle_norm(th_deg(final_point - self_inertia_final_point(w)) - w.self.body_deg));
    return true;
  }
  const Vec2 target_point = ball_inertia_point(w, best->reach_cycle());
  if (best->dash_cycle == 0) {
    body_turn_to_point(w, Vec2{50.5, w.self.pos.y * 0.75}, best->reach_cycle(), out);
    return true;
  }
  if (best->turn_cycle > 0) {
    const Vec2 my_inertia = self_inertia_point(w, best->reach_cycle());
    double target_angle = th_deg(target_point - my_inertia);
    if (best->dash_power < 0.0) {
      target_angle = angle_norm(target_angle - 180.0);
    }
    *out = do_turn(w, angle_norm(target_angle - w.self.body_deg));
    return true;
  }
  if (wait_turn(w, t, target_point, *best, out)) {
    return true;
  }
  if (save_recovery && !stamina_of(w.self).capacity_is_empty()) {
    const double consumed = best->dash_power < 0.0 ? best->dash_power * -2.0 : best->dash_power;
    if (w.self.stamina - consumed < kRecoverDecThreshold + 1.0) {
      *out = do_turn(w, 0.0);
      return false;
    }
  }
  return inertia_dash(w, target_point, *best, save_recovery, out);
}

}  // namespace pamdp::hfo::agent2d
