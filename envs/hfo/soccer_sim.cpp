#include "envs/hfo/soccer_sim.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string_view>

#include "envs/hfo/client_effector.hpp"
#include "envs/hfo/defender.hpp"
#include "envs/hfo/goalie.hpp"

namespace pamdp::hfo {
namespace {

constexpr double kPi = std::numbers::pi;

// Goal line test of the server referee: the ball's centre must pass x = 52.5 + ball radius,
// between the outer edges of the posts (reference §5.2).
constexpr double kGoalLineX = kPitchHalfLength + kBallSize;       // 52.585
constexpr double kGoalMouthY = kGoalHalfWidth + kGoalPostRadius;  // 7.07
// Separation the server leaves between an object and a post after a bounce, so that the
// reflected remainder of the move is not detected at the same contact point again.
constexpr double kPostSeparation = 1e-10;
constexpr double kCollisionSeparation = 1e-10;
// E1 trainer: a player "holds" the ball within 1.5 x the kickable area.
constexpr double kTrainerHoldDist = 1.5 * (kKickableMargin + kPlayerSize + kBallSize);

// Centre of the post in the same quadrant as p (the only post p can reach in one cycle).
Vec2 nearest_post(Vec2 p) {
  return {p.x >= 0.0 ? kPitchHalfLength - kGoalPostRadius : -(kPitchHalfLength - kGoalPostRadius),
          p.y >= 0.0 ? kGoalHalfWidth + kGoalPostRadius : -(kGoalHalfWidth + kGoalPostRadius)};
}

// Earliest t in [0, 1] at which a circle of radius r moving from p by m touches centre c, or -1.
double post_contact_time(Vec2 p, Vec2 m, Vec2 c, double r) {
  const Vec2 d = p - c;
  const double a = m.r2();
  const double b = 2.0 * d.dot(m);
  const double cc = d.r2() - r * r;
  if (a == 0.0 || b >= 0.0 || cc < 0.0) {
    return -1.0;  // not moving, moving away, or already overlapping (handled separately)
  }
  const double disc = b * b - 4.0 * a * cc;
  if (disc < 0.0) {
    return -1.0;
  }
  const double t = (-b - std::sqrt(disc)) / (2.0 * a);
  return (t >= 0.0 && t <= 1.0) ? t : -1.0;
}

Vec2 reflect(Vec2 v, Vec2 unit_normal) {
  return v - unit_normal * (2.0 * v.dot(unit_normal));
}

}  // namespace

const char* status_name(int status) {
  switch (status) {
    case kInGame: return "IN_GAME";
    case kGoal: return "GOAL";
    case kCapturedByDefense: return "CAPTURED_BY_DEFENSE";
    case kOutOfBounds: return "OUT_OF_BOUNDS";
    case kOutOfTime: return "OUT_OF_TIME";
    default: return "UNKNOWN";
  }
}

SoccerSim::SoccerSim(const SoccerSimConfig& config, uint64_t seed) : config_(config), rng_(seed) {
  if (config_.offense_agents < 1 || config_.offense_agents > kMaxOffenseAgents) {
    throw std::invalid_argument("SoccerSim: offense_agents must be within [1, " + std::to_string(kMaxOffenseAgents) +
                                "], got " + std::to_string(config_.offense_agents));
  }
  if (config_.field_defenders < 0 || config_.field_defenders > kMaxFieldDefenders ||
      (config_.field_defenders > 0 && !config_.goalie)) {
    throw std::invalid_argument("SoccerSim: field_defenders must be within [0, " + std::to_string(kMaxFieldDefenders) +
                                "] and needs the goalie, got " + std::to_string(config_.field_defenders));
  }
  std::array<PlayerState, kMaxOffenseAgents> offense{};
  for (int i = 0; i < config_.offense_agents; ++i) {
    offense[i].pos = {0.0, 2.0 * i};
  }
  set_state(std::span<const PlayerState>(offense.data(), config_.offense_agents), BallState{{10.0, 0.0}, {0.0, 0.0}});
}

void SoccerSim::set_training_updates(int64_t updates) {
  const int64_t span = config_.start_curriculum_updates;
  if (span <= 0) {
    return;
  }
  const double done = std::clamp(static_cast<double>(updates) / static_cast<double>(span), 0.0, 1.0);
  start_scale_ = config_.start_curriculum_from + (1.0 - config_.start_curriculum_from) * done;
}

void SoccerSim::reset_episode() {
  // Ball (velocity 0), reference §5.1.
  double bx = 0.0;
  switch (config_.start) {
    case StartDistribution::kPaper: bx = 0.2 * rng_.uniform(-0.1, kPitchHalfLength) + 5.25; break;
    case StartDistribution::kDec2015:
    case StartDistribution::kHfo: bx = kPitchHalfLength * rng_.uniform(0.0, 0.2); break;
  }
  double by = kPitchHalfWidth * rng_.uniform(-0.8, 0.8);

  // Offense agents: HFORef::resetField (rcssserver referee.cpp) shuffles its ten offsets
  // around the ball each reset and gives offset i to the i-th offense player, so no two share
  // one; then the era's clamp. A partial Fisher-Yates shuffle draws the same distribution, and
  // with one agent it is the single draw of one offset of ten.
  static constexpr std::array<std::array<double, 2>, 10> kOffsets{
      {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}, {0, 2}, {0, -2}, {-2, -2}, {-2, 2}, {2, 2}, {2, -2}}};
  const int n = config_.offense_agents;
  std::array<int, kOffsets.size()> pick{};
  for (int i = 0; i < static_cast<int>(pick.size()); ++i) {
    pick[i] = i;
  }
  for (int i = 0; i < n; ++i) {
    const int j = i + static_cast<int>(rng_.below(pick.size() - i));
    std::swap(pick[i], pick[j]);
  }
  std::array<PlayerState, kMaxOffenseAgents> offense{};
  for (int i = 0; i < n; ++i) {
    const auto& off = kOffsets[pick[i]];
    double ax = bx + 10.5 * (rng_.uniform() + off[0]);
    double ay = by + 10.5 * (rng_.uniform() + off[1]);
    switch (config_.start) {
      case StartDistribution::kPaper:
        ax = clamp(ax, -0.1, kPitchHalfLength);
        ay = clamp(ay, -kPitchHalfWidth, kPitchHalfWidth);
        break;
      case StartDistribution::kDec2015:
        ax = clamp(ax, -0.1, 21.0);
        ay = clamp(ay, -27.2, 27.2);
        break;
      case StartDistribution::kHfo:
        ax = clamp(ax, -0.1, kPitchHalfLength);
        ay = clamp(ay, -27.2, 27.2);
        break;
    }
    offense[i].pos = {ax, ay};
  }
  if (start_scale_ < 1.0) {
    // The start curriculum: ball and players drawn as above, moved toward the goal's centre.
    const auto toward_goal = [s = start_scale_](Vec2 p) {
      return Vec2{kPitchHalfLength + s * (p.x - kPitchHalfLength), s * p.y};
    };
    const Vec2 b = toward_goal({bx, by});
    bx = b.x;
    by = b.y;
    for (int i = 0; i < n; ++i) {
      offense[i].pos = toward_goal(offense[i].pos);
    }
  }
  for (int i = 0; i < n; ++i) {
    double body = state_.players[i].body_deg;
    switch (config_.body_at_reset) {
      case BodyAtReset::kCarry: body = first_episode_ ? 0.0 : body; break;
      case BodyAtReset::kZero: body = 0.0; break;
      case BodyAtReset::kUniform: body = wrap_deg(rng_.uniform(-180.0, 180.0)); break;
    }
    offense[i].body_deg = body;
  }
  first_episode_ = false;

  // HFO's reset places the goalie at (52.5, 0) at rest with full stamina but leaves its body
  // as it was (HFORef::resetField calls Player::place, which sets position and velocity only,
  // and recoverAll, which restores stamina, effort and recovery). Its tackle freeze and catch
  // ban run on, and so does its own catch memory. The cycle the server waits after the
  // terminal state (HFORef::analyse) counts for them; the goalie's command in that cycle is
  // not played here.
  const PlayerState old_goalie = state_.players[goalie_index()];
  std::array<PlayerState, kMaxFieldDefenders> old_defenders{};
  for (int k = 0; k < config_.field_defenders; ++k) {
    old_defenders[static_cast<size_t>(k)] = state_.players[defender_index(k)];
  }
  set_state(std::span<const PlayerState>(offense.data(), n), BallState{{bx, by}, {0.0, 0.0}});
  if (!config_.goalie) {
    return;
  }
  // Field defenders (HFORef::resetField): x U[42, 52.5], y U[-27.2, 27.2], placed and recovered
  // as the goalie is; drawn after the offense so that games without them draw as before.
  for (int k = 0; k < config_.field_defenders; ++k) {
    PlayerState& d = state_.players[defender_index(k)];
    const PlayerState& old = old_defenders[static_cast<size_t>(k)];
    d.pos = {rng_.uniform(kDefenderStartMinX, kPitchHalfLength), rng_.uniform(-kDefenderStartMaxY, kDefenderStartMaxY)};
    d.body_deg = old.body_deg;
    d.tackle_cycles = std::max(0, old.tackle_cycles - 1);
  }
  PlayerState& g = state_.players[goalie_index()];
  g.body_deg = old_goalie.body_deg;  // the constructor's set_state gave it 180 to start
  g.tackle_cycles = std::max(0, old_goalie.tackle_cycles - 1);
  g.catch_ban = std::max(0, old_goalie.catch_ban - 1);
  g.since_catch = std::min(PlayerState::kNoCatchYet, old_goalie.since_catch + 1);
  // HFO's client plays NOOPs for the first two cycles of an episode, so its first observation
  // comes two cycles after the reset (docs/hfo-server.md); the goalie (and the field defenders)
  // play in both. Only the defense moves: the ball is at rest and the agents send nothing.
  for (int i = 0; i < kCyclesBeforeFirstObservation; ++i) {
    step();
  }
}

void SoccerSim::set_state(const PlayerState& agent, const BallState& ball) {
  set_state(std::span<const PlayerState>(&agent, 1), ball);
}

void SoccerSim::set_state(std::span<const PlayerState> offense, const BallState& ball) {
  const int n = config_.offense_agents;
  if (static_cast<int>(offense.size()) != n) {
    throw std::invalid_argument("SoccerSim::set_state: " + std::to_string(offense.size()) +
                                " offense players given, the sim has offense_agents = " + std::to_string(n));
  }
  for (int i = 0; i < n; ++i) {
    state_.players[i] = offense[i];
    state_.players[i].body_deg = wrap_deg(offense[i].body_deg);
    state_.players[i].team = Team::kOffense;
    state_.players[i].goalie = false;
  }
  state_.num_players = n;
  state_.ball = ball;
  state_.cycle = 0;
  state_.untouched = 0;
  state_.prev_ball = ball.pos;
  state_.defense_hold = 0;
  state_.trainer_hold = 0;
  state_.ball_caught = false;
  if (config_.goalie) {
    // HFO places the goalie at (52.5, 0) at every reset (reference §5.1).
    PlayerState goalie;
    goalie.pos = kGoalieStart;
    goalie.body_deg = kGoalieStartBodyDeg;
    goalie.team = Team::kDefense;
    goalie.goalie = true;
    state_.players[goalie_index()] = goalie;
    state_.num_players = goalie_index() + 1;
    // Field defenders, until a reset draws their places: on the penalty spots' x, either side.
    for (int k = 0; k < config_.field_defenders; ++k) {
      PlayerState d;
      d.pos = {kDefenderStartMinX + 5.0, k == 0 ? -10.0 : 10.0};
      d.body_deg = kGoalieStartBodyDeg;
      d.team = Team::kDefense;
      state_.players[defender_index(k)] = d;
      state_.num_players = defender_index(k) + 1;
    }
  }
  player_accel_.fill(Vec2{});
  ball_accel_ = {};
  last_goalie_command_ = {};
  last_defender_command_.fill({});
  goalie_sensed_ = false;
}

void SoccerSim::set_defender(int k, const PlayerState& defender) {
  if (k < 0 || k >= config_.field_defenders) {
    throw std::invalid_argument("SoccerSim::set_defender: field defender " + std::to_string(k) + " of " +
                                std::to_string(config_.field_defenders));
  }
  PlayerState& d = state_.players[defender_index(k)];
  d = defender;
  d.team = Team::kDefense;
  d.goalie = false;
  d.body_deg = wrap_deg(defender.body_deg);
  goalie_sensed_ = false;
}

void SoccerSim::set_goalie(const PlayerState& goalie) {
  PlayerState& g = state_.players[goalie_index()];
  const Team team = g.team;
  const bool is_goalie = g.goalie;
  g = goalie;
  g.team = team;
  g.goalie = is_goalie;
  g.body_deg = wrap_deg(goalie.body_deg);
}

bool SoccerSim::kickable(int player) const {
  return (state_.ball.pos - state_.players[player].pos).r() <= kClientKickableArea;
}

void SoccerSim::check_offense_player(int player) const {
  if (player < 0 || player >= config_.offense_agents) {
    std::fprintf(stderr, "SoccerSim: command for player %d, but the offense agents are 0..%d\n", player,
                 config_.offense_agents - 1);
    std::abort();
  }
}

Vec2 SoccerSim::noise_vector(double max_radius) {
  // Uniform radius (not area-uniform) and uniform direction, as the server draws it.
  const double r = rng_.uniform(0.0, max_radius);
  const double th = rng_.uniform(-kPi, kPi);
  return polar(r, th);
}

bool SoccerSim::dash(double power, double dir_deg) {
  return dash_player(0, power, dir_deg);
}

bool SoccerSim::turn(double dir_deg) {
  return turn_player(0, dir_deg);
}

bool SoccerSim::kick(double power, double dir_deg) {
  return kick_player(0, power, dir_deg);
}

bool SoccerSim::tackle(double dir_deg) {
  return tackle_player(0, dir_deg);
}

bool SoccerSim::dash_player(int player, double power, double dir_deg) {
  check_offense_player(player);
  sense_goalie();
  return send_dash(player, power, dir_deg);
}

bool SoccerSim::turn_player(int player, double dir_deg) {
  check_offense_player(player);
  sense_goalie();
  return send_turn(player, dir_deg);
}

bool SoccerSim::kick_player(int player, double power, double dir_deg) {
  check_offense_player(player);
  sense_goalie();
  return send_kick(player, power, dir_deg);
}

bool SoccerSim::tackle_player(int player, double dir_deg) {
  check_offense_player(player);
  sense_goalie();
  return server_tackle(player, dir_deg);
}

bool SoccerSim::send_dash(int i, double power, double dir_deg) {
  PlayerState& p = state_.players[i];
  if (p.tackle_cycles > 0) {
    return false;
  }
  // --- Client (librcsc ActionEffector::setDash). ---
  const ClientDash c = client_dash(p.vel, p.body_deg, p.stamina, p.effort, power, dir_deg);
  return server_dash(i, c.power, c.dir_deg);
}

bool SoccerSim::server_dash(int i, double power, double dir) {
  PlayerState& p = state_.players[i];
  if (p.tackle_cycles > 0) {
    return false;
  }
  // --- Server: clamp, discretize, consume stamina, push. ---
  power = clamp(power, kMinDashPower, kMaxDashPower);
  dir = discretize_dash_dir(clamp(dir, kMinMoment, kMaxMoment));
  const bool back = power < 0.0;
  double spent = back ? -2.0 * power : power;
  spent = std::min(spent, p.stamina + kExtraStamina);
  p.stamina = std::max(0.0, p.stamina - spent);
  power = back ? -spent / 2.0 : spent;
  const double eff = std::fabs(p.effort * power * dash_dir_rate(dir) * kDashPowerRate);
  player_accel_[i] += polar(eff, (p.body_deg + dir + (back ? 180.0 : 0.0)) * kDegToRad);
  return true;
}

bool SoccerSim::send_turn(int i, double dir_deg) {
  PlayerState& p = state_.players[i];
  if (p.tackle_cycles > 0) {
    return false;
  }
  // Client: HFO's Turn is the desired actual turn; librcsc pre-compensates inertia.
  return server_turn(i, client_turn_moment(p.vel, dir_deg));
}

bool SoccerSim::server_turn(int i, double moment) {
  PlayerState& p = state_.players[i];
  if (p.tackle_cycles > 0) {
    return false;
  }
  const double inertia = 1.0 + kInertiaMoment * p.vel.r();
  moment = clamp(moment, kMinMoment, kMaxMoment);
  if (config_.noise) {
    moment *= 1.0 + rng_.uniform(-kPlayerRand, kPlayerRand);
  }
  p.body_deg = wrap_deg(p.body_deg + moment / inertia);
  return true;
}

bool SoccerSim::send_kick(int i, double power, double dir_deg) {
  PlayerState& p = state_.players[i];
  if (p.tackle_cycles > 0) {
    return false;
  }
  const double dist = (state_.ball.pos - p.pos).r();
  // Client gating: no command at all unless the client calls the ball kickable.
  if (dist > kClientKickableArea) {
    return false;
  }
  power = round3(clamp(power, 0.0, kMaxKickPower));
  if (dist > kKickableArea) {
    return true;  // sent, but the server ignores it (cannot happen behind the client gate)
  }
  return kick_player_server(i, power, dir_deg);
}

bool SoccerSim::kick_player_server(int i, double power, double dir_deg) {
  const PlayerState& p = state_.players[i];
  const Vec2 to_ball = state_.ball.pos - p.pos;
  const double dist = to_ball.r();
  power = clamp(power, 0.0, kMaxKickPower);
  const double dir = clamp(wrap_deg(dir_deg), kMinMoment, kMaxMoment);
  const double phi = std::fabs(wrap_rad(std::atan2(to_ball.y, to_ball.x) - p.body_deg * kDegToRad));
  const double gap = dist - kPlayerSize - kBallSize;
  const double eff = power * kKickPowerRate * (1.0 - 0.25 * phi / kPi - 0.25 * gap / kKickableMargin);
  Vec2 accel = polar(eff, (p.body_deg + dir) * kDegToRad);
  if (config_.noise) {
    const double max_r = kKickRand * (power / kMaxKickPower) *
                         ((0.5 + 0.25 * (phi / kPi + gap / kKickableMargin)) +
                          (0.5 + 0.5 * state_.ball.vel.r() / (kBallSpeedMax * kBallDecay)));
    accel += noise_vector(max_r);
  }
  ball_accel_ += accel;
  return true;
}

bool SoccerSim::server_tackle(int i, double dir_deg, std::optional<bool> succeeds, bool foul) {
  PlayerState& p = state_.players[i];
  if (p.tackle_cycles > 0) {
    return false;
  }
  p.tackle_cycles = kTackleCycles;
  // Player::tackle: a foul counts only while an opponent can kick the ball; it is then judged
  // with foul_exponent, and a successful one does not freeze the tackler.
  double exponent = kTackleExponent;
  if (foul) {
    foul = false;
    for (int j = 0; j < state_.num_players; ++j) {
      const PlayerState& o = state_.players[j];
      if (o.team != p.team && (state_.ball.pos - o.pos).r() <= kKickableArea) {
        foul = true;
        exponent = kFoulExponent;
        break;
      }
    }
  }
  // Ball in the body frame.
  const Vec2 d = state_.ball.pos - p.pos;
  const double body = p.body_deg * kDegToRad;
  const double c = std::cos(-body);
  const double s = std::sin(-body);
  const Vec2 q{d.x * c - d.y * s, d.x * s + d.y * c};
  if (q.x <= 0.0) {
    return true;  // the back tackle distance is 0: always fails
  }
  const double fail = std::pow(q.x / kTackleDist, exponent) + std::pow(std::fabs(q.y) / kTackleWidth, exponent);
  if (fail >= 1.0) {
    return true;
  }
  // Success is drawn from the server's generator even with noise off (a replay may give it).
  if (succeeds ? !*succeeds : rng_.uniform() < fail) {
    return true;
  }
  if (foul) {
    p.tackle_cycles = 0;
  }
  const double a_deg = clamp(wrap_deg(dir_deg), kMinMoment, kMaxMoment);
  const double power = kMaxTacklePower + (kMaxBackTacklePower - kMaxTacklePower) * std::fabs(a_deg) / 180.0;
  const double eff = power * kTacklePowerRate * (1.0 - 0.5 * std::fabs(std::atan2(q.y, q.x)) / kPi);
  Vec2 accel = polar(eff, (p.body_deg + a_deg) * kDegToRad);
  if (config_.noise) {
    const double max_r =
        kKickRand * kTackleRandFactor *
        ((0.5 + 0.5 * (1.0 - fail)) + (0.5 + 0.5 * state_.ball.vel.r() / (kBallSpeedMax * kBallDecay)));
    accel += noise_vector(max_r);
  }
  ball_accel_ += accel;
  return true;
}

bool SoccerSim::goalie_catch(int player, double dir_deg) {
  PlayerState& p = state_.players[player];
  if (!p.goalie || p.catch_ban > 0 || p.tackle_cycles > 0) {
    return false;
  }
  // rcssserver refuses nothing for the ball's place: in HFO mode CatchRef::ballCaught returns
  // before its penalty-area check (referee.cpp).
  p.catch_ban = kCatchBanCycles;
  // Ball in the frame of the catch direction: the catchable area is the rectangle
  // [0, l] x [-w/2, w/2] in front of the player's centre.
  const Vec2 b = state_.ball.pos;
  const double a = (p.body_deg + clamp(wrap_deg(dir_deg), kMinMoment, kMaxMoment)) * kDegToRad;
  const Vec2 d = b - p.pos;
  const double along = d.x * std::cos(a) + d.y * std::sin(a);
  const double across = -d.x * std::sin(a) + d.y * std::cos(a);
  if (along < 0.0 || along > kCatchableAreaLength || std::fabs(across) > 0.5 * kCatchableAreaWidth) {
    return false;
  }
  // kCatchProbability is 1: no draw, so the noise stream does not depend on catches.
  static_assert(kCatchProbability == 1.0);
  // Player::goalieCatch on success: the goalie moves toward the ball until they touch, faces
  // it and stops; Stadium::ballCaught then resolves collisions at once. The ball keeps its
  // velocity (HFO mode: no free kick).
  // The same operations in the same order as the server, so that the touching distance
  // rounds the same way: whether collisions() finds the ball touching decides between a ball
  // that bounces off (and is captured) and one that flies on.
  const double r = d.r();
  if (r > 0.0) {
    const double mag = r - (kBallSize + kPlayerSize);
    const Vec2 step = d * (mag / r);
    p.pos += step;
    p.body_deg = wrap_deg(std::atan2(step.y, step.x) * kRadToDeg);
  }
  p.vel = {};
  player_accel_[player] = {};
  collide_objects();
  state_.ball_caught = true;
  p.caught = true;
  return true;
}

bool SoccerSim::command_as_received(int player, const char* kind, double p1, double p2,
                                    std::optional<bool> tackle_succeeds) {
  sense_goalie();
  const std::string_view k(kind);
  if (k == "DASH") {
    return server_dash(player, p1, p2);
  }
  if (k == "TURN") {
    return server_turn(player, p1);
  }
  if (k == "KICK") {
    PlayerState& p = state_.players[player];
    if (p.tackle_cycles > 0 || (state_.ball.pos - p.pos).r() > kKickableArea) {
      return false;
    }
    return kick_player_server(player, p1, p2);
  }
  if (k == "TACKLE") {
    return server_tackle(player, p1, tackle_succeeds);
  }
  if (k == "CATCH") {
    return goalie_catch(player, p1);
  }
  return k == "NONE";
}

void SoccerSim::sense_goalie() {
  if (!config_.goalie || goalie_sensed_) {
    return;
  }
  const GoalieCommand c = decide_goalie(state_, goalie_index(), config_.noise);
  pending_goalie_command_ = {static_cast<uint8_t>(c.kind), c.p1, c.p2};
  // The field defenders sense the same state in the same moment.
  for (int k = 0; k < config_.field_defenders; ++k) {
    const DefenderDecision d = decide_defender(state_, defender_index(k), k + 2, config_.noise);
    state_.players[defender_index(k)].intention = d.intention;  // its own memory, read only by itself
    state_.players[defender_index(k)].recover_mode = d.recover_mode;
    pending_defender_command_[static_cast<size_t>(k)] = {static_cast<uint8_t>(d.command.kind), d.command.p1,
                                                         d.command.p2, d.foul};
  }
  goalie_sensed_ = true;
}

void SoccerSim::play_npc_command(int i, const GoalieCommandLog& c) {
  switch (static_cast<GoalieCommand::Kind>(c.kind)) {
    case GoalieCommand::Kind::kDash: server_dash(i, c.p1, c.p2); break;
    case GoalieCommand::Kind::kTurn: server_turn(i, c.p1); break;
    case GoalieCommand::Kind::kKick: send_kick(i, c.p1, c.p2); break;
    case GoalieCommand::Kind::kTackle: server_tackle(i, c.p1, std::nullopt, c.foul); break;
    case GoalieCommand::Kind::kCatch:
    case GoalieCommand::Kind::kNone: break;
  }
}

void SoccerSim::play_defenders() {
  for (int k = 0; k < config_.field_defenders; ++k) {
    const GoalieCommandLog& c = pending_defender_command_[static_cast<size_t>(k)];
    last_defender_command_[static_cast<size_t>(k)] = c;
    play_npc_command(defender_index(k), c);
  }
}

void SoccerSim::play_goalie() {
  sense_goalie();
  goalie_sensed_ = false;
  const int gi = goalie_index();
  PlayerState& g = state_.players[gi];
  last_goalie_command_ = pending_goalie_command_;
  const GoalieCommand c{static_cast<GoalieCommand::Kind>(pending_goalie_command_.kind), pending_goalie_command_.p1,
                        pending_goalie_command_.p2};
  switch (c.kind) {
    case GoalieCommand::Kind::kDash: server_dash(gi, c.p1, c.p2); break;
    case GoalieCommand::Kind::kTurn: server_turn(gi, c.p1); break;
    case GoalieCommand::Kind::kCatch:
      g.since_catch = 0;
      goalie_catch(gi, c.p1);
      break;
    case GoalieCommand::Kind::kKick: send_kick(gi, c.p1, c.p2); break;
    case GoalieCommand::Kind::kTackle: server_tackle(gi, c.p1); break;
    case GoalieCommand::Kind::kNone: break;
  }
}

void SoccerSim::move_object(Vec2& pos, Vec2& vel, Vec2& accel, double size, double decay, double accel_max,
                            double speed_max, double rand, bool* hit_post) {
  if (!accel.is_zero()) {
    const double a = accel.r();
    if (a > accel_max) {
      accel *= accel_max / a;
    }
    vel += accel;
    const double v = vel.r();
    if (v > speed_max) {
      vel *= speed_max / v;
    }
  }
  if (config_.noise && rand > 0.0) {
    vel += noise_vector(rand * vel.r());
  }

  // Goal posts: circles of radius 0.06; elastic bounce, reference §2.3 step 5.
  const double reach = size + kGoalPostRadius;
  {
    const Vec2 c = nearest_post(pos);
    const Vec2 d = pos - c;
    const double dist = d.r();
    if (dist < reach) {
      const Vec2 n = dist > 0.0 ? d * (1.0 / dist) : Vec2{pos.x >= 0.0 ? 1.0 : -1.0, 0.0};
      pos = c + n * (reach + kPostSeparation);
      if (vel.dot(n) < 0.0) {
        vel = reflect(vel, n);
      }
      if (hit_post != nullptr) {
        *hit_post = true;
      }
    }
  }
  Vec2 move = vel;
  for (int bounce = 0; bounce < 8; ++bounce) {
    const Vec2 c1 = nearest_post(pos);
    const Vec2 c2 = nearest_post(pos + move);
    double t = post_contact_time(pos, move, c1, reach);
    Vec2 c = c1;
    if (!(c2 == c1)) {
      const double t2 = post_contact_time(pos, move, c2, reach);
      if (t2 >= 0.0 && (t < 0.0 || t2 < t)) {
        t = t2;
        c = c2;
      }
    }
    if (t < 0.0) {
      break;
    }
    const Vec2 contact = pos + move * t;
    Vec2 n = contact - c;
    n *= 1.0 / n.r();
    move = reflect(move * (1.0 - t), n);
    vel = reflect(vel, n);
    pos = contact + n * kPostSeparation;
    if (hit_post != nullptr) {
      *hit_post = true;
    }
  }
  pos += move;
  vel *= decay;
  accel = {};
}

void SoccerSim::collide_objects() {
  // Objects: index 0 is the ball, 1..n the players (reference §2.9).
  constexpr int kMaxObjects = SoccerState::kMaxPlayers + 1;
  const int n = state_.num_players + 1;
  std::array<Vec2*, kMaxObjects> pos{};
  std::array<double, kMaxObjects> size{};
  std::array<bool, kMaxObjects> collided{};
  pos[0] = &state_.ball.pos;
  size[0] = kBallSize;
  for (int i = 1; i < n; ++i) {
    pos[i] = &state_.players[i - 1].pos;
    size[i] = kPlayerSize;
  }
  for (int pass = 0; pass < 10; ++pass) {
    std::array<Vec2, kMaxObjects> sum{};
    std::array<int, kMaxObjects> count{};
    bool any = false;
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) {
        const double reach = size[a] + size[b];
        Vec2 d = *pos[b] - *pos[a];
        // Stadium::collisions compares squared distances.
        if (d.r2() >= reach * reach) {
          continue;
        }
        double dist = d.r();
        any = true;
        collided[a] = collided[b] = true;
        if (a == 0) {
          state_.players[b - 1].collided_ball = true;
        } else {
          state_.players[a - 1].collided_player = true;
          state_.players[b - 1].collided_player = true;
        }
        const Vec2 mid = (*pos[a] + *pos[b]) * 0.5;
        if (dist <= 0.0) {
          d = polar(1.0, rng_.uniform(-kPi, kPi));
          dist = 1.0;
        }
        const Vec2 unit = d * (1.0 / dist);
        double half = reach * 0.5 + kCollisionSeparation;
        Vec2 pa = mid - unit * half;
        Vec2 pb = mid + unit * half;
        for (int nudge = 0; nudge < 10 && (pb - pa).r() < reach; ++nudge) {
          half *= 1.0001;
          pa = mid - unit * half;
          pb = mid + unit * half;
        }
        sum[a] += pa;
        sum[b] += pb;
        ++count[a];
        ++count[b];
      }
    }
    if (!any) {
      break;
    }
    for (int i = 0; i < n; ++i) {
      if (count[i] > 0) {
        *pos[i] = sum[i] * (1.0 / count[i]);
      }
    }
  }
  if (collided[0]) {
    state_.ball.vel *= -0.1;
  }
  for (int i = 1; i < n; ++i) {
    if (collided[i]) {
      state_.players[i - 1].vel *= -0.1;
    }
  }
}

void SoccerSim::update_stamina(PlayerState& p) {
  if (p.stamina <= kRecoverDecThreshold && p.recovery > kRecoverMin) {
    p.recovery = std::max(kRecoverMin, p.recovery - kRecoverDec);
  }
  if (p.stamina <= kEffortDecThreshold && p.effort > kEffortMin) {
    p.effort = std::max(kEffortMin, p.effort - kEffortDec);
  }
  if (p.stamina >= kEffortIncThreshold && p.effort < kEffortMax) {
    p.effort = std::min(kEffortMax, p.effort + kEffortInc);
  }
  const double inc = std::min({p.recovery * kStaminaIncMax, kStaminaMax - p.stamina, p.capacity});
  p.stamina = std::min(kStaminaMax, p.stamina + std::max(0.0, inc));
  p.capacity = std::max(0.0, p.capacity - std::max(0.0, inc));
}

int SoccerSim::step() {
  if (config_.goalie) {
    // The goalie and the field defenders see the same state as the agent did and act in the
    // same cycle.
    play_goalie();
    play_defenders();
  }
  const int np = state_.num_players;
  for (int i = 0; i < np; ++i) {
    PlayerState& p = state_.players[i];
    if (p.tackle_cycles > 0) {
      --p.tackle_cycles;
    }
    if (p.catch_ban > 0) {
      --p.catch_ban;
    }
    if (p.goalie && p.since_catch < PlayerState::kNoCatchYet) {
      ++p.since_catch;
    }
    // Collision flags describe this cycle only.
    p.collided_ball = p.collided_player = p.collided_post = false;
  }
  for (int i = 0; i < np; ++i) {
    PlayerState& p = state_.players[i];
    move_object(p.pos, p.vel, player_accel_[i], kPlayerSize, kPlayerDecay, kPlayerAccelMax, kPlayerSpeedMax,
                kPlayerRand, &p.collided_post);
  }
  move_object(state_.ball.pos, state_.ball.vel, ball_accel_, kBallSize, kBallDecay, kBallAccelMax, kBallSpeedMax,
              kBallRand, nullptr);
  collide_objects();
  ++state_.cycle;
  const int status = config_.referee == Referee::kServer ? referee_server() : referee_trainer();
  for (int i = 0; i < np; ++i) {
    update_stamina(state_.players[i]);
  }
  return status;
}

int SoccerSim::referee_server() {
  const Vec2 ball = state_.ball.pos;
  const Vec2 prev = state_.prev_ball;
  state_.prev_ball = ball;

  if (std::fabs(prev.x) <= kGoalLineX && ball.x > kGoalLineX) {
    const double t = (kGoalLineX - prev.x) / (ball.x - prev.x);
    const double y = prev.y + t * (ball.y - prev.y);
    if (std::fabs(y) <= kGoalMouthY) {
      return kGoal;
    }
  }
  if (prev.x < 0.0 || prev.x > kPitchHalfLength || std::fabs(prev.y) > kPitchHalfWidth) {
    return kOutOfBounds;
  }
  // HFORef::analyse: the defense has held the ball for TURNOVER_TIME (2) checks.
  if (state_.defense_hold >= 2) {
    return kCapturedByDefense;
  }
  if (state_.untouched > config_.untouched_limit || state_.cycle > config_.max_steps) {
    return kOutOfTime;
  }
  ++state_.untouched;
  // In the server's order (offense, then the goalie, then the field defenders): the first
  // defender within the kickable area holds the ball and counts a check; otherwise an attacker
  // within it resets the count; with nobody near, the count stays.
  bool offense_near = false;
  bool goalie_holds = false;
  for (int i = 0; i < state_.num_players; ++i) {
    const PlayerState& p = state_.players[i];
    if ((ball - p.pos).r() > kKickableArea) {
      continue;
    }
    state_.untouched = 0;
    if (p.team == Team::kOffense) {
      offense_near = true;
      continue;
    }
    offense_near = false;
    ++state_.defense_hold;
    goalie_holds = p.goalie;
    break;
  }
  if (offense_near) {
    state_.defense_hold = 0;
  }
  // The goalie with the ball ends it at once; a catch alone does not: in HFO mode the ball flies
  // on, and only a ball that ends within reach is captured.
  if (goalie_holds) {
    return kCapturedByDefense;
  }
  return kInGame;
}

int SoccerSim::referee_trainer() {
  const Vec2 ball = state_.ball.pos;
  state_.prev_ball = ball;
  // Who holds the ball: the only player within 1.6275 for two consecutive cycles.
  int holders = 0;
  bool defense_holder = false;
  for (int i = 0; i < state_.num_players; ++i) {
    if ((ball - state_.players[i].pos).r() <= kTrainerHoldDist) {
      ++holders;
      defense_holder = state_.players[i].team == Team::kDefense;
    }
  }
  state_.trainer_hold = holders == 1 ? state_.trainer_hold + 1 : 0;
  const bool held = state_.trainer_hold >= 2;
  state_.untouched = held ? 0 : state_.untouched + 1;
  if (state_.cycle <= 5) {
    return kInGame;
  }
  if (ball.x > kPitchHalfLength && std::fabs(ball.y) <= kGoalHalfWidth) {
    return kGoal;
  }
  if (ball.x < -0.1 || ball.x > kPitchHalfLength || std::fabs(ball.y) > kPitchHalfWidth) {
    return kOutOfBounds;
  }
  if ((held && defense_holder) || state_.ball_caught) {
    return kCapturedByDefense;
  }
  if (state_.untouched > config_.untouched_limit || state_.cycle > config_.max_steps) {
    return kOutOfTime;
  }
  return kInGame;
}

}  // namespace pamdp::hfo
