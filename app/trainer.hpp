// Single-process training (`pamdp train`): one env, a replay buffer and the DDPG learner in
// one thread, for quick experiments, tests and the first learning curves.
//
// A run directory holds: config.toml (the resolved config), metrics.csv (one row per log
// tick), episodes.csv (one row per episode), checkpoint.ckpt and replay.bin (written together
// at episode boundaries every train.checkpoint_every_seconds and at the end). Resuming from
// it continues bit for bit: env episodes are seeded from (seed, episode index), every random
// stream is in the checkpoint, and stop conditions are checked only at episode boundaries
// (a run ends at the first episode end after a limit). train.max_updates is exact: no update
// past it, the episode it falls in played to its end without updates; so a run stopped by
// max_updates and resumed with a higher one is not bit for bit a run that never stopped (one
// stopped by a signal, max_seconds or max_episodes is).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "app/experiment_config.hpp"
#include "learner/evaluation.hpp"

namespace pamdp::app {

struct TrainSummary {
  int64_t updates = 0;
  int64_t env_steps = 0;
  int64_t episodes = 0;
  double seconds = 0.0;
  EvalResult final_eval;  // greedy evaluation at the end (train.eval_episodes episodes)
};

class TrainMetrics;  // app/role_metrics.hpp

struct TrainOptions {
  std::string run_dir;
  bool resume = false;                      // continue from run_dir/checkpoint.ckpt
  bool quiet = false;                       // no progress lines on stdout
  const std::atomic<bool>* stop = nullptr;  // set by a signal handler to stop at the next episode end
  TrainMetrics* metrics = nullptr;          // live metrics (/metrics); may be null
};

TrainSummary train(const ExperimentConfig& config, const TrainOptions& options);

}  // namespace pamdp::app
