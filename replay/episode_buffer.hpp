// The running episode's transitions, kept until it ends so that each can carry its discounted
// Monte-Carlo return (the paper's mixed target, §4.3) before it goes to replay. One class for
// every path that plays episodes into replay: the episode player (actor/episode_player.hpp) of
// `pamdp train` and of the actors.
//
// Sized once for the env's longest episode; push(), compute_returns() and transition()
// allocate nothing.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "replay/replay_buffer.hpp"

namespace pamdp {

class EpisodeBuffer {
 public:
  EpisodeBuffer(int max_steps, int obs_dim, int action_dim);

  void clear() { n_ = 0; }
  [[nodiscard]] size_t size() const { return n_; }
  [[nodiscard]] size_t capacity() const { return rewards_.size(); }

  // Appends one step; size() < capacity() (checked by assert).
  void push(std::span<const float> state, std::span<const float> action, float reward,
            std::span<const float> next_state);

  // G_t = r_t + gamma * G_{t+1}, with G = 0 after the last step, accumulated in double.
  void compute_returns(double gamma);

  // Step i with its return (valid after compute_returns). The last step is terminal: the
  // episode has ended, and time-outs count as terminals as in the paper's code.
  [[nodiscard]] TransitionView transition(size_t i) const;

 private:
  size_t obs_, act_;
  size_t n_ = 0;
  std::vector<float> states_, next_, actions_, rewards_, returns_;
};

// Inserts the ended episode's transitions with their returns into `replay` (and `also`, when
// given), then clears it.
void flush_episode(EpisodeBuffer& episode, double gamma, ReplayBuffer& replay, ReplayBuffer* also = nullptr);

}  // namespace pamdp
