#include "envs/hfo/hfo_team_env.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>

namespace pamdp::hfo {
namespace {

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "HfoTeamEnv: %s\n", what);
  std::abort();
}

float mean_of(std::span<const float> v) {
  float sum = 0.0F;
  for (float x : v) {
    sum += x;
  }
  return sum / static_cast<float>(v.size());
}

}  // namespace

HfoTeamEnv::HfoTeamEnv(const SoccerSimConfig& config, bool shoot_action, int out_of_bounds_penalty, bool team_reward)
    : sim_(config), shoot_(shoot_action), team_reward_(team_reward) {
  rewards_.fill(ShapedReward(out_of_bounds_penalty));
}

std::span<const int> HfoTeamEnv::outcomes() const {
  return kStatuses;
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
                           std::span<float> obs, std::span<const PlayerState> defenders) {
  if (goalie != nullptr && !sim_.config().goalie) {
    misuse("set_state() with a goalie on an env without one");
  }
  if (static_cast<int>(defenders.size()) > sim_.config().field_defenders) {
    misuse("set_state() with more field defenders than the env has");
  }
  sim_.set_state(offense, ball);
  if (goalie != nullptr) {
    sim_.set_goalie(*goalie);
  }
  for (size_t k = 0; k < defenders.size(); ++k) {
    sim_.set_defender(static_cast<int>(k), defenders[k]);
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
  if (team_reward_) {
    const float mean = mean_of(rewards);
    std::fill(rewards.begin(), rewards.end(), mean);
  }
  return status;
}

StepResult HfoTeamEnv::step_team(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards) {
  const int status = step(actions, obs, rewards);
  return {mean_of(rewards), status};
}

StepResult HfoTeamEnv::step(const ParamAction& action, std::span<float> obs) {
  if (agents() != 1) {
    misuse("step() with one action on a team of several; use step_team()");
  }
  float reward = 0.0F;
  return step_team({&action, 1}, obs, {&reward, 1});
}

}  // namespace pamdp::hfo
