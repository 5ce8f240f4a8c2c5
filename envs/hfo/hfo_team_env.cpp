#include "envs/hfo/hfo_team_env.hpp"

#include <cstdio>
#include <cstdlib>

namespace pamdp::hfo {
namespace {

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "HfoTeamEnv: %s\n", what);
  std::abort();
}

}  // namespace

void play_action(SoccerSim& sim, int player, const ParamAction& action, bool shoot) {
  if (action.params.size() < static_cast<size_t>(hfo_action_space(shoot).num_params())) {
    misuse("the parameter vector must hold the 6 HFO parameters (8 with env.shoot_action)");
  }
  const auto p = [&](int i) { return static_cast<double>(action.params[static_cast<size_t>(i)]); };
  switch (action.id) {
    case kDash: sim.dash_player(player, p(param::kDashPower), p(param::kDashDir)); break;
    case kTurn: sim.turn_player(player, p(param::kTurnDir)); break;
    case kTackle: sim.tackle_player(player, p(param::kTackleDir)); break;
    case kKick: sim.kick_player(player, p(param::kKickPower), p(param::kKickDir)); break;
    case kShoot:
      if (!shoot) {
        misuse("SHOOT (4) needs env.shoot_action");
      }
      sim.kick_player(player, p(param::kShootPower), p(param::kShootDir));
      break;
    default: misuse("action id out of range (0 DASH, 1 TURN, 2 TACKLE, 3 KICK, 4 SHOOT)");
  }
}

HfoTeamEnv::HfoTeamEnv(const SoccerSimConfig& config, bool shoot_action, int out_of_bounds_penalty)
    : sim_(config), shoot_(shoot_action) {
  rewards_.fill(ShapedReward(out_of_bounds_penalty));
}

void HfoTeamEnv::write_all(std::span<float> obs) const {
  const auto n = static_cast<size_t>(observation_size());
  if (obs.size() != n * static_cast<size_t>(agents())) {
    misuse("obs must hold agents() * observation_size() floats");
  }
  for (int i = 0; i < agents(); ++i) {
    write_features(sim_.state(), i, obs.subspan(static_cast<size_t>(i) * n, n));
  }
}

void HfoTeamEnv::begin_episode(std::span<float> obs) {
  for (auto& r : rewards_) {
    r.reset();
  }
  episode_over_ = false;
  write_all(obs);
}

void HfoTeamEnv::reset(uint64_t seed, std::span<float> obs) {
  sim_.reseed(seed);
  reset(obs);
}

void HfoTeamEnv::reset(std::span<float> obs) {
  sim_.reset_episode();
  begin_episode(obs);
}

void HfoTeamEnv::set_state(std::span<const PlayerState> offense, const BallState& ball, const PlayerState* goalie,
                           std::span<float> obs) {
  if (goalie != nullptr && !sim_.config().goalie) {
    misuse("set_state() with a goalie on an env without one");
  }
  sim_.set_state(offense, ball);
  if (goalie != nullptr) {
    sim_.set_goalie(*goalie);
  }
  begin_episode(obs);
}

int HfoTeamEnv::step(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards) {
  if (static_cast<int>(actions.size()) != agents() || static_cast<int>(rewards.size()) != agents()) {
    misuse("step() takes one action and one reward slot per offense agent");
  }
  if (episode_over_) {
    misuse("step() after a terminal status; call reset() first");
  }
  for (int i = 0; i < agents(); ++i) {
    play_action(sim_, i, actions[static_cast<size_t>(i)], shoot_);
  }
  const int status = sim_.step();
  episode_over_ = status != kInGame;
  write_all(obs);
  const auto n = static_cast<size_t>(observation_size());
  for (int i = 0; i < agents(); ++i) {
    rewards[static_cast<size_t>(i)] =
        rewards_[static_cast<size_t>(i)](obs.subspan(static_cast<size_t>(i) * n, n), status);
  }
  return status;
}

}  // namespace pamdp::hfo
