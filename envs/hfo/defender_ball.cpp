// What an agent2d field defender does with the ball, and the intentions that follow: HFO's base
// team (b8b2a1d) src/sample_player.cpp (doForceKick, doIntention), src/chain_action/
// (Bhv_ChainAction, SelfPassGenerator, SampleFieldEvaluator, Bhv_NormalDribble and its
// IntentionNormalDribble, IntentionTurnTo) and librcsc's Body_KickOneStep and KickTable,
// re-implemented from their rules on the goalie's world model (defender.hpp).
#include "envs/hfo/defender_ball.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace pamdp::hfo::defender_ball {
namespace {

using agent2d::Command;
using agent2d::GoalieWorld;
using agent2d::InterceptTable;
using agent2d::mirror;

// Body_KickOneStep::get_max_possible_vel: the fastest first velocity along `angle_deg` one kick
// can give a ball moving at `ball_vel` (relative to the ball), or the kick that stops the ball
// when no kick reaches that direction. Circle2D::intersection(Ray2D) counts the circle's points
// on the ray's side (within 1 degree of its direction).
Vec2 max_possible_vel(double angle_deg, double kick_rate, Vec2 ball_vel, bool stop_when_none = true) {
  const double max_accel = std::min(kMaxKickPower * kick_rate, kBallAccelMax);
  const Vec2 u = polar(1.0, angle_deg * kDegToRad);
  const double along = u.x * ball_vel.x + u.y * ball_vel.y;
  const double disc = along * along - (ball_vel.r2() - max_accel * max_accel);
  Vec2 sols[2];
  int n = 0;
  if (disc >= 0.0) {
    for (const double t : {along - std::sqrt(disc), along + std::sqrt(disc)}) {
      const Vec2 p = u * t;
      if (std::fabs(agent2d::angle_norm(agent2d::th_deg(p) - angle_deg)) < 1.0) {
        sols[n++] = p;
      }
    }
  }
  if (n == 0) {
    if (!stop_when_none) {
      return {};  // KickTable::calc_max_velocity
    }
    Vec2 accel = ball_vel * -1.0;  // stop the ball
    if (const double r = accel.r(); r > max_accel) {
      accel *= max_accel / r;
    }
    return accel;
  }
  if (n == 1) {
    if (sols[0].r() > kBallSpeedMax) {
      // Only a circle holding the origin can bring the ball down to the speed limit.
      return ball_vel.r2() <= max_accel * max_accel ? sols[0] * (kBallSpeedMax / sols[0].r()) : Vec2{};
    }
    return sols[0];
  }
  Vec2 far = sols[0].r() >= sols[1].r() ? sols[0] : sols[1];
  const Vec2 near = sols[0].r() >= sols[1].r() ? sols[1] : sols[0];
  if (far.r() > kBallSpeedMax) {
    far = near.r() > kBallSpeedMax ? Vec2{} : far * (kBallSpeedMax / far.r());
  }
  return far;
}

double self_kick_rate(const GoalieWorld& w) {
  // SelfObject::updateBallInfo's kick rate (soccer_math.h kick_rate).
  const double dir_diff = std::fabs(agent2d::angle_norm(w.ball_angle_from_self_deg - w.self.body_deg));
  return kKickPowerRate *
         (1.0 - 0.25 * dir_diff / 180.0 - 0.25 * (w.ball_dist_from_self - kBallSize - kPlayerSize) / kKickableMargin);
}

// --- The chain action with the ball kickable (RoleCenterBack::doKick -> Bhv_ChainAction) -------
//
// HFO's base team searches chains of cooperative actions (SamplePlayer::createActionGenerator):
// a shot only as a chain's second action, and a pass, a cross, a short dribble or a self-pass
// as its first. The defender is over 35 m from the goal it attacks (its own frame's (52.5, 0)),
// so no chain reaches a shot, and the search is one step deep: every candidate's end state is
// scored by SampleFieldEvaluator (the ball's x, plus 40 minus its distance to that goal when
// positive), and the best one above the present state's score is played; with none, the
// default hold. Modelled here: the self-pass (SelfPassGenerator), the first kick of the dribble
// it plays (Bhv_NormalDribble) and the hold. Not yet: the pass (StrictCheckPassGenerator) and
// the short dribble (ShortDribbleGenerator), 5 % of the recorded chain actions together.

// SampleFieldEvaluator's evaluate_state for a state with the defender holding the ball at `ball`
// (no shot bonus: FieldAnalyzer::can_shoot_from needs the goal within reach).
double field_evaluation(Vec2 ball) {
  if (std::fabs(ball.x) > kPitchHalfLength || std::fabs(ball.y) > kPitchHalfWidth) {
    return -DBL_MAX / 2.0;
  }
  return ball.x + std::max(0.0, 40.0 - (Vec2{kPitchHalfLength, 0.0} - ball).r());
}

struct SelfPass {
  Vec2 receive;
  double first_speed = 0.0;
  int n_turn = 0;
  int n_dash = 0;
};

// SelfPassGenerator::createSelfCache: where the defender stands after one step of inertia (the
// kick), n_turn steps of inertia and full dashes along `dash_deg`; stops early where stamina,
// the goal line or the touch line ends the run. Returns the number of positions.
int self_pass_cache(const GoalieWorld& w, double dash_deg, int n_turn, int max_dash, std::array<Vec2, 24>* cache) {
  int n = 0;
  const double stamina_thr =
      agent2d::stamina_of(w.self).capacity_is_empty() ? -kExtraStamina : kRecoverDecThreshold + 350.0;
  agent2d::StaminaModel stamina = agent2d::stamina_of(w.self);
  Vec2 pos = w.self.pos + w.self.vel;
  Vec2 vel = w.self.vel * kPlayerDecay;
  stamina.wait();
  for (int i = 0; i < n_turn; ++i) {
    pos += vel;
    vel *= kPlayerDecay;
    stamina.wait();
    (*cache)[static_cast<size_t>(n++)] = pos;
  }
  const Vec2 dir = polar(1.0, dash_deg * kDegToRad);
  for (int i = 0; i < max_dash; ++i) {
    if (stamina.stamina < stamina_thr) {
      break;
    }
    const double power = std::min(kMaxDashPower, std::max(0.0, stamina.stamina - stamina_thr));
    vel += dir * (power * kDashPowerRate * stamina.effort);
    pos += vel;
    if (pos.x > kPitchHalfLength - 2.5) {
      break;
    }
    if (std::fabs(pos.y) > kPitchHalfWidth - 3.0 &&
        ((pos.y > 0.0 && dash_deg > 0.0) || (pos.y < 0.0 && dash_deg < 0.0))) {
      break;
    }
    vel *= kPlayerDecay;
    stamina.dash(power);
    (*cache)[static_cast<size_t>(n++)] = pos;
  }
  return n;
}

// SelfPassGenerator::canKick: one kick gives the ball its first speed, and neither the defender
// nor an opponent (after its inertia, or one full dash along its body) can touch it next cycle.
bool self_pass_can_kick(const GoalieWorld& w, double kick_rate, Vec2 receive, double first_speed) {
  const double target_deg = agent2d::th_deg(receive - w.ball_pos);
  const Vec2 max_vel = max_possible_vel(target_deg, kick_rate, w.ball_vel, false);
  if (max_vel.r2() < first_speed * first_speed) {
    return false;
  }
  const Vec2 my_next = w.self.pos + w.self.vel;
  const Vec2 ball_next = w.ball_pos + polar(first_speed, target_deg * kDegToRad);
  if ((my_next - ball_next).r2() < std::pow(kPlayerSize + kBallSize + 0.1, 2)) {
    return false;
  }
  for (int i = 0; i < w.num_opponents; ++i) {
    const agent2d::PlayerView& o = w.opponents[static_cast<size_t>(i)];
    Vec2 o_next = o.pos + o.vel;
    if ((ball_next - o_next).r2() < std::pow(kKickableArea + 0.1, 2)) {
      return false;
    }
    // Full state: its body is always fresh (bodyCount 0), so one full dash along it.
    o_next += polar(kMaxDashPower * kDashPowerRate * kEffortMax, o.body_deg * kDegToRad);
    if ((ball_next - o_next).r2() < kKickableArea * kKickableArea) {
      return false;
    }
  }
  return true;
}

// SelfPassGenerator::checkOpponent: no opponent reaches the receive point first (with full
// state every position and velocity count is 0, which fixes the bonus steps).
bool self_pass_safe(const GoalieWorld& w, int n_turn, int n_dash, Vec2 receive) {
  const int self_step = 1 + n_turn + n_dash;
  const double target_deg = agent2d::th_deg(receive - w.ball_pos);
  for (int i = 0; i < w.num_opponents; ++i) {
    const agent2d::PlayerView& o = w.opponents[static_cast<size_t>(i)];
    const Vec2 rel = agent2d::rotate_deg(o.pos - w.ball_pos, -target_deg);
    if (rel.x < -4.0) {
      continue;
    }
    const Vec2 opp_pos = o.pos + o.vel * ((1.0 - agent2d::player_decay_pow(self_step)) / (1.0 - kPlayerDecay));
    const double target_dist = (opp_pos - receive).r();
    if (target_dist > agent2d::kRealSpeedMax * self_step + kKickableArea) {
      continue;
    }
    if (target_dist - kKickableArea < 0.001) {
      return false;
    }
    const double dash_dist = target_dist - kKickableArea - 0.2 - (o.pos - w.self.pos).r() * 0.01;
    const int opp_n_dash = agent2d::cycles_to_reach_distance(dash_dist);
    const int opp_n_turn = agent2d::predict_player_turn_cycle(o.body_deg, o.vel.r(), target_dist,
                                                              agent2d::th_deg(receive - opp_pos), kKickableArea, false);
    const int opp_n_step = opp_n_turn == 0 ? opp_n_dash : opp_n_turn + opp_n_dash + 1;
    int bonus_step = receive.x < 27.0 ? 1 : 0;
    if (o.tackling) {
      bonus_step = -5;
    }
    if (rel.x > 0.8) {
      bonus_step += 1;  // and the position count's bonus, 0 with full state
    } else {
      // The generator assigns here, dropping the two bonuses above: bound(0, posCount -
      // penalty, 3), 0 with full state.
      bonus_step = 0;
    }
    if (opp_n_step - bonus_step <= self_step) {
      return false;
    }
  }
  return true;
}

// SelfPassGenerator::createCourses and the one-step search over its courses: the best
// self-pass by the field evaluation (ties to the course nearer the goal it attacks, the
// generator's order), or false when none scores above `floor_eval`.
bool best_self_pass(const GoalieWorld& w, double kick_rate, double floor_eval, SelfPass* out) {
  constexpr int kAngleDivs = 60;
  constexpr double kAngleStep = 360.0 / kAngleDivs;
  constexpr int kMinDash = 5;
  const Vec2 ball = w.ball_pos;
  const int max_dash = ball.x < -20.0 ? 6 : ball.x < 0.0 ? 7 : ball.x < 10.0 ? 13 : ball.x < 20.0 ? 15 : 20;
  const double max_effective_turn = kMaxMoment / (1.0 + kInertiaMoment * w.self.vel.r() * kPlayerDecay);
  const Vec2 our_goal{-kPitchHalfLength, 0.0};
  const Vec2 their_goal{kPitchHalfLength, 0.0};
  constexpr double kTheirPenaltyLineX = kPitchHalfLength - 16.5;
  double best_eval = floor_eval;  // the present state's, ActionChainGraph's start, or a queued dribble's
  double best_goal_dist2 = DBL_MAX;
  bool found = false;
  std::array<Vec2, 24> cache{};
  for (int a = 0; a < kAngleDivs; ++a) {
    const double add_angle = kAngleStep * a;
    int n_turn = 0;
    if (a != 0) {
      if (std::fabs(agent2d::angle_norm(add_angle)) > max_effective_turn) {
        continue;
      }
      n_turn = 1;
    }
    const double dash_deg = agent2d::angle_norm(w.self.body_deg + add_angle);
    if (ball.x < kTheirPenaltyLineX + 5.0 && std::fabs(dash_deg) > 85.0) {
      continue;
    }
    const int size = self_pass_cache(w, dash_deg, n_turn, max_dash, &cache);
    // This direction's courses, the longest first (every second dash step down to 10, then each).
    std::array<int, 12> dashes{};
    int num = 0;
    for (int n_dash = size - n_turn, dash_dec = 2; n_dash >= kMinDash; n_dash -= dash_dec) {
      if (n_dash <= 10) {
        dash_dec = 1;
      }
      dashes[static_cast<size_t>(num++)] = n_dash;
    }
    // The generator keeps at most 10 courses of a direction. Only a course that could beat the
    // best so far is checked (the checks are the cost); the others are checked only if the count
    // they might fill decides whether an 11th course is looked at.
    const auto receive_of = [&](int c) {
      return cache[static_cast<size_t>(n_turn + dashes[static_cast<size_t>(c)] - 1)];
    };
    const auto first_speed_of = [&](int c) {
      return agent2d::first_term_geom_series((receive_of(c) - ball).r(), kBallDecay,
                                             1 + n_turn + dashes[static_cast<size_t>(c)]);
    };
    const auto accepted = [&](int c) {
      const Vec2 receive = receive_of(c);
      return (receive - our_goal).r2() >= 18.0 * 18.0 && self_pass_can_kick(w, kick_rate, receive, first_speed_of(c)) &&
             self_pass_safe(w, n_turn, dashes[static_cast<size_t>(c)], receive);
    };
    int count = 0;
    std::array<int, 12> unchecked{};
    int num_unchecked = 0;
    for (int c = 0; c < num; ++c) {
      const Vec2 receive = receive_of(c);
      const double eval = field_evaluation(receive);
      const double goal_dist2 = (receive - their_goal).r2();
      if (!(eval > best_eval || (found && eval == best_eval && goal_dist2 < best_goal_dist2))) {
        unchecked[static_cast<size_t>(num_unchecked++)] = c;
        continue;
      }
      if (c >= 10) {  // the courses before it all kept?
        int kept = count;
        for (int u = 0; u < num_unchecked; ++u) {
          kept += accepted(unchecked[static_cast<size_t>(u)]) ? 1 : 0;
        }
        if (kept >= 10) {
          break;
        }
      }
      if (!accepted(c)) {
        continue;
      }
      ++count;
      best_eval = eval;
      best_goal_dist2 = goal_dist2;
      *out = {receive, first_speed_of(c), n_turn, dashes[static_cast<size_t>(c)]};
      found = true;
    }
  }
  return found;
}

// IntentionNormalDribble::checkOpponent: an opponent (the nearest to the defender) at the ball
// now, or on the ball's next position next cycle along its body, breaks the queue off.
bool dribble_opponent_near(const GoalieWorld& w) {
  const agent2d::PlayerView* nearest = nullptr;
  double nearest_d2 = DBL_MAX;
  for (int i = 0; i < w.num_opponents; ++i) {
    const agent2d::PlayerView& o = w.opponents[static_cast<size_t>(i)];
    if (const double d2 = (o.pos - w.self.pos).r2(); d2 < nearest_d2) {
      nearest_d2 = d2;
      nearest = &o;
    }
  }
  if (nearest == nullptr) {
    return false;
  }
  const Vec2 ball_next = w.ball_pos + w.ball_vel;
  if ((nearest->pos - w.ball_pos).r() < kKickableArea + 0.2) {
    return true;
  }
  if ((nearest->pos - ball_next).r() < kPlayerSpeedMax + kKickableArea + 0.3) {
    // Full state: its body is known (bodyCount 0); the distance from the line along it.
    const Vec2 opp_next = nearest->pos + nearest->vel;
    const Vec2 along = polar(1.0, nearest->body_deg * kDegToRad);
    const Vec2 rel = ball_next - opp_next;
    if (std::fabs(along.x * rel.y - along.y * rel.x) <= 1.2 && rel.r() < 0.6 + 1.2) {
      return true;
    }
  }
  return false;
}

// PlayerAgent::doIntention with IntentionNormalDribble: true and the command when the queue
// plays this cycle; false when it has ended or breaks off (the defender then decides afresh).
bool play_dribble_queue(const GoalieWorld& w, int cycle, const PlayerState::Intention& queue, double kick_rate,
                        DefenderDecision* d) {
  // finished()
  if (queue.kind != PlayerState::Intention::Kind::kDribble || queue.turns + queue.dashes <= 0 ||
      queue.last_cycle + 1 != cycle || w.exist_kickable_teammate || w.exist_kickable_opponent) {
    return false;
  }
  const Vec2 target = mirror(queue.target);
  if ((w.ball_pos - target).r2() < 1.0 && (w.self.pos - target).r2() < 1.0) {
    return false;
  }
  const Vec2 ball_next = w.ball_pos + w.ball_vel;
  if (std::fabs(ball_next.x) > kPitchHalfLength - 0.5 || std::fabs(ball_next.y) > kPitchHalfWidth - 0.5) {
    return false;
  }
  // execute(): with the ball at its feet again and no turn left, the chain action runs again
  // with the queued dribble among its candidates (ShortDribbleGenerator::setQueuedAction, ahead
  // of the self-passes); anything else chosen cancels the queue.
  if (w.self_kickable && queue.turns <= 0) {
    const double queued = field_evaluation(target);
    SelfPass better;
    if (!(queued > field_evaluation(w.ball_pos)) || best_self_pass(w, kick_rate, queued, &better)) {
      return false;
    }
  }
  if (dribble_opponent_near(w)) {
    return false;
  }
  PlayerState::Intention next = queue;
  next.last_cycle = cycle;
  if (next.turns > 0) {
    // doTurn: toward the target from where its inertia leaves it, unless already facing it.
    --next.turns;
    const Vec2 my_inertia = agent2d::self_inertia_point(w, next.turns + next.dashes);
    const double target_dist = (target - my_inertia).r();
    const double angle_diff = agent2d::angle_norm(agent2d::th_deg(target - my_inertia) - w.self.body_deg);
    const double margin = std::max(15.0, std::fabs(std::atan2(0.5, target_dist) * kRadToDeg));
    if (std::fabs(angle_diff) < margin) {
      return false;
    }
    d->command = agent2d::do_turn(w, angle_diff);
  } else if (next.dashes > 0) {
    // doDash: a safe full dash along the body, unless it would run over the ball or leave it.
    --next.dashes;
    const double power = agent2d::safety_dash_power(w, kMaxDashPower);
    const Vec2 my_next =
        w.self.pos + w.self.vel + polar(power * kDashPowerRate * w.self.effort, w.self.body_deg * kDegToRad);
    const Vec2 rel = agent2d::rotate_deg(ball_next - my_next, -w.self.body_deg);
    const double dist = rel.r();
    if (dist < kPlayerSize + kBallSize || std::fabs(rel.y) > kKickableArea - 0.1) {
      return false;
    }
    if (next.dashes <= 0 && dist > kKickableArea - 0.15) {
      return false;
    }
    if (next.dashes > 0 &&
        std::fabs(agent2d::angle_norm(w.self.body_deg - agent2d::th_deg(ball_next - my_next))) > 90.0 &&
        dist > kKickableArea - 0.2) {
      return false;
    }
    d->command = agent2d::do_dash(w, power, 0.0);
  } else {
    return false;
  }
  d->rule = DefenderDecision::Rule::kDribbleQueue;
  d->target = queue.target;
  d->intention = next;
  return true;
}

// --- Bhv_ChainAction::doTurnToForward and its IntentionTurnTo -------------------------------

// The opponents by distance from the defender (WorldModel::opponentsFromSelf), into `order`.
int opponents_from_self(const GoalieWorld& w, std::array<int, GoalieWorld::kMaxOpponents>* order) {
  const int n = w.num_opponents;
  for (int i = 0; i < n; ++i) {
    (*order)[static_cast<size_t>(i)] = i;
  }
  // Insertion sort: at most 3 opponents.
  const auto d2 = [&](int i) { return (w.opponents[static_cast<size_t>(i)].pos - w.self.pos).r2(); };
  for (int i = 1; i < n; ++i) {
    for (int j = i; j > 0 && d2((*order)[static_cast<size_t>(j)]) < d2((*order)[static_cast<size_t>(j - 1)]); --j) {
      std::swap((*order)[static_cast<size_t>(j)], (*order)[static_cast<size_t>(j - 1)]);
    }
  }
  return n;
}

// FieldAnalyzer::predict_player_reach_cycle with keep_ball's arguments (no penalty distance, its
// body known, no wait, back dashes allowed).
int player_reach_cycle(const agent2d::PlayerView& o, Vec2 target, double dist_thr) {
  const double speed = o.vel.r();
  const Vec2 final_pos = o.pos + o.vel * (1.0 / (1.0 - kPlayerDecay));
  const double final_dist = (final_pos - target).r();
  const int final_reach = agent2d::predict_player_turn_cycle(o.body_deg, speed, final_dist,
                                                             agent2d::th_deg(target - final_pos), dist_thr, true) +
                          agent2d::cycles_to_reach_distance(final_dist);
  constexpr int kMaxCycle = 6;
  if (final_reach > kMaxCycle) {
    return final_reach;
  }
  for (int cycle = 0; cycle <= kMaxCycle; ++cycle) {
    const Vec2 inertia = o.pos + o.vel * ((1.0 - agent2d::player_decay_pow(cycle)) / (1.0 - kPlayerDecay));
    const double target_dist = (inertia - target).r();
    if (target_dist < dist_thr) {
      return cycle;
    }
    const double dash_dist = target_dist - dist_thr * 0.5;
    if (dash_dist < 0.001) {
      return cycle;
    }
    if (dash_dist > agent2d::kRealSpeedMax * cycle) {
      continue;
    }
    const int n_dash = agent2d::cycles_to_reach_distance(dash_dist);
    if (n_dash > cycle) {
      continue;
    }
    const int n_turn = agent2d::predict_player_turn_cycle(o.body_deg, speed, target_dist,
                                                          agent2d::th_deg(target - inertia), dist_thr, true);
    if (n_turn + n_dash <= cycle) {
      return cycle;
    }
  }
  return final_reach;
}

// Bhv_ChainAction::getKeepBallVel: of 12 points around where the defender will be in two
// cycles, the ball velocity that takes the ball there (in two cycles) and leaves the nearby
// opponents (within 10 m) the most steps to it, then the slowest; false when no kick reaches any.
bool keep_ball_vel(const GoalieWorld& w, double kick_rate, Vec2* out) {
  constexpr int kAngleDivs = 12;
  const double collide_dist2 = std::pow(kPlayerSize + kBallSize, 2);
  const double keep_dist = kPlayerSize + kKickableMargin * 0.5 + kBallSize;
  const Vec2 next_self = w.self.pos + w.self.vel;
  const Vec2 next2_self = next_self + w.self.vel * kPlayerDecay;
  std::array<int, GoalieWorld::kMaxOpponents> order{};
  const int n_opp = opponents_from_self(w, &order);
  bool found = false;
  int best_opponent_step = 0;
  double best_speed = 1000.0;
  for (int a = 0; a < kAngleDivs; ++a) {
    const Vec2 keep = next2_self + polar(keep_dist, 360.0 / kAngleDivs * a * kDegToRad);
    if (std::fabs(keep.x) > kPitchHalfLength - 0.2 || std::fabs(keep.y) > kPitchHalfWidth - 0.2) {
      continue;
    }
    const Vec2 move = keep - w.ball_pos;
    const double speed = move.r() / (1.0 + kBallDecay);
    const double move_deg = agent2d::th_deg(move);
    if (max_possible_vel(move_deg, kick_rate, w.ball_vel, false).r2() < speed * speed) {
      continue;
    }
    const Vec2 vel = polar(speed, move_deg * kDegToRad);
    const Vec2 ball_next = w.ball_pos + vel;
    Vec2 ball_next_next = keep;
    if ((next_self - ball_next).r2() < collide_dist2) {
      ball_next_next = ball_next + vel * (kBallDecay * -0.1);
    }
    int min_step = 1000;
    for (int i = 0; i < n_opp; ++i) {
      const agent2d::PlayerView& o = w.opponents[static_cast<size_t>(order[static_cast<size_t>(i)])];
      if ((o.pos - w.self.pos).r() > 10.0) {
        break;
      }
      const int o_step = player_reach_cycle(o, ball_next_next, kKickableArea);
      if (o_step <= 0) {
        break;
      }
      min_step = std::min(min_step, o_step);
    }
    if (min_step > best_opponent_step || (min_step == best_opponent_step && best_speed > speed)) {
      *out = vel;
      best_opponent_step = min_step;
      best_speed = speed;
      found = true;
    }
  }
  return found;
}

// Bhv_ChainAction::doTurnToForward: true and the command when the defender, facing its own goal
// (over 110 degrees off (42, 0)) with no opponent within 4 m, turns toward (42, y / 2), or kicks
// the ball to a keep point first when it would leave its feet (then turns the next cycle).
bool turn_to_forward(const GoalieWorld& w, int cycle, double kick_rate, DefenderDecision* d) {
  Vec2 face{42.0, 0.0};
  if (std::fabs(agent2d::angle_norm(agent2d::th_deg(face - w.self.pos) - w.self.body_deg)) < 110.0) {
    return false;
  }
  std::array<int, GoalieWorld::kMaxOpponents> order{};
  const int n_opp = opponents_from_self(w, &order);
  for (int i = 0; i < n_opp; ++i) {
    const double dist = (w.opponents[static_cast<size_t>(order[static_cast<size_t>(i)])].pos - w.self.pos).r();
    if (dist < 4.0) {
      return false;
    }
    if (dist > 10.0) {
      break;
    }
  }
  face.y = w.self.pos.y * 0.5;
  const double kickable = kKickableArea - w.self.vel.r() * w.player_rand - w.ball_vel.r() * w.ball_rand - 0.2;
  const Vec2 self_next = w.self.pos + w.self.vel;
  const Vec2 ball_next = w.ball_pos + w.ball_vel;
  d->rule = DefenderDecision::Rule::kTurnForward;
  d->target = mirror(face);
  if ((self_next - ball_next).r2() < kickable * kickable) {
    agent2d::body_turn_to_point(w, face, 1, &d->command);
    return true;
  }
  Vec2 vel;
  if (!keep_ball_vel(w, kick_rate, &vel)) {
    return false;
  }
  const Vec2 accel = vel - w.ball_vel;
  const double power = accel.r() / kick_rate;
  // Over the maximum power agent2d holds the ball instead (Body_HoldBall, not modelled: a kick
  // of power 0).
  d->command = power > kMaxKickPower ? Command{Command::Kind::kKick, 0.0, 0.0}
                                     : Command{Command::Kind::kKick, power,
                                               agent2d::angle_norm(agent2d::th_deg(accel) - w.self.body_deg)};
  d->intention = {PlayerState::Intention::Kind::kTurnToForward, d->target, 0, 0, cycle};
  return true;
}

// PlayerAgent::doIntention with IntentionTurnTo: the cycle after the keep kick, the turn toward
// the face point while the ball stays at its feet and no opponent is about to reach it.
bool play_turn_to(const GoalieWorld& w, int cycle, const PlayerState::Intention& intention, DefenderDecision* d) {
  if (intention.kind != PlayerState::Intention::Kind::kTurnToForward || intention.last_cycle + 1 != cycle ||
      !w.self_kickable || w.exist_kickable_opponent) {
    return false;
  }
  InterceptTable table;
  agent2d::predict_ball_and_opponents(w, &table);
  if (table.opponent_reach_cycle <= 1) {
    return false;
  }
  const double kickable = kKickableArea - w.self.vel.r() * w.player_rand - w.ball_vel.r() * w.ball_rand - 0.15;
  if ((w.self.pos + w.self.vel - (w.ball_pos + w.ball_vel)).r2() > kickable * kickable) {
    return false;
  }
  d->rule = DefenderDecision::Rule::kTurnForward;
  d->target = intention.target;
  agent2d::body_turn_to_point(w, mirror(intention.target), 1, &d->command);
  return true;
}

}  // namespace

// SamplePlayer::doForceKick: with the ball kickable by itself and an opponent alike, a field
// player kicks it as fast as one kick can toward the opponents' goal (Body_KickOneStep to
// (52.5, 0) in its own frame at ServerParam::ballSpeedMax; (45, 0) from beyond x 36 and |y| 10,
// which HFO's half field never puts a defender).
agent2d::Command force_kick(const GoalieWorld& w) {
  Vec2 target{kPitchHalfLength, 0.0};
  if (w.self.pos.x > 36.0 && std::fabs(w.self.pos.y) > 10.0) {
    target.x = 45.0;
  }
  const double kick_rate = self_kick_rate(w);
  Vec2 first_vel = max_possible_vel(agent2d::th_deg(target - w.ball_pos), kick_rate, w.ball_vel);
  if (const double r = first_vel.r(); r > kBallSpeedMax) {
    first_vel *= kBallSpeedMax / r;
  }
  const Vec2 accel = first_vel - w.ball_vel;
  const double power = std::min(accel.r() / kick_rate, kMaxKickPower);
  return {Command::Kind::kKick, power, agent2d::angle_norm(agent2d::th_deg(accel) - w.self.body_deg)};
}

void chain_action(const GoalieWorld& w, int cycle, DefenderDecision* d) {
  d->rule = DefenderDecision::Rule::kKick;
  const double kick_rate = self_kick_rate(w);
  if (turn_to_forward(w, cycle, kick_rate, d)) {
    return;
  }
  d->command = {Command::Kind::kKick, 0.0, 0.0};  // the hold: its kick is not modelled
  SelfPass pass;
  if (best_self_pass(w, kick_rate, field_evaluation(w.ball_pos), &pass)) {
    // Bhv_NormalDribble's first kick: the ball toward the receive point at the first speed.
    const Vec2 first_vel = polar(pass.first_speed, agent2d::th_deg(pass.receive - w.ball_pos) * kDegToRad);
    const Vec2 accel = first_vel - w.ball_vel;
    d->rule = DefenderDecision::Rule::kSelfPass;
    d->target = mirror(pass.receive);
    d->intention = {PlayerState::Intention::Kind::kDribble, d->target, pass.n_turn, pass.n_dash, cycle};
    d->command = {Command::Kind::kKick, accel.r() / kick_rate,
                  agent2d::angle_norm(agent2d::th_deg(accel) - w.self.body_deg)};
  }
}

bool play_intention(const GoalieWorld& w, int cycle, const PlayerState::Intention& intention, DefenderDecision* d) {
  return play_dribble_queue(w, cycle, intention, self_kick_rate(w), d) || play_turn_to(w, cycle, intention, d);
}

}  // namespace pamdp::hfo::defender_ball
