#include "envs/toy/reach_stop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace pamdp::toy {
namespace {

// Misuse of the env (stepping a finished episode, an unknown action) is a bug in the caller,
// not an expected failure: stop with a message rather than return something plausible.
[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "ReachStopEnv: %s\n", what);
  std::abort();
}

}  // namespace

ReachStopEnv::ReachStopEnv(const ReachStopConfig& config, uint64_t seed) : config_(config), rng_(seed) {
  if (config_.max_steps < 1) {
    throw std::invalid_argument("ReachStopConfig.max_steps must be >= 1, got " + std::to_string(config_.max_steps));
  }
  if (!(config_.max_step > 0.0F) || !std::isfinite(config_.max_step)) {
    throw std::invalid_argument("ReachStopConfig.max_step must be finite and > 0");
  }
  if (!(config_.tolerance >= 0.0F) || !std::isfinite(config_.tolerance)) {
    throw std::invalid_argument("ReachStopConfig.tolerance must be finite and >= 0");
  }
  if (!std::isfinite(config_.success_bonus)) {
    throw std::invalid_argument("ReachStopConfig.success_bonus must be finite");
  }
}

const ActionSpace& ReachStopEnv::action_space() const {
  static const ActionSpace kSpace{
      .actions = {{"MOVE", {kVelocityParam}}, {"STOP", {}}},
      .params = {{"velocity", -1.0F, 1.0F}},
  };
  return kSpace;
}

std::string_view ReachStopEnv::status_name(int status) const {
  switch (status) {
    case kInProgress: return "IN_PROGRESS";
    case kSuccess: return "SUCCESS";
    case kWrongStop: return "WRONG_STOP";
    case kOutOfTime: return "OUT_OF_TIME";
    default: return "UNKNOWN";
  }
}

std::span<const int> ReachStopEnv::outcomes() const {
  static constexpr std::array<int, 4> kOutcomes{kInProgress, kSuccess, kWrongStop, kOutOfTime};
  return kOutcomes;
}

void ReachStopEnv::reset(uint64_t seed, std::span<float> obs) {
  rng_.reseed(seed);
  reset(obs);
}

void ReachStopEnv::reset(std::span<float> obs) {
  const auto pos = static_cast<float>(rng_.uniform(-1.0, 1.0));
  const auto target = static_cast<float>(rng_.uniform(-1.0, 1.0));
  set_state(pos, target, obs);
}

void ReachStopEnv::set_state(float pos, float target, std::span<float> obs) {
  if (!(std::fabs(pos) <= 1.0F) || !(std::fabs(target) <= 1.0F)) {
    misuse("set_state: pos and target must lie in [-1, 1]");
  }
  pos_ = pos;
  target_ = target;
  steps_ = 0;
  write_obs(obs);
}

StepResult ReachStopEnv::step(const ParamAction& action, std::span<float> obs) {
  if (steps_ < 0) {
    misuse("step() after a terminal status; call reset() first");
  }
  StepResult r;
  const float dist_before = std::fabs(target_ - pos_);
  switch (action.id) {
    case kMove: {
      if (action.params.size() <= static_cast<size_t>(kVelocityParam)) {
        misuse("MOVE needs the velocity parameter");
      }
      // NaN velocity clamps to NaN; treat it as "stand still" so the state stays finite.
      float v = action.params[kVelocityParam];
      v = std::isnan(v) ? 0.0F : std::clamp(v, -1.0F, 1.0F);
      pos_ = std::clamp(pos_ + config_.max_step * v, -1.0F, 1.0F);
      r.reward = dist_before - std::fabs(target_ - pos_);
      break;
    }
    case kStop:
      if (dist_before <= config_.tolerance) {
        r.status = kSuccess;
        r.reward = config_.success_bonus;
      } else {
        r.status = kWrongStop;
      }
      break;
    default: misuse("action id out of range (0 MOVE, 1 STOP)");
  }
  ++steps_;
  if (r.status == kInProgress && steps_ >= config_.max_steps) {
    r.status = kOutOfTime;
  }
  write_obs(obs);
  if (r.status != kInProgress) {
    steps_ = -1;
  }
  return r;
}

void ReachStopEnv::write_obs(std::span<float> obs) const {
  if (obs.size() != static_cast<size_t>(kObservationSize)) {
    misuse("observation span must hold exactly observation_size() floats");
  }
  obs[0] = pos_;
  obs[1] = target_;
  obs[2] = target_ - pos_;
}

}  // namespace pamdp::toy
