// One env's episodes, step by step, as `pamdp train` (app/trainer.cpp) and every actor slot
// (actor/actor_loop.cpp) play them: the one episode path of both. At the start of an episode it
// draws whether the teacher plays it (exploration.demo_fraction); each step it asks the acting
// policy for its output when that output is used, picks the action (ε-greedy, or the teacher's),
// writes the teacher's label of the agent's state (exploration.demo_relabel), steps the env and
// keeps the transition. Where an ended episode goes (a replay buffer, batches for the shards) is
// the caller's: it reads episode() and labels() once ended() says so.
//
// A team game (env.agents() = n > 1) is played the same way, player by player: each acts on its
// own observation through the same acting policy (parameter sharing), explores on its own draws,
// and keeps its own episode (episode(i), labels(i)); a demonstration is the teachers' (one per
// player), and the episode's return is the players' mean. With n = 1 nothing changes: the same
// draws, the same env calls.
//
// step() allocates nothing. The env and the teacher are the caller's and must outlive the player.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "actor/exploration.hpp"
#include "core/policy.hpp"
#include "core/rng.hpp"
#include "envs/env.hpp"
#include "replay/episode_buffer.hpp"

namespace pamdp {

class EpisodePlayer {
 public:
  // Writes the acting policy's output vector for an observation. An empty function means there is
  // no policy yet: the output stays as it was (zeros at first).
  using Act = std::function<void(std::span<const float> obs, std::span<float> out)>;

  // teacher: the scripted policy that plays demonstrations and labels (nullptr: none). labels:
  // keep the teacher's label of each of the agent's steps (needs a teacher).
  EpisodePlayer(Env& env, Policy* teacher, bool labels);
  // For a team: `teachers` is empty (none) or holds one per player (std::invalid_argument
  // otherwise).
  EpisodePlayer(Env& env, std::span<Policy* const> teachers, bool labels);
  // The same, for teachers the caller owns as unique_ptrs.
  EpisodePlayer(Env& env, std::span<const std::unique_ptr<Policy>> teachers, bool labels);

  // Resets the env with env_seed and starts an episode, played by the teacher with probability
  // demo_share. The draw comes from rng only when demo_share > 0, so runs without
  // demonstrations keep their random streams.
  void begin(uint64_t env_seed, double demo_share, Rng& rng);

  // Plays one step of the running episode and returns the env's result; after it, ended() says
  // whether the episode is over (a terminal outcome, or as long as the env's longest episode).
  StepResult step(const Act& act, EpsilonGreedy& explore, double epsilon);

  [[nodiscard]] bool ended() const { return ended_; }
  // The players of the game (env.agents()).
  [[nodiscard]] int players() const { return static_cast<int>(episodes_.size()); }
  // Player `i`'s steps this episode; the last is terminal once it has ended.
  [[nodiscard]] EpisodeBuffer& episode(int i = 0) { return episodes_[static_cast<size_t>(i)]; }
  // The same states with the teacher's actions, when this episode is labelled; else nullptr.
  [[nodiscard]] EpisodeBuffer* labels(int i = 0) { return label_ ? &labels_[static_cast<size_t>(i)] : nullptr; }
  [[nodiscard]] bool demo() const { return demo_; }
  // The undiscounted return; of a team, the players' mean.
  [[nodiscard]] float episode_return() const { return return_; }
  [[nodiscard]] int steps() const { return steps_; }

 private:
  Env& env_;
  std::vector<Policy*> teachers_;
  const ActionSpace& space_;
  std::vector<EpisodeBuffer> episodes_;
  std::vector<EpisodeBuffer> labels_;  // one per player when labelling, else empty
  // Player-major: player i's observation at [i * obs, (i + 1) * obs), its output at [i * width, ...).
  std::vector<float> obs_, next_obs_, net_out_, stored_, label_out_;
  std::vector<ParamAction> actions_;
  std::vector<float> rewards_;
  bool demo_ = false;   // the teacher plays this episode
  bool label_ = false;  // the agent plays it and the teacher labels its steps
  bool ended_ = false;
  float return_ = 0.0F;
  int steps_ = 0;
};

}  // namespace pamdp
