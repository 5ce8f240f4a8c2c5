// HfoTeamEnv: N learned offense players in one embedded HFO game, HFO's `--offense-agents N`
// (with or without the goalie). Each player acts on its own observation, the features of
// features.hpp from its own place (58 + 8 per other player: its teammates, then its opponents),
// and earns its own shaped reward (dqn-hfo's, ShapedReward, from its own features), or with
// team_reward every player earns the team's mean of them; the episode status is the team's. With
// N = 1 it plays exactly as HfoEnv. As an Env (env.name = "hfo" with env.offense_agents = N > 1)
// its step is step_team().
//
// Buffers are player-major: obs holds agents() * observation_size() floats, player i's at
// [i * observation_size(), (i + 1) * observation_size()); rewards holds agents() floats.
// Not thread-safe; allocates nothing per step.
#pragma once

#include <array>
#include <span>

#include "core/action_space.hpp"
#include "envs/env.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

class HfoTeamEnv final : public Env {
 public:
  // config.offense_agents is N (1-4; SoccerSim throws std::invalid_argument otherwise).
  // team_reward (env.team_reward): every player earns the players' mean shaped reward.
  explicit HfoTeamEnv(const SoccerSimConfig& config, bool shoot_action = false, int out_of_bounds_penalty = 0,
                      bool team_reward = false);

  [[nodiscard]] std::string_view name() const override { return "hfo"; }
  [[nodiscard]] int agents() const override { return sim_.offense_agents(); }
  [[nodiscard]] int observation_size() const override { return feature_count(sim_.state().num_players); }
  [[nodiscard]] const ActionSpace& action_space() const override { return hfo_action_space(shoot_); }
  [[nodiscard]] int max_episode_steps() const override { return sim_.config().max_steps + 1; }
  [[nodiscard]] std::string_view status_name(int status) const override { return hfo::status_name(status); }
  [[nodiscard]] std::span<const int> outcomes() const override;
  [[nodiscard]] int success_status() const override { return kGoal; }

  void reset(uint64_t seed, std::span<float> obs) override;
  void reset(std::span<float> obs) override;
  void set_training_updates(int64_t updates) override { sim_.set_training_updates(updates); }
  // Starts an episode from an explicit state (tests, `pamdp sim trace`): one state per offense
  // player; `goalie` (may be null) replaces the goalie's start on an env with a goalie, and
  // `defenders` the first field defenders' (at most SoccerSimConfig::field_defenders).
  void set_state(std::span<const PlayerState> offense, const BallState& ball, const PlayerState* goalie,
                 std::span<float> obs, std::span<const PlayerState> defenders = {});
  // One cycle: every player's action (agents() of them, in player order), then the server's
  // cycle. Returns the episode status (kInGame while it goes on); calling it after a terminal
  // status without a reset stops the process.
  int step(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards);
  // The same as an Env: the status, and the players' mean reward.
  StepResult step_team(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards) override;
  // One player's step, for a team of one (agents() = 1); with more it stops the process.
  StepResult step(const ParamAction& action, std::span<float> obs) override;

  [[nodiscard]] const SoccerSim& sim() const { return sim_; }

 private:
  void begin_episode(std::span<float> obs);
  void write_all(std::span<float> obs) const;

  SoccerSim sim_;
  std::array<ShapedReward, kMaxOffenseAgents> rewards_;
  bool shoot_ = false;
  bool team_reward_ = false;
  bool episode_over_ = false;
};

}  // namespace pamdp::hfo
