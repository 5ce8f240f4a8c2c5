// One training run's lifecycle, the same for `pamdp train` (one process, an in-process replay
// buffer) and `pamdp learner` (the distributed system's learner, fed by the replay shards):
//
//   start    a new run writes config.toml (and warm-starts from train.init_from); a resumed one
//            loads checkpoint.ckpt, the run's clock and counters, and refills the last-100
//            training rates from episodes.csv;
//   episodes every finished episode is counted and written to episodes.csv;
//   updates  every update draws its minibatch through one seam, a Sampler (learner/sampler.hpp):
//            the in-process replay buffer for `train`, the replay shards for `learner`; the
//            latest update's statistics feed the metrics rows;
//   evaluate every train.eval_every_updates updates: a greedy evaluation, confirmed on more
//            episodes before it replaces best.ckpt (BestEval), reported to the live metrics;
//   rows     metrics.csv rows with the rates since the previous row;
//   save     checkpoint.ckpt (with the caller's own state: random streams, replay snapshots);
//   finish   a last checkpoint and the logs flushed.
//
// What differs between the two stays with the caller: which sampler, who plays the episodes,
// the extra metrics columns and the progress line. The run directory's files are
// described in learner/run_logs.hpp. Not thread-safe: one thread drives a run.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "actor/exploration.hpp"
#include "envs/env.hpp"
#include "learner/algorithm.hpp"
#include "learner/checkpoint.hpp"
#include "learner/evaluation.hpp"
#include "learner/run_logs.hpp"
#include "learner/sampler.hpp"

namespace pamdp {

// The training loop's settings (config keys train.*).
struct TrainLoopConfig {
  std::string algorithm = "ddpg";  // the learner (learner/algorithm.hpp's registry)
  int64_t max_updates = 3000000;
  int64_t max_episodes = 0;  // 0 = no limit
  double max_seconds = 0.0;  // 0 = no limit
  double updates_per_step = 1.0;
  int64_t eval_every_updates = 10000;  // 0 = never
  int eval_episodes = 10;
  // > 0: an evaluation that would beat the best is confirmed on this many other episodes
  // before best.ckpt is replaced (learner/run_logs.hpp, BestEval); 0 = take it as it is.
  int confirm_episodes = 0;
  // With confirm_episodes > 0: a confirmed candidate that beats best.ckpt's figure must also beat
  // best.ckpt's policy played on the candidate's confirmation starts; when it does not, best.ckpt's
  // figure becomes the pooled result of its evaluations (learner/run_logs.hpp, BestEval).
  bool recheck_best = false;
  // > 0: best.ckpt prefers an evaluation whose average steps to goal are at most this (one within
  // beats one over it; learner/run_logs.hpp, BestEval), for a goal that counts steps; 0 = off.
  double best_steps_limit = 0.0;
  double checkpoint_every_seconds = 600.0;
  double log_every_seconds = 10.0;
  // Warm start: a checkpoint whose networks a new run starts from (learner/checkpoint.hpp
  // warm_start_from_checkpoint; e.g. a 1v0 agent continued against the goalie). Empty: from scratch.
  std::string init_from;
};

// The last 100 episodes, for progress lines and metrics rows. Averages are 0 when empty.
class RecentEpisodes {
 public:
  void add(double ret, int64_t steps, bool success);
  [[nodiscard]] size_t size() const { return window_.size(); }
  [[nodiscard]] double success_rate() const;
  [[nodiscard]] double mean_return() const;
  [[nodiscard]] double mean_steps() const;

 private:
  struct Episode {
    double ret;
    int64_t steps;
    bool success;
  };
  std::deque<Episode> window_;
};

struct RunSpec {
  std::filesystem::path dir;
  std::string role;         // "train" or "learner": begins log lines
  std::string config_toml;  // the resolved config: config.toml of a new run, and in every checkpoint
  uint64_t seed = 1;        // the evaluations' episodes are drawn from it
  TrainLoopConfig loop;
  ExplorationConfig exploration;  // resolved: the evaluations' action mask, the ε the rows report
  std::vector<std::string> extra_metric_columns;
  // How a resumed run treats the episode rows written after its checkpoint. false: it replays
  // that stretch bit for bit, so the rows go and are written again (`pamdp train`). true: they
  // stay, since actors played them and their transitions are in the replay shards; the run
  // counts them and numbers its next episodes after them (`pamdp learner`).
  bool keeps_episodes_after_checkpoint = false;
};

// One episode as it ended, for episodes.csv and the training rates.
struct FinishedEpisode {
  int status = 0;  // the env's status; success is the env's success_status()
  double ret = 0.0;
  int64_t steps = 0;
  uint32_t actor = 0;
  uint64_t weights_version = 0;  // 0: no network chose its actions
  bool scripted = false;         // a demonstration: left out of the training rates
};

class TrainingRun {
 public:
  // `algorithm` is the learner; `env` names the outcomes; `eval_env` plays the greedy
  // evaluations. All must outlive the run.
  TrainingRun(RunSpec spec, Algorithm& algorithm, const Env& env, Env& eval_env);

  // A new run (resume false) or one resumed from dir/checkpoint.ckpt. Returns the checkpoint's
  // metadata (default for a new run): the caller restores its own state from it (random streams,
  // fractional update credit, weights version). Throws std::runtime_error naming the file.
  // Either way dir/config.toml ends up holding spec.config_toml; a resume that changed it keeps
  // the earlier one as config-before-<updates>.toml.
  CheckpointMeta start(bool resume);

  // Fills in the caller's part of every checkpoint's metadata (checkpoint.ckpt and best.ckpt):
  // random streams, fractional update credit, weights version.
  std::function<void(CheckpointMeta&)> on_save;
  // Runs before checkpoint.ckpt is written: what must be at least as new as it (replay snapshots).
  std::function<void()> before_checkpoint;
  // Every evaluation's result (the live metrics).
  std::function<void(const EvalResult&)> on_eval;
  // Builds an algorithm of the run's own config and shapes, updating on the CPU, that best.ckpt
  // is loaded into to be played again (train.recheck_best). Required with train.recheck_best
  // (start() throws std::logic_error without it); never called otherwise.
  std::function<std::unique_ptr<Algorithm>()> make_incumbent;

  // Env steps played, counted as they are played (`train`) or when their episode is reported
  // (`learner`): the rows' env_steps.
  void record_env_steps(int64_t n) { env_steps_ += n; }
  // Counts the episode (its steps are counted by record_env_steps), writes its row (numbered,
  // timed and stamped with the updates here).
  void record_episode(const FinishedEpisode& e);
  // One update on the sampler's next minibatch; its statistics feed the next metrics row. False,
  // and no update, when the sampler had none.
  bool update(Sampler& sampler);

  // True once the updates reached the next evaluation point.
  [[nodiscard]] bool evaluation_due() const;
  // Runs the evaluation that is due and moves to the next point; false when none was due.
  bool evaluate_if_due();
  // A greedy evaluation now (the end of a run), with confirmation and best.ckpt.
  void evaluate();

  // The next metrics row: counters, training rates, the latest update and evaluation, and the
  // update and env-step rates since the previous row. The caller writes it with its extras.
  MetricsRow next_metrics_row();
  RunLogs& logs() { return *logs_; }

  [[nodiscard]] bool checkpoint_due() const;
  void save();
  // A last checkpoint, the logs flushed.
  void finish();

  [[nodiscard]] double elapsed() const;
  [[nodiscard]] double last_row_seconds() const { return last_row_; }
  [[nodiscard]] int64_t episodes() const { return episodes_; }
  [[nodiscard]] int64_t env_steps() const { return env_steps_; }
  [[nodiscard]] int64_t updates() const { return algorithm_.updates(); }
  [[nodiscard]] const RecentEpisodes& recent() const { return recent_; }
  [[nodiscard]] const UpdateStats& last_update() const { return last_stats_; }
  [[nodiscard]] const std::optional<EvalResult>& last_eval() const { return last_eval_; }
  // The update count last_eval() was played at; -1 before the first.
  [[nodiscard]] int64_t last_eval_updates() const { return last_eval_updates_; }
  // The ε of the schedule at the current update.
  [[nodiscard]] double epsilon() const;
  [[nodiscard]] const RunSpec& spec() const { return spec_; }

 private:
  [[nodiscard]] CheckpointMeta meta_now();
  void record_resumed_config();
  void save_to(const std::filesystem::path& file);
  // Loads dir/best.ckpt into incumbent_ (built on first use).
  void load_incumbent();

  RunSpec spec_;
  Algorithm& algorithm_;
  const Env& env_;
  Env& eval_env_;
  std::optional<RunLogs> logs_;
  std::optional<BestEval> best_;
  std::unique_ptr<Algorithm> incumbent_;  // best.ckpt's policy (train.recheck_best)
  RecentEpisodes recent_;
  UpdateStats last_stats_;
  std::optional<EvalResult> last_eval_;
  int64_t last_eval_updates_ = -1;
  int64_t episodes_ = 0;
  int64_t env_steps_ = 0;
  int64_t next_eval_ = INT64_MAX;
  double base_seconds_ = 0.0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  double last_checkpoint_ = 0.0;
  double last_row_ = 0.0;
  int64_t row_updates_ = 0;
  int64_t row_env_steps_ = 0;
};

}  // namespace pamdp
