// Platform: the parameterized-action benchmark of Masson, Ranchod & Konidaris, "Reinforcement
// Learning with Parameterized Actions" (AAAI 2016), in the form later papers measure it on:
// C. Bester's gym port (cycraig/gym-platform, gym_platform/envs/platform_env.py, "Platform-v0"),
// used by MP-DQN (Bester, James & Konidaris 2019, cycraig/MP-DQN) and HyAR. The rules and
// constants below are that source's, cited by its names (Constants, Player, Enemy, step,
// _update, _terminal_check, get_state); the code is ours.
//
// The task: a player starts at the left end of three platforms separated by two gaps, with one
// enemy pacing each of the first two platforms, and must reach the right end of the third.
// Three actions, each with one parameter (native units, as gym-platform's action space):
//   RUN(dx in [0, 30]), HOP(dx in [0, 720]), LEAP(dx in [0, 430]).
// One decision step runs the simulation at dt = 0.05 until the action is done: RUN for 20 ticks
// (step(): difft from 1.0 down by dt while > 0), HOP and LEAP until the player stands on a
// platform again; a terminal ends it early.
//
// Reward: the step's progress to the right over the course's length (1035), so an episode that
// reaches the end returns 1 (_terminal_check gives the last step the rest of the way). Ends:
//   GOAL      the player reached x >= 1035 (the success status);
//   ENEMY     it touched an enemy;
//   FELL      it fell below the platforms' top;
//   OUT_OF_TIME after 200 decision steps (Platform-v0's max_episode_steps, which MP-DQN's runs
//             and its evaluation protocol play under).
//
// Observation (9 floats in [-1, 1]): get_state()'s features, scaled by _scale_state to [0, 1]
// and then to [-1, 1] as MP-DQN's ScaledStateWrapper does (2 s - 1):
//   0 player x, 1 player dx, 2 x of the enemy on the player's platform, 3 that enemy's dx,
//   4 width of the player's platform, 5 width of the next, 6 the gap between them, 7 x of the
//   player's platform, 8 height difference to the next (always 0 in Platform-v0, so -1).
//
// Noise (gym-platform's, from its np_random; here from our Rng, so a seed gives the same episode
// here but not numpy's): every acceleration of the player loses |N(0, 0.025)| of dx; a hop or
// leap loses |N(0, 1)| from each of its two launch components; the pacing enemy's dx gains
// N(0, 0.025) each tick. PlatformConfig::noise = false removes all of it (for tests).
//
// Departure from the source: a decision step stops after kMaxTicksPerStep ticks (the physics
// lands every jump within about 900; the cap only bounds the loop).
//
// Cost: a decision step is up to about 20 ticks (RUN) or a few dozen (a jump) of a few
// arithmetic operations; nothing allocates. Not thread-safe: one env per thread.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "core/rng.hpp"
#include "envs/env.hpp"

namespace pamdp::platform {

struct PlatformConfig {
  bool noise = true;    // gym-platform's noise; off only for tests
  int max_steps = 200;  // decision steps before OUT_OF_TIME (Platform-v0)
};

class PlatformEnv final : public Env {
 public:
  enum ActionId : int { kRun = 0, kHop = 1, kLeap = 2 };
  enum Status : int { kInProgress = 0, kGoal = 1, kEnemy = 2, kFell = 3, kOutOfTime = 4 };
  static constexpr int kObservationSize = 9;
  static constexpr int kMaxTicksPerStep = 5000;

  // Throws std::invalid_argument if config.max_steps < 1.
  explicit PlatformEnv(const PlatformConfig& config = {}, uint64_t seed = 0);

  [[nodiscard]] std::string_view name() const override { return "platform"; }
  [[nodiscard]] const ActionSpace& action_space() const override;
  [[nodiscard]] int observation_size() const override { return kObservationSize; }
  [[nodiscard]] int max_episode_steps() const override { return config_.max_steps; }
  [[nodiscard]] std::string_view status_name(int status) const override;
  [[nodiscard]] std::span<const int> outcomes() const override;
  [[nodiscard]] int success_status() const override { return kGoal; }

  void reset(uint64_t seed, std::span<float> obs) override;
  void reset(std::span<float> obs) override;
  // Reads params[action.id] (RUN 0, HOP 1, LEAP 2), clipped to its range.
  StepResult step(const ParamAction& action, std::span<float> obs) override;

  // The state, for tests and traces (positions are the entities' lower-left corners).
  struct Body {
    double x = 0.0, y = 0.0, dx = 0.0, dy = 0.0;
  };
  [[nodiscard]] const Body& player() const { return player_; }
  [[nodiscard]] const Body& enemy(int i) const { return enemies_[static_cast<size_t>(i)]; }
  // Ticks the last decision step ran.
  [[nodiscard]] int last_ticks() const { return last_ticks_; }

 private:
  struct Tick {
    double reward = 0.0;
    int status = kInProgress;
  };
  Tick tick(int action, double param);
  void write_obs(std::span<float> obs) const;
  [[nodiscard]] bool on_platforms() const;
  [[nodiscard]] int enemy_index() const;  // the enemy of the platform the player is over
  [[nodiscard]] double noise(double sd);
  void accelerate(double ax, double ay);
  void jump_to(double diff_x, double dy0, double dev);
  void update_enemy(Body& e, int platform);

  PlatformConfig config_;
  Rng rng_;
  Body player_;
  std::array<Body, 2> enemies_{};
  double step_start_x_ = 0.0;
  int steps_ = 0;
  int last_ticks_ = 0;
  bool done_ = false;
};

}  // namespace pamdp::platform
