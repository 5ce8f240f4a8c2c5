// The CSV files of a run directory, written the same way by `pamdp train` and `pamdp learner`
// so that `pamdp plot` and anyone's script read one format:
//
//   metrics.csv   one row per log interval: wall_seconds, updates, env_steps, episodes, epsilon,
//                 success_rate_100, mean_return_100, mean_steps_100, critic_loss, q_mean,
//                 updates_per_s, env_steps_per_s, eval_success_rate, eval_avg_steps_to_success,
//                 eval_avg_return, then the role's extra columns (the learner's: samples/s,
//                 shards, actors, weights version, bad messages, time waiting for data).
//   episodes.csv  one row per episode: episode, wall_seconds, updates, actor, return, steps,
//                 outcome, weights_version, policy. weights_version 0: no network chose the
//                 actions (ε = 1 before the first weights or update, or a demonstration).
//                 policy: "agent" (the actor, ε-greedy) or "scripted" (a demonstration by the
//                 scripted offense, exploration.demo_fraction); the training rates
//                 (success_rate_100, …) of `pamdp train` leave demonstrations out.
//
// "success" is the env's success outcome (GOAL in HFO). Eval columns are empty until the first
// greedy evaluation. Files are appended to (a resumed run continues them); a file whose header
// is not this format (a run from an older version) is renamed to NAME.old-format and restarted.
// A resumed `pamdp train` run first drops the rows its killed predecessor wrote after the last
// checkpoint: it replays that stretch bit for bit and writes those rows again. A resumed
// `pamdp learner` drops the metrics rows past its checkpoint (it redoes those updates) and keeps
// the episode rows, numbering its next episodes after them.
// Rows are flushed at every metrics row so a killed run keeps its log up to the last one.
// Not thread-safe; cost: one formatted line per call.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "learner/evaluation.hpp"

namespace pamdp {

struct MetricsRow {
  double wall_seconds = 0.0;
  int64_t updates = 0;
  int64_t env_steps = 0;
  int64_t episodes = 0;
  std::optional<double> epsilon;  // empty where there is no single schedule (Ape-X)
  double success_rate_100 = 0.0;
  double mean_return_100 = 0.0;
  double mean_steps_100 = 0.0;
  double critic_loss = 0.0;
  double q_mean = 0.0;
  double updates_per_s = 0.0;
  double env_steps_per_s = 0.0;
  std::optional<EvalResult> eval;  // the latest greedy evaluation, if any
};

struct EpisodeRow {
  int64_t episode = 0;
  double wall_seconds = 0.0;
  int64_t updates = 0;
  uint32_t actor = 0;
  double ret = 0.0;
  int64_t steps = 0;
  std::string_view outcome;
  uint64_t weights_version = 0;
  bool scripted = false;  // a demonstration: policy "scripted" instead of "agent"
};

// Where a resumed run continues: its checkpoint's counters. Without `episodes`, every whole
// episode row is kept: `pamdp learner` logs episodes its actors played, which stay real (their
// transitions are in the replay shards) when the learner is killed before its next checkpoint.
struct ResumePoint {
  int64_t updates = 0;
  std::optional<int64_t> episodes;
};

class RunLogs {
 public:
  // Opens (appending) dir/metrics.csv and dir/episodes.csv. With `resume_at`, metrics rows of
  // more updates and episode rows of a later episode are removed first. Throws
  // std::runtime_error naming the file when one cannot be written.
  RunLogs(const std::filesystem::path& dir, std::vector<std::string> extra_metric_columns = {},
          std::optional<ResumePoint> resume_at = std::nullopt);

  // `extras` has one value per extra column given to the constructor.
  void metrics(const MetricsRow& row, std::span<const double> extras = {});
  void episode(const EpisodeRow& row);
  void flush();  // writes the rows gathered so far
  ~RunLogs();

  static const std::vector<std::string>& metric_columns();  // without the extras
  static const std::vector<std::string>& episode_columns();

 private:
  // Episode rows are written in blocks of about this many bytes, and at flush().
  static constexpr std::streamoff kEpisodeBytesPerWrite = 64 * 1024;

  std::vector<std::string> extras_;
  std::ofstream metrics_file_;
  std::ofstream episodes_file_;
  // Rows not yet written: a file grows by whole rows only.
  std::ostringstream metrics_pending_;
  std::ostringstream episodes_pending_;
};

// One row of episodes.csv as read back.
struct LoggedEpisode {
  int64_t episode = 0;
  double wall_seconds = 0.0;
  double ret = 0.0;
  int64_t steps = 0;
  std::string outcome;
  uint64_t weights_version = 0;
  bool scripted = false;
};

// Calls `visit` with every row of dir/episodes.csv that parses, in file order, holding one row at
// a time (a long run's file has millions); none when there is no file. A resumed run reads its
// rows back with it (TrainingRun::start): rows cut off by a kill are skipped.
void for_each_logged_episode(const std::filesystem::path& dir, const std::function<void(const LoggedEpisode&)>& visit);

// Keeps the best greedy evaluation of a run: a higher success rate wins, then fewer steps to
// success, then a higher return. With a steps limit (train.best_steps_limit > 0), an evaluation
// with successes whose average steps to success are within the limit beats one over it, whatever
// their rates; two on the same side compare as above. For a goal that counts both (HFO: scoring
// at least .99 in at most 75 steps), an early pick that scores high but slowly does not hold
// best.ckpt against later, faster candidates that score a little less. Persisted in a small text
// file (the run directory's best_eval.txt) so that a resumed run keeps comparing against the best
// of its earlier part.
//
// The maximum over a run's ~200 evaluations of 100 episodes is biased upwards: the policy that
// scored 1.0 on one set of starts scores .93 on another. With `confirm`, an evaluation that
// would beat the best is only a candidate: confirm() evaluates the same policy again (on more,
// independent episodes) and that result is what is compared and kept, so the figure in
// best_eval.txt is the candidate's unbiased score, not its lucky draw.
//
// That figure is unbiased for the candidate, not for the winner: the best of a run's ~30
// confirmations still overstates itself (a best.ckpt confirmed at .995 on its run's starts scored
// .986 on 3,000 others, docs/results.md issue 29), and each challenger is compared against that
// optimistic figure on starts of its own. With `recheck` as well (train.recheck_best), a
// confirmed challenger that beats the kept figure is compared once more, against the kept policy
// played on the challenger's own confirmation starts (a paired comparison, so the luck of one set
// of starts does not decide). The challenger wins only if it beats that result too. When it
// loses, the kept figure becomes the pooled result of all the kept policy's evaluations so far,
// so that figure falls back toward the policy's true score. The figure in best_eval.txt is then
// the pooled one, over its stated episodes.
class BestEval {
 public:
  // `role` ("train", "learner") begins the log line of each confirmation.
  explicit BestEval(std::filesystem::path file, std::string role = "train", double steps_limit = 0.0);

  // True when the (confirmed) result beats every one kept before (the first one always does);
  // then the file is rewritten (atomically) with it and `updates`. `kept`, when given, receives
  // the result that was compared (the confirmation's, when one ran). A confirmation is logged
  // with both results and the verdict. A result without successes is kept unconfirmed.
  // `recheck`, when given, plays the kept policy on the confirmation's starts (see above); it is
  // called only after a confirmation that beats the kept figure, and only when that figure has
  // successes. A lost recheck rewrites the file with the pooled figure of the kept policy.
  bool offer(const EvalResult& r, int64_t updates, const std::function<EvalResult()>& confirm = {},
             EvalResult* kept = nullptr, const std::function<EvalResult()>& recheck = {});
  [[nodiscard]] const std::optional<EvalResult>& best() const { return best_; }
  // The updates at which the kept policy was evaluated (0 when none or not recorded).
  [[nodiscard]] int64_t best_updates() const { return best_updates_; }

 private:
  [[nodiscard]] bool beats(const EvalResult& r, const EvalResult& b) const;
  [[nodiscard]] bool beats_best(const EvalResult& r) const { return !best_ || beats(r, *best_); }
  void write() const;

  std::filesystem::path file_;
  std::string role_;
  double steps_limit_;
  std::optional<EvalResult> best_;
  int64_t best_updates_ = 0;
};

// Two evaluations of one policy as one: rates and returns weighted by episodes, steps to goal by
// successes. An `a` without a recorded episode count (best_eval.txt written before it held one)
// adds nothing: the result is `b`.
EvalResult pooled(const EvalResult& a, const EvalResult& b);

}  // namespace pamdp
