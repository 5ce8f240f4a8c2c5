// ReachStop: a one-dimensional "reach the target, then stop" PAMDP, small enough that a
// learner must solve it within minutes. It exists to prove that the learning code works
// before it is pointed at soccer, and to give the env harness a second, non-HFO env.
//
// Task: the agent sits at `pos` in [-1, 1], a target sits at `target` in [-1, 1]; both are
// drawn uniformly at every reset. Two discrete actions share one parameter vector:
//   MOVE(velocity in [-1, 1]): pos += max_step * velocity, clamped to [-1, 1];
//   STOP: ends the episode, with SUCCESS if |target - pos| <= tolerance, else WRONG_STOP.
// An episode that has not stopped after max_steps decisions ends with OUT_OF_TIME.
//
// Reward: the distance to the target removed by the step (positive when the agent moves
// closer), plus success_bonus on SUCCESS. So the return of any episode is
// (initial distance - final distance) + success_bonus * [success]: a learner has a dense signal
// for the parameter and a sparse one for the discrete choice.
//
// Observation: [pos, target, target - pos]; the first two lie in [-1, 1], the last in
// [-2, 2] (kObservationBound bounds them all).
//
// Cost: reset() and step() are a few arithmetic operations and allocate nothing.
// Not thread-safe: one env per thread.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "core/rng.hpp"
#include "envs/env.hpp"

namespace pamdp::toy {

struct ReachStopConfig {
  int max_steps = 20;          // decisions before OUT_OF_TIME
  float max_step = 0.25F;      // distance one MOVE with |velocity| = 1 covers
  float tolerance = 0.1F;      // |target - pos| at which STOP counts as SUCCESS
  float success_bonus = 1.0F;  // reward added on SUCCESS
};

class ReachStopEnv final : public Env {
 public:
  enum ActionId : int { kMove = 0, kStop = 1 };
  static constexpr int kVelocityParam = 0;  // index into the shared parameter vector
  enum Status : int { kInProgress = 0, kSuccess = 1, kWrongStop = 2, kOutOfTime = 3 };
  static constexpr int kObservationSize = 3;
  static constexpr float kObservationBound = 2.0F;  // every |observation value| <= this

  // Throws std::invalid_argument naming the field if `config` is out of range
  // (max_steps >= 1, max_step > 0, tolerance >= 0, finite bonus).
  explicit ReachStopEnv(const ReachStopConfig& config = {}, uint64_t seed = 0);

  [[nodiscard]] std::string_view name() const override { return "reach_stop"; }
  [[nodiscard]] const ActionSpace& action_space() const override;
  [[nodiscard]] int observation_size() const override { return kObservationSize; }
  [[nodiscard]] int max_episode_steps() const override { return config_.max_steps; }
  [[nodiscard]] std::string_view status_name(int status) const override;
  [[nodiscard]] std::span<const int> outcomes() const override;
  [[nodiscard]] int success_status() const override { return kSuccess; }

  void reset(uint64_t seed, std::span<float> obs) override;
  void reset(std::span<float> obs) override;
  // MOVE reads params[kVelocityParam] (clamped to [-1, 1]); STOP reads nothing.
  StepResult step(const ParamAction& action, std::span<float> obs) override;

  // Starts an episode from an explicit position and target, both in [-1, 1] (tests).
  void set_state(float pos, float target, std::span<float> obs);
  [[nodiscard]] float pos() const { return pos_; }
  [[nodiscard]] float target() const { return target_; }
  [[nodiscard]] const ReachStopConfig& config() const { return config_; }

 private:
  void write_obs(std::span<float> obs) const;

  ReachStopConfig config_;
  Rng rng_;
  float pos_ = 0.0F;
  float target_ = 0.0F;
  int steps_ = 0;
};

}  // namespace pamdp::toy
