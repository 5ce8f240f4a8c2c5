// A FIFO ring buffer of transitions with uniform sampling with replacement: the storage of a
// replay shard (reference §7.1: 500,000 FIFO, minibatch 32 uniform with replacement).
//
// Storage is allocated once in the constructor; insert() and sample() copy floats into
// preallocated memory and allocate nothing. Not thread-safe: the shard server serializes
// access (single-process training calls it from one thread).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/rng.hpp"

namespace pamdp {

struct TransitionView {
  std::span<const float> state;
  std::span<const float> action;  // the full actor output vector
  float reward = 0.0F;
  std::span<const float> next_state;
  bool terminal = false;
  float mc_return = 0.0F;  // discounted return from this step to the episode's end
};

// Destination of a sampled minibatch, one sample per column (column-major obs x B etc.).
struct BatchBuffers {
  int obs_dim = 0;
  int action_dim = 0;
  int capacity = 0;
  std::vector<float> states, actions, rewards, next_states, terminal, mc_returns;
  BatchBuffers(int obs, int act, int batch)
      : obs_dim(obs),
        action_dim(act),
        capacity(batch),
        states(static_cast<size_t>(obs) * batch),
        actions(static_cast<size_t>(act) * batch),
        rewards(static_cast<size_t>(batch)),
        next_states(static_cast<size_t>(obs) * batch),
        terminal(static_cast<size_t>(batch)),
        mc_returns(static_cast<size_t>(batch)) {}
};

class ReplayBuffer {
 public:
  ReplayBuffer(int64_t capacity, int obs_dim, int action_dim);

  void insert(const TransitionView& t);
  // Fills the first `batch` columns of out with uniform draws (with replacement).
  // Requires size() > 0 and batch <= out.capacity.
  void sample(Rng& rng, int batch, BatchBuffers& out) const;

  [[nodiscard]] int64_t size() const { return size_; }
  [[nodiscard]] int64_t capacity() const { return capacity_; }
  [[nodiscard]] int64_t inserted() const { return inserted_; }
  [[nodiscard]] int obs_dim() const { return obs_dim_; }
  [[nodiscard]] int action_dim() const { return action_dim_; }

  // Raw access for snapshots: rows are stored in insertion order modulo capacity.
  [[nodiscard]] std::span<const float> raw() const { return data_; }
  std::span<float> raw_mutable() { return data_; }
  void set_counters(int64_t size, int64_t inserted);

 private:
  [[nodiscard]] int64_t row_width() const { return 2LL * obs_dim_ + action_dim_ + 3; }
  int64_t capacity_;
  int obs_dim_;
  int action_dim_;
  int64_t size_ = 0;
  int64_t inserted_ = 0;
  std::vector<float> data_;  // capacity x row: state, action, reward, next_state, terminal, mc_return
};

}  // namespace pamdp
