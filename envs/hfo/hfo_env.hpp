// HfoEnv: the embedded Half Field Offense task (1v0 by default) behind the Env interface:
// SoccerSim physics and referee, the 58 features, the paper's four parameterized actions and
// the reward dqn-hfo computed from features (reference §6.2).
#pragma once

#include <array>
#include <span>

#include "envs/env.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

// Discrete action ids (reference §4) and indices into the shared 6-parameter vector. kShoot
// exists only with env.shoot_action (below).
enum ActionId : int { kDash = 0, kTurn = 1, kTackle = 2, kKick = 3, kShoot = 4 };
namespace param {
inline constexpr int kDashPower = 0;
inline constexpr int kDashDir = 1;
inline constexpr int kTurnDir = 2;
inline constexpr int kTackleDir = 3;
inline constexpr int kKickPower = 4;
inline constexpr int kKickDir = 5;
inline constexpr int kCount = 6;
inline constexpr int kShootPower = 6;  // with env.shoot_action
inline constexpr int kShootDir = 7;
inline constexpr int kCountWithShoot = 8;
}  // namespace param

// The paper's action space: DASH(power, dir), TURN(dir), TACKLE(dir), KICK(power, dir), with
// the bounds the actor is kept in (reference §7.4 step 5).
//
// `shoot` (env.shoot_action) adds a fifth action, SHOOT(shoot_power, shoot_dir): the same kick
// command with parameters of its own, so a network keeps two kicks apart, a soft touch to
// dribble and a full-power shot, and the discrete choice between them switches at once where
// one kick head would pass through the powers in between (docs/learning.md, "A second kick").
// The server and the simulator see a KICK either way.
const ActionSpace& hfo_action_space(bool shoot = false);

// The shaped reward of dqn-hfo, computed from consecutive feature vectors (reference §6.2):
// no shaping on the first transition of an episode nor on the terminal one, kickable bonus
// once per episode, 5 for a goal. Beyond dqn-hfo, out_of_bounds_penalty is subtracted on the
// OUT_OF_BOUNDS transition (env.out_of_bounds_penalty, default 0 = dqn-hfo's reward): the shaping
// pays a shot's progress as the ball rolls, so a shot that goes out keeps most of the return of
// one that scores (docs/results.md, "Where the remaining failures are").
class ShapedReward {
 public:
  explicit ShapedReward(int out_of_bounds_penalty = 0) : out_of_bounds_penalty_(out_of_bounds_penalty) {}
  void reset() {
    steps_ = 0;
    got_kick_ = false;
  }
  float operator()(std::span<const float> features, int status);

 private:
  struct Snapshot {
    double ball_prox = 0.0;
    double kickable = 0.0;
    double ball_goal_dist = 0.0;
  };
  static Snapshot snapshot(std::span<const float> f);
  Snapshot prev_;
  int out_of_bounds_penalty_ = 0;
  int steps_ = 0;
  bool got_kick_ = false;
};

// Plays offense player `player`'s action through the simulator's client: the one place the
// action ids map to commands (SHOOT is a KICK with its own parameters and needs `shoot`), for
// HfoEnv and HfoTeamEnv alike. A bad id or short parameter vector stops the process
// (programming error).
void play_action(SoccerSim& sim, int player, const ParamAction& action, bool shoot);

class HfoEnv final : public Env {
 public:
  // shoot_action: the action space with SHOOT (env.shoot_action); out_of_bounds_penalty: the
  // reward's (env.out_of_bounds_penalty, ShapedReward).
  explicit HfoEnv(const SoccerSimConfig& config = {}, bool shoot_action = false, int out_of_bounds_penalty = 0);

  [[nodiscard]] std::string_view name() const override { return "hfo"; }
  [[nodiscard]] const ActionSpace& action_space() const override { return hfo_action_space(shoot_); }
  [[nodiscard]] int observation_size() const override { return feature_count(sim_.state().num_players); }
  [[nodiscard]] int max_episode_steps() const override { return sim_.config().max_steps + 1; }
  [[nodiscard]] std::string_view status_name(int status) const override { return hfo::status_name(status); }
  [[nodiscard]] std::span<const int> outcomes() const override;
  [[nodiscard]] int success_status() const override { return kGoal; }

  void reset(uint64_t seed, std::span<float> obs) override;
  void reset(std::span<float> obs) override;
  void set_training_updates(int64_t updates) override { sim_.set_training_updates(updates); }
  StepResult step(const ParamAction& action, std::span<float> obs) override;

  // Starts an episode from an explicit state (tests, `pamdp sim trace`).
  void set_state(const PlayerState& agent, const BallState& ball, std::span<float> obs);
  // The same with the goalie's state too (a 1v1 env only).
  void set_state(const PlayerState& agent, const BallState& ball, const PlayerState& goalie, std::span<float> obs);
  [[nodiscard]] const SoccerSim& sim() const { return sim_; }

 private:
  void begin_episode(std::span<float> obs);

  SoccerSim sim_;
  ShapedReward reward_;
  bool shoot_ = false;
  bool episode_over_ = false;
};

}  // namespace pamdp::hfo
