// Robot Soccer Goal: the PAMDP benchmark of Masson, Ranchod & Konidaris (AAAI 2016,
// "Reinforcement Learning with Parameterized Actions"), with the rules, constants and reward of
// C. Bester's gym port (github.com/cycraig/gym-goal, gym_goal/envs/goal_env.py, config.py,
// util.py) and the observation of MP-DQN's Goal runs (github.com/cycraig/MP-DQN,
// common/goal_domain.py GoalObservationWrapper, common/wrappers.py ScaledStateWrapper).
//
// Task: a striker kicks a ball past a keeper into a goal on a half pitch, x in [0, 20],
// y in [-15, 15]; the goal mouth is x = 20, |y| <= 7.01, 2.44 deep.
//
// Actions, one shared parameter vector of 4 (gym-goal ACTION_LOOKUP, PARAMETERS_MIN/MAX):
//   0 KICK_TO(x in [0, 40] = param 0, y in [-15, 15] = param 1)
//   1 SHOOT_GOAL_LEFT(y in [-7.01, 7.01] = param 2)
//   2 SHOOT_GOAL_RIGHT(y in [-7.01, 7.01] = param 3)
// Parameters are clamped to these ranges (NaN reads as the range's midpoint). KICK_TO kicks
// towards the point (x, x): gym-goal hands kick_to the clipped x alone and numpy broadcasts it
// (GoalEnv._perform_action, as in Masson's aaai-goal simulator.py), so y has no effect; kept for
// comparison with the published results. Both shoot actions are the same kick at (20.4, y);
// gym-goal keeps two so that a learner can hold one near each post.
// One decision step runs internal simulation steps until the episode ends (shoots) or until the
// striker can kick a ball slower than 0.1 (KICK_TO); last_sim_steps() says how many.
//
// Episode: the striker starts at (0, U(-15, 15)) facing (20, 0), the ball just in its kick range
// ahead, the keeper on its guarding line. It ends with GOAL (+50), CAUGHT (the keeper within 2 of
// the ball), OUT_OF_BOUNDS (the ball off the half pitch and not in the goal) or OUT_OF_TIME: the
// 100th decision step simulates nothing and ends the episode (gym-goal GoalEnv.max_time = 100).
// Every outcome but GOAL pays -(ball's distance to the goal mouth). Status 0 is IN_PROGRESS.
//
// Observation (17 floats): gym-goal get_state()'s 14 values plus MP-DQN's 3, each mapped
// linearly from MP-DQN's [low, high] to [-1, 1]:
//   0-1 striker position   x [0, 20], y [-15, 15]      2-3 striker velocity [-1, 1]
//   4 striker orientation, wrapped to [-pi, pi]       5-6 keeper position, 7-8 keeper velocity,
//   9 keeper orientation [-pi, pi]                     10-11 ball position, 12-13 ball velocity [-3, 3]
//   14-15 unit vector from keeper to ball [-1, 1]
//   16 where the keeper-to-ball line meets x = 20, clipped to [-7.01, 14.02] (MP-DQN's range)
// A body past the goal line or a sideline maps a little outside [-1, 1] (random play: up to
// 1.11); every value is clamped to [-kObservationBound, kObservationBound]. MP-DQN's observation
// leaves the striker's orientation unwrapped; that is the one difference.
//
// Noise (GoalConfig::noise): every acceleration scales its direction by 1 + U(-r, r) and adds
// U(-r|v|, r|v|) to each component, r = 0.1 for players and 0.05 for the ball (gym-goal
// Entity.accelerate), drawn from the env's Rng in gym-goal's order. With the noise off no draws
// are taken. Given the same draws, trajectories agree with gym-goal's own code to 3e-12
// (tests/goal_vs_gym_goal/check.sh: 1,200 episodes, 1,697 decisions of random play).
//
// Cost: a simulation step is about 105 ns (two atan2, two sin/cos pairs); random play averages
// 25 per decision step (bench BM_GoalStep: 376 k decisions/s). step() and reset() allocate
// nothing. Not thread-safe: one env per thread.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

#include "core/rng.hpp"
#include "envs/env.hpp"

namespace pamdp::goal {

struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};

// A moving entity. The ball's orientation is unused.
struct Body {
  Vec2 position;
  Vec2 velocity;
  double orientation_rad = 0.0;
};

struct GoalState {
  Body striker;
  Body keeper;
  Body ball;
};

struct GoalConfig {
  bool noise = true;  // gym-goal's acceleration noise; false makes the dynamics deterministic
};

class GoalEnv final : public Env {
 public:
  enum ActionId : int { kKickTo = 0, kShootGoalLeft = 1, kShootGoalRight = 2 };
  // Indices into the shared parameter vector.
  static constexpr int kKickToX = 0;
  static constexpr int kKickToY = 1;
  static constexpr int kShootLeftY = 2;
  static constexpr int kShootRightY = 3;
  enum Status : int { kInProgress = 0, kGoal = 1, kCaught = 2, kOutOfBounds = 3, kOutOfTime = 4 };
  static constexpr int kObservationSize = 17;
  static constexpr float kObservationBound = 2.0F;
  static constexpr int kMaxSteps = 100;  // decision steps, the last of which only ends the episode
  // Internal steps one decision may run. gym-goal has no bound; the episode ends OUT_OF_TIME here.
  static constexpr int kMaxSimStepsPerDecision = 1000;

  explicit GoalEnv(const GoalConfig& config = {}, uint64_t seed = 0);

  [[nodiscard]] std::string_view name() const override { return "goal"; }
  [[nodiscard]] const ActionSpace& action_space() const override;
  [[nodiscard]] int observation_size() const override { return kObservationSize; }
  [[nodiscard]] int max_episode_steps() const override { return kMaxSteps; }
  [[nodiscard]] std::string_view status_name(int status) const override;
  [[nodiscard]] std::span<const int> outcomes() const override;
  [[nodiscard]] int success_status() const override { return kGoal; }

  void reset(uint64_t seed, std::span<float> obs) override;
  void reset(std::span<float> obs) override;
  // Aborts on an unknown action id, a parameter vector shorter than 4, or a finished episode.
  StepResult step(const ParamAction& action, std::span<float> obs) override;

  // Starts an episode from `state` (tests). The env's random stream is left where it is.
  void set_state(const GoalState& state, std::span<float> obs);
  [[nodiscard]] const GoalState& state() const { return state_; }
  // Internal simulation steps the last step() ran (0 for the time-limit step).
  [[nodiscard]] int last_sim_steps() const { return last_sim_steps_; }
  [[nodiscard]] const GoalConfig& config() const { return config_; }

 private:
  void simulate(Vec2 target);  // one internal step, every action being a kick to `target`
  [[nodiscard]] int outcome();
  void write_obs(std::span<float> obs) const;

  GoalConfig config_;
  Rng rng_;
  GoalState state_;
  int steps_ = 0;  // decision steps in this episode; -1 after a terminal status
  int last_sim_steps_ = 0;
};

}  // namespace pamdp::goal
