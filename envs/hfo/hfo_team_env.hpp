// HfoTeamEnv: N learned offense players in one embedded HFO game, HFO's `--offense-agents N`
// (with or without the goalie). Each player acts on its own observation, the features of
// features.hpp from its own place (58 + 8 per other player: its teammates, then its opponents),
// and earns its own shaped reward (dqn-hfo's, ShapedReward, from its own features); the episode
// status is the team's. With N = 1 it plays exactly as HfoEnv.
//
// Buffers are player-major: obs holds agents() * observation_size() floats, player i's at
// [i * observation_size(), (i + 1) * observation_size()); rewards holds agents() floats.
// Not thread-safe; allocates nothing per step.
#pragma once

#include <array>
#include <span>

#include "core/action_space.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

class HfoTeamEnv {
 public:
  // config.offense_agents is N (1-4; SoccerSim throws std::invalid_argument otherwise).
  explicit HfoTeamEnv(const SoccerSimConfig& config, bool shoot_action = false, int out_of_bounds_penalty = 0);

  [[nodiscard]] int agents() const { return sim_.offense_agents(); }
  [[nodiscard]] int observation_size() const { return feature_count(sim_.state().num_players); }
  [[nodiscard]] const ActionSpace& action_space() const { return hfo_action_space(shoot_); }
  [[nodiscard]] int max_episode_steps() const { return sim_.config().max_steps + 1; }

  void reset(uint64_t seed, std::span<float> obs);
  void reset(std::span<float> obs);
  // Starts an episode from an explicit state (tests, `pamdp sim trace`): one state per offense
  // player; `goalie` (may be null) replaces the goalie's start on an env with a goalie.
  void set_state(std::span<const PlayerState> offense, const BallState& ball, const PlayerState* goalie,
                 std::span<float> obs);
  // One cycle: every player's action (agents() of them, in player order), then the server's
  // cycle. Returns the episode status (kInGame while it goes on); calling it after a terminal
  // status without a reset stops the process.
  int step(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards);

  [[nodiscard]] const SoccerSim& sim() const { return sim_; }

 private:
  void begin_episode(std::span<float> obs);
  void write_all(std::span<float> obs) const;

  SoccerSim sim_;
  std::array<ShapedReward, kMaxOffenseAgents> rewards_;
  bool shoot_ = false;
  bool episode_over_ = false;
};

}  // namespace pamdp::hfo
