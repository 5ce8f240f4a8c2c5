// VectorEnv: N envs stepped together in C++, EnvPool's way: every result is written straight
// into caller-owned batch arrays (row i belongs to env i), and a finished env is reset by the
// vector itself (Gymnasium's autoreset modes). Python's binding hands it NumPy buffers.
//
// Threads: with num_threads = T > 1, T - 1 workers are started in the constructor and the calling
// thread takes the first slice; each thread steps a fixed contiguous slice of the envs, so a
// slice's results never depend on the thread count. A step allocates nothing.
// Teams: an env of A learned players (Env::agents(), the hfo env with env.offense_agents = A) is
// stepped with step_team; its row of every per-player buffer is A rows, player-major (obs: A x
// observation_size, reward: A, actions: A), while terminated, truncated and status stay one per
// env, since a game ends for all its players at once.
// Not thread-safe: one caller at a time.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "envs/env.hpp"

namespace pamdp::python {

enum class AutoReset {
  kNextStep,  // the step after a terminal one resets that env (its action is ignored): obs of the
              // new episode, reward 0, not done (Gymnasium >= 1.0's default, EnvPool's)
  kSameStep,  // the terminal step resets at once: obs of the new episode, the terminal obs in
              // final_obs (Gymnasium < 1.0's behaviour)
};

// Where a step writes, all caller-owned, N rows each (A = agents(): 1 but for a team).
struct VectorBuffers {
  std::span<float> obs;           // N x A x observation_size
  std::span<float> reward;        // N x A
  std::span<uint8_t> terminated;  // N, 0/1 (NumPy bool)
  std::span<uint8_t> truncated;   // N, 0/1
  std::span<int32_t> status;      // N, the env's status code (0: goes on)
  std::span<float> final_obs;     // kSameStep: N x A x observation_size, rows where has_final is 1
  std::span<uint8_t> has_final;   // kSameStep: N
};

class VectorEnv {
 public:
  // `timeout_status` is the status that counts as truncation (time limit), -1 if none. `rebuild`,
  // when given, makes a fresh env for every seeded reset (see fresh_env_per_seed()). Every env
  // must have as many players as the first.
  VectorEnv(std::vector<std::unique_ptr<Env>> envs, int num_threads, AutoReset mode, int timeout_status,
            std::function<std::unique_ptr<Env>()> rebuild = {});
  VectorEnv(const VectorEnv&) = delete;
  VectorEnv& operator=(const VectorEnv&) = delete;
  ~VectorEnv();

  [[nodiscard]] int num_envs() const { return static_cast<int>(envs_.size()); }
  [[nodiscard]] int num_threads() const { return num_threads_; }
  [[nodiscard]] int observation_size() const { return obs_size_; }
  // Learned players per env (Env::agents()): 1 but for a team game.
  [[nodiscard]] int agents() const { return agents_; }
  [[nodiscard]] const Env& env(int i) const { return *envs_[static_cast<size_t>(i)]; }

  // Resets every env: env i with seeds[i] (a fresh env first, with `rebuild`), or continuing its
  // own stream when `seeds` is empty.
  void reset(std::span<const uint64_t> seeds, const VectorBuffers& out);
  // One step of every env: env i's player a takes action ids[i * A + a] with parameter row
  // i * A + a of `params` (N x A x num_params). Ids must be valid (the binding checks them).
  void step(std::span<const int> ids, std::span<const float> params, const VectorBuffers& out);

 private:
  void run(const std::function<void(int, int)>& slice);
  void step_slice(int begin, int end);
  void worker(int index);

  std::vector<std::unique_ptr<Env>> envs_;
  int num_threads_;
  AutoReset mode_;
  int timeout_status_;
  std::function<std::unique_ptr<Env>()> rebuild_;
  int obs_size_;
  int num_params_;
  int agents_;
  std::vector<ParamAction> actions_;  // N x A, the team step's actions (built per step, no allocation)
  std::vector<uint8_t> needs_reset_;
  std::function<void(int, int)> step_job_;  // built once: a step allocates nothing

  // The current job, read by the workers.
  std::span<const int> ids_;
  std::span<const float> params_;
  VectorBuffers out_;
  const std::function<void(int, int)>* job_ = nullptr;

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  uint64_t generation_ = 0;
  int running_ = 0;
  bool stop_ = false;
};

}  // namespace pamdp::python
