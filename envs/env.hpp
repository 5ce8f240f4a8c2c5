// The environment interface every PAMDP env implements (the embedded soccer simulator, the
// real HFO server, toy tasks for tests). The rest of the system talks only to this.
//
// Contract:
//  - Observations are written into a caller-owned span of exactly observation_size() floats.
//  - reset(seed) starts a new episode; the same seed on a freshly constructed env gives the
//    same episode. reset() without a seed continues the env's own random stream.
//  - step() applies one action and advances one decision step. After a terminal status the
//    caller must reset() before stepping again.
//  - Status 0 means "episode goes on"; any other value is a terminal outcome named by
//    status_name(). An env lists every outcome it can produce in outcomes().
//  - Not thread-safe: one env per thread. step() and reset() must not allocate.
//  - A team game (agents() = n > 1: HFO's --offense-agents n) steps n learned players at once,
//    each on its own observation: every observation span holds n of them, player-major (player
//    i's at [i * observation_size(), (i + 1) * observation_size())), and step_team() is the
//    step. observation_size() and action_space() are one player's.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

#include "core/action_space.hpp"

namespace pamdp {

struct StepResult {
  float reward = 0.0F;
  int status = 0;  // 0 = in progress; otherwise the env's terminal outcome code
  [[nodiscard]] bool terminal() const { return status != 0; }
};

// A count an env keeps about its own behaviour, e.g. action parameters it had to clip to a
// server's range. For eval output and logs; most envs keep none.
struct EnvCounter {
  std::string_view name;  // snake_case, e.g. "kick_power_clamped"
  int64_t value = 0;
};

class Env {
 public:
  Env() = default;
  Env(const Env&) = delete;
  Env& operator=(const Env&) = delete;
  virtual ~Env() = default;

  [[nodiscard]] virtual std::string_view name() const = 0;
  [[nodiscard]] virtual const ActionSpace& action_space() const = 0;
  [[nodiscard]] virtual int observation_size() const = 0;
  // Upper bound on decision steps in one episode (for harnesses and buffer sizing).
  [[nodiscard]] virtual int max_episode_steps() const = 0;

  // Human name of a status code ("IN_GAME", "GOAL", ...).
  [[nodiscard]] virtual std::string_view status_name(int status) const = 0;
  // Every status code this env can return, 0 first.
  [[nodiscard]] virtual std::span<const int> outcomes() const = 0;
  // The terminal status that counts as success (scoring rate), or -1 if none.
  [[nodiscard]] virtual int success_status() const = 0;

  // The env's counters since construction; empty by default. Valid until the next call on the env.
  [[nodiscard]] virtual std::span<const EnvCounter> counters() const { return {}; }

  virtual void reset(uint64_t seed, std::span<float> obs) = 0;
  virtual void reset(std::span<float> obs) = 0;
  virtual StepResult step(const ParamAction& action, std::span<float> obs) = 0;

  // The learner's update count, told before every reset by the episode path of `pamdp train` and
  // of every actor (app/trainer.cpp, actor/actor_loop.cpp). An env with a curriculum over
  // training (hfo: env.start_curriculum_updates) draws its next starts from it; one never told,
  // such as an evaluation's, plays its full task. The default ignores it.
  virtual void set_training_updates(int64_t updates) { (void)updates; }

  // Learned players it steps at once; 1 but for a team game.
  [[nodiscard]] virtual int agents() const { return 1; }
  // One step of every player: actions[i] is player i's; writes each player's next observation
  // and its reward (rewards[i]). The result's status is the game's, its reward the players'
  // mean. The default, for one player, is step().
  virtual StepResult step_team(std::span<const ParamAction> actions, std::span<float> obs, std::span<float> rewards) {
    const StepResult r = step(actions[0], obs);
    rewards[0] = r.reward;
    return r;
  }
};

}  // namespace pamdp
