// N one-player envs of one game stepped in lockstep as one team env (Env::agents() = N): player i
// is players[i], and each player steps on a thread of its own, since a player's step on a
// synchronous server (HFO's rcssserver) returns only once every player of the game has sent its
// command. The real server's team env (env.server_agents = N): one process plays N agents of one
// bin/HFO --offense-agents N, as HFO's own example/thread_agents.cpp does with its client library.
//
// Contract beyond envs/env.hpp:
//  - Every player's env must have the same observation size, action space and outcomes.
//  - reset() resets every player at once (their first reset connects them at once too, which a
//    server that waits for all its agents needs). step_team() sends every action at once, waits
//    for all, and returns the game's status. The players must agree on it; a disagreement (they
//    are not in one game) is a std::runtime_error naming both statuses.
//  - Rewards: each player's own; with team_reward, each gets the players' mean. The result's
//    reward is the mean either way (as hfo::HfoTeamEnv).
//  - An exception in a player's step (its server went down) is rethrown by step_team() or reset()
//    once every player has finished that step; the first player's (in order) wins.
//  - reset(seed) passes the seed on to every player (player i gets seed + i).
//  - Steps do not allocate (the threads and their hand-over are made once, at construction).
//  - Destruction destroys the players at once too (each may say goodbye to its server).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "envs/env.hpp"

namespace pamdp::hfo_server {

class LockstepTeamEnv final : public Env {
 public:
  // players: at least one, each a one-player env (agents() == 1) of the same game. Throws
  // std::invalid_argument when they differ in width, actions or outcomes.
  LockstepTeamEnv(std::vector<std::unique_ptr<Env>> players, bool team_reward);
  ~LockstepTeamEnv() override;

  [[nodiscard]] std::string_view name() const override { return players_.front()->name(); }
  [[nodiscard]] const ActionSpace& action_space() const override { return players_.front()->action_space(); }
  [[nodiscard]] int observation_size() const override { return players_.front()->observation_size(); }
  [[nodiscard]] int max_episode_steps() const override { return players_.front()->max_episode_steps(); }
  [[nodiscard]] std::string_view status_name(int status) const override {
    return players_.front()->status_name(status);
  }
  [[nodiscard]] std::span<const int> outcomes() const override { return players_.front()->outcomes(); }
  [[nodiscard]] int success_status() const override { return players_.front()->success_status(); }
  // The players' counters, summed by name (every player's env keeps the same ones).
  [[nodiscard]] std::span<const EnvCounter> counters() const override;
  [[nodiscard]] int agents() const override { return static_cast<int>(players_.size()); }

  void reset(uint64_t seed, std::span<float> obs) override;
  void reset(std::span<float> obs) override;
  StepResult step(const ParamAction& action, std::span<float> obs) override;  // one player only
  StepResult step_team(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards) override;
  void set_training_updates(int64_t updates) override;

 private:
  enum class Job { kNone, kReset, kResetSeeded, kStep, kDestroy, kQuit };

  void run(Job job);      // player 0 on the calling thread, the others on theirs; rethrows
  void play(int player);  // player `player`'s part of the current job
  void worker(int player);

  std::vector<std::unique_ptr<Env>> players_;
  bool team_reward_;
  size_t width_ = 0;                  // one player's observation size
  std::vector<std::thread> threads_;  // players 1..N-1
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  uint64_t generation_ = 0;
  int pending_ = 0;
  Job job_ = Job::kNone;
  // The current job's arguments and results, one slot per player.
  uint64_t seed_ = 0;
  std::span<const ParamAction> actions_;
  std::span<float> obs_;
  std::vector<StepResult> results_;
  std::vector<std::exception_ptr> errors_;
  mutable std::vector<EnvCounter> counters_;
};

}  // namespace pamdp::hfo_server
