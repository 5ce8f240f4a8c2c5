#include "replay/episode_buffer.hpp"

#include <algorithm>
#include <cassert>

namespace pamdp {
namespace {

size_t area(int rows, int width) {
  return static_cast<size_t>(rows) * static_cast<size_t>(width);
}

}  // namespace

EpisodeBuffer::EpisodeBuffer(int max_steps, int obs_dim, int action_dim)
    : obs_(static_cast<size_t>(obs_dim)),
      act_(static_cast<size_t>(action_dim)),
      states_(area(max_steps, obs_dim)),
      next_(area(max_steps, obs_dim)),
      actions_(area(max_steps, action_dim)),
      rewards_(static_cast<size_t>(max_steps)),
      returns_(static_cast<size_t>(max_steps)) {}

void EpisodeBuffer::push(std::span<const float> state, std::span<const float> action, float reward,
                         std::span<const float> next_state) {
  assert(n_ < capacity() && state.size() == obs_ && next_state.size() == obs_ && action.size() == act_);
  std::copy(state.begin(), state.end(), states_.begin() + static_cast<ptrdiff_t>(n_ * obs_));
  std::copy(action.begin(), action.end(), actions_.begin() + static_cast<ptrdiff_t>(n_ * act_));
  std::copy(next_state.begin(), next_state.end(), next_.begin() + static_cast<ptrdiff_t>(n_ * obs_));
  rewards_[n_] = reward;
  ++n_;
}

void EpisodeBuffer::compute_returns(double gamma) {
  double g = 0.0;
  for (size_t i = n_; i-- > 0;) {
    g = rewards_[i] + gamma * g;
    returns_[i] = static_cast<float>(g);
  }
}

TransitionView EpisodeBuffer::transition(size_t i) const {
  assert(i < n_);
  return {{states_.data() + i * obs_, obs_},
          {actions_.data() + i * act_, act_},
          rewards_[i],
          {next_.data() + i * obs_, obs_},
          i + 1 == n_,
          returns_[i]};
}

void flush_episode(EpisodeBuffer& episode, double gamma, ReplayBuffer& replay, ReplayBuffer* also) {
  episode.compute_returns(gamma);
  for (size_t i = 0; i < episode.size(); ++i) {
    const TransitionView t = episode.transition(i);
    replay.insert(t);
    if (also != nullptr) {
      also->insert(t);
    }
  }
  episode.clear();
}

}  // namespace pamdp
