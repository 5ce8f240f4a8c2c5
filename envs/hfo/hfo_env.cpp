#include "envs/hfo/hfo_env.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pamdp::hfo {
namespace {

// Programmer misuse (not a user error): stop with a message, also in Release builds.
[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "HfoEnv: %s\n", what);
  std::abort();
}

}  // namespace

const ActionSpace& hfo_action_space(bool shoot) {
  static const ActionSpace kSpace{
      .actions = {{"DASH", {param::kDashPower, param::kDashDir}},
                  {"TURN", {param::kTurnDir}},
                  {"TACKLE", {param::kTackleDir}},
                  {"KICK", {param::kKickPower, param::kKickDir}}},
      .params = {{"dash_power", 0.0F, 100.0F},
                 {"dash_dir", -180.0F, 180.0F},
                 {"turn_dir", -180.0F, 180.0F},
                 {"tackle_dir", -180.0F, 180.0F},
                 {"kick_power", 0.0F, 100.0F},
                 {"kick_dir", -180.0F, 180.0F}},
  };
  static const ActionSpace kWithShoot = [] {
    ActionSpace s = kSpace;
    s.actions.push_back({"SHOOT", {param::kShootPower, param::kShootDir}});
    s.params.push_back({"shoot_power", 0.0F, 100.0F});
    s.params.push_back({"shoot_dir", -180.0F, 180.0F});
    return s;
  }();
  return shoot ? kWithShoot : kSpace;
}

ShapedReward::Snapshot ShapedReward::snapshot(std::span<const float> f) {
  // Distances in proximity units: D = 1 - P in [0, 2]. The ball-goal distance follows from
  // the two egocentric bearings by the law of cosines, exactly as dqn-hfo did; the bearing
  // of an object is sgn(sin) * acos(cos), so cos(tb - tg) expands without calling acos.
  const double pb = f[feat::kBallProximity];
  const double pg = f[feat::kGoalCentre + 2];
  const double db = 1.0 - pb;
  const double dg = 1.0 - pg;
  const double cb = f[feat::kBallAngleCos];
  const double cg = f[feat::kGoalCentre + 1];
  const double sb = std::copysign(std::sqrt(std::max(0.0, 1.0 - cb * cb)), f[feat::kBallAngleSin] < 0 ? -1.0 : 1.0);
  const double sg = std::copysign(std::sqrt(std::max(0.0, 1.0 - cg * cg)), f[feat::kGoalCentre] < 0 ? -1.0 : 1.0);
  const double cos_diff = cb * cg + sb * sg;
  const double dbg2 = db * db + dg * dg - 2.0 * db * dg * cos_diff;
  return {pb, f[feat::kKickable], std::sqrt(std::max(0.0, dbg2))};
}

float ShapedReward::operator()(std::span<const float> features, int status) {
  const Snapshot now = snapshot(features);
  double d_prox = 0.0;
  double d_kick = 0.0;
  double d_dist = 0.0;
  if (steps_ > 0) {
    d_prox = now.ball_prox - prev_.ball_prox;
    d_kick = now.kickable - prev_.kickable;
    d_dist = now.ball_goal_dist - prev_.ball_goal_dist;
  }
  prev_ = now;
  if (status != kInGame) {
    d_prox = d_kick = d_dist = 0.0;
  }
  double r = d_prox - 3.0 * d_dist + (status == kGoal ? 5.0 : 0.0);
  if (status == kOutOfBounds) {
    r -= out_of_bounds_penalty_;
  }
  if (d_kick >= 1.0 && !got_kick_) {
    r += 1.0;
    got_kick_ = true;
  }
  ++steps_;
  return static_cast<float>(r);
}

HfoEnv::HfoEnv(const SoccerSimConfig& config, bool shoot_action, int out_of_bounds_penalty)
    : sim_(config), reward_(out_of_bounds_penalty), shoot_(shoot_action) {}

std::span<const int> HfoEnv::outcomes() const {
  return kStatuses;
}

void HfoEnv::begin_episode(std::span<float> obs) {
  reward_.reset();
  episode_over_ = false;
  write_features(sim_.state(), obs);
}

void HfoEnv::reset(uint64_t seed, std::span<float> obs) {
  sim_.reseed(seed);
  reset(obs);
}

void HfoEnv::reset(std::span<float> obs) {
  sim_.reset_episode();
  begin_episode(obs);
}

void HfoEnv::set_state(const PlayerState& agent, const BallState& ball, std::span<float> obs) {
  sim_.set_state(agent, ball);
  begin_episode(obs);
}

void HfoEnv::set_state(const PlayerState& agent, const BallState& ball, const PlayerState& goalie,
                       std::span<float> obs) {
  if (!sim_.config().goalie) {
    misuse("set_state() with a goalie on an env without one");
  }
  sim_.set_state(agent, ball);
  sim_.set_goalie(goalie);
  begin_episode(obs);
}

void play_action(SoccerSim& sim, int player, const ParamAction& action, bool shoot) {
  if (action.params.size() < static_cast<size_t>(hfo_action_space(shoot).num_params())) {
    misuse("play_action(): the parameter vector must hold the 6 HFO parameters (8 with env.shoot_action)");
  }
  const auto p = [&](int i) { return static_cast<double>(action.params[static_cast<size_t>(i)]); };
  switch (action.id) {
    case kDash: sim.dash_player(player, p(param::kDashPower), p(param::kDashDir)); break;
    case kTurn: sim.turn_player(player, p(param::kTurnDir)); break;
    case kTackle: sim.tackle_player(player, p(param::kTackleDir)); break;
    case kKick: sim.kick_player(player, p(param::kKickPower), p(param::kKickDir)); break;
    case kShoot:
      if (!shoot) {
        misuse("play_action(): SHOOT (4) needs env.shoot_action");
      }
      sim.kick_player(player, p(param::kShootPower), p(param::kShootDir));
      break;
    default: misuse("play_action(): action id out of range (0 DASH, 1 TURN, 2 TACKLE, 3 KICK, 4 SHOOT)");
  }
}

StepResult HfoEnv::step(const ParamAction& action, std::span<float> obs) {
  if (episode_over_) {
    misuse("step() after a terminal status; call reset() first");
  }
  play_action(sim_, 0, action, shoot_);
  const int status = sim_.step();
  episode_over_ = status != kInGame;
  write_features(sim_.state(), obs);
  return {reward_(obs, status), status};
}

}  // namespace pamdp::hfo
