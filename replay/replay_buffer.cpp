#include "replay/replay_buffer.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>

namespace pamdp {

ReplayBuffer::ReplayBuffer(int64_t capacity, int obs_dim, int action_dim)
    : capacity_(capacity), obs_dim_(obs_dim), action_dim_(action_dim) {
  if (capacity < 1 || obs_dim < 1 || action_dim < 1) {
    throw std::invalid_argument("ReplayBuffer: capacity, obs_dim and action_dim must be >= 1");
  }
  data_.resize(static_cast<size_t>(capacity * row_width()));
}

void ReplayBuffer::insert(const TransitionView& t) {
  assert(static_cast<int>(t.state.size()) == obs_dim_ && static_cast<int>(t.next_state.size()) == obs_dim_ &&
         static_cast<int>(t.action.size()) == action_dim_);
  float* row = data_.data() + (inserted_ % capacity_) * row_width();
  row = std::copy(t.state.begin(), t.state.end(), row);
  row = std::copy(t.action.begin(), t.action.end(), row);
  *row++ = t.reward;
  row = std::copy(t.next_state.begin(), t.next_state.end(), row);
  *row++ = t.terminal ? 1.0F : 0.0F;
  *row = t.mc_return;
  ++inserted_;
  size_ = std::min(size_ + 1, capacity_);
}

void ReplayBuffer::sample(Rng& rng, int batch, BatchBuffers& out) const {
  assert(size_ > 0 && batch <= out.capacity && out.obs_dim == obs_dim_ && out.action_dim == action_dim_);
  const size_t obs = static_cast<size_t>(obs_dim_);
  const size_t act = static_cast<size_t>(action_dim_);
  for (int j = 0; j < batch; ++j) {
    const auto idx = static_cast<int64_t>(rng.below(static_cast<uint64_t>(size_)));
    const float* row = data_.data() + idx * row_width();
    const auto col = static_cast<size_t>(j);
    std::copy_n(row, obs, out.states.data() + col * obs);
    row += obs;
    std::copy_n(row, act, out.actions.data() + col * act);
    row += act;
    out.rewards[col] = *row++;
    std::copy_n(row, obs, out.next_states.data() + col * obs);
    row += obs;
    out.terminal[col] = *row++;
    out.mc_returns[col] = *row;
  }
}

void ReplayBuffer::set_counters(int64_t size, int64_t inserted) {
  if (size < 0 || size > capacity_ || inserted < size) {
    throw std::invalid_argument("ReplayBuffer: inconsistent counters");
  }
  size_ = size;
  inserted_ = inserted;
}

}  // namespace pamdp
