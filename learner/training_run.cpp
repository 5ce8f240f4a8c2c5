#include "learner/training_run.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "core/files.hpp"
#include "core/gemm.hpp"
#include "core/log.hpp"
#include "learner/greedy_policy.hpp"

namespace pamdp {

namespace fs = std::filesystem;

void RecentEpisodes::add(double ret, int64_t steps, bool success) {
  window_.push_back({ret, steps, success});
  if (window_.size() > 100) {
    window_.pop_front();
  }
}

namespace {
template <typename W, typename F>
double window_mean(const W& window, F value) {
  double total = 0.0;
  for (const auto& e : window) {
    total += value(e);
  }
  return total / std::max<double>(1.0, static_cast<double>(window.size()));
}
}  // namespace

double RecentEpisodes::success_rate() const {
  return window_mean(window_, [](const Episode& e) { return e.success ? 1.0 : 0.0; });
}
double RecentEpisodes::mean_return() const {
  return window_mean(window_, [](const Episode& e) { return e.ret; });
}
double RecentEpisodes::mean_steps() const {
  return window_mean(window_, [](const Episode& e) { return static_cast<double>(e.steps); });
}

TrainingRun::TrainingRun(RunSpec spec, Algorithm& algorithm, const Env& env, Env& eval_env)
    : spec_(std::move(spec)), algorithm_(algorithm), env_(env), eval_env_(eval_env) {}

// A resume may change the config (`--set train.max_updates=…`). config.toml then gets the config
// the run goes on with, so a later plain --resume continues with it too, and the one before is
// kept beside it as config-before-<updates>.toml.
void TrainingRun::record_resumed_config() {
  const fs::path path = spec_.dir / "config.toml";
  std::string before;
  if (fs::exists(path)) {
    const std::vector<uint8_t> bytes = read_file_bytes(path.string());
    before.assign(bytes.begin(), bytes.end());
  }
  if (before == spec_.config_toml) {
    return;
  }
  if (!before.empty()) {
    const fs::path kept = spec_.dir / ("config-before-" + std::to_string(algorithm_.updates()) + ".toml");
    write_file_atomically(kept.string(), before.data(), before.size());
    log::info("{}: resumed with a changed config: config.toml now holds it; the one before is {}", spec_.role,
              kept.string());
  }
  write_file_atomically(path.string(), spec_.config_toml.data(), spec_.config_toml.size());
}

CheckpointMeta TrainingRun::start(bool resume) {
  if (spec_.loop.recheck_best && !make_incumbent) {
    throw std::logic_error("TrainingRun: train.recheck_best needs make_incumbent");
  }
  fs::create_directories(spec_.dir);
  CheckpointMeta meta;
  if (resume) {
    meta = load_checkpoint((spec_.dir / "checkpoint.ckpt").string(), algorithm_);
    episodes_ = meta.episodes;
    env_steps_ = meta.env_steps;
    base_seconds_ = meta.elapsed_seconds;
    record_resumed_config();
  } else {
    if (!spec_.loop.init_from.empty()) {
      warm_start_from_checkpoint(spec_.loop.init_from, algorithm_);
      log::info("{}: networks warm-started from {}", spec_.role, spec_.loop.init_from);
    }
    write_file_atomically((spec_.dir / "config.toml").string(), spec_.config_toml.data(), spec_.config_toml.size());
  }
  if (const std::string note = algorithm_.evaluated_copy_note(); !note.empty()) {
    log::info("{}: {}", spec_.role, note);
  }
  log::info("{}: CPU matrix products on {} (PAMDP_GEMM=eigen|openblas overrides)", spec_.role, gemm_backend());
  std::optional<ResumePoint> resume_at;
  if (resume) {
    resume_at =
        ResumePoint{algorithm_.updates(),
                    spec_.keeps_episodes_after_checkpoint ? std::nullopt : std::optional<int64_t>(meta.episodes)};
  }
  logs_.emplace(spec_.dir, spec_.extra_metric_columns, resume_at);
  if (resume) {
    // One pass over episodes.csv: the last-100 training rates go on from the agent's episodes
    // logged before, and the rows kept past the checkpoint (keeps_episodes_after_checkpoint) are
    // counted. The clock goes on from the last row, so wall_seconds never go back.
    const std::string_view success = env_.status_name(env_.success_status());
    int64_t after = 0;
    for_each_logged_episode(spec_.dir, [&](const LoggedEpisode& e) {
      if (!e.scripted) {
        recent_.add(e.ret, e.steps, e.outcome == success);
      }
      base_seconds_ = std::max(base_seconds_, e.wall_seconds);
      if (e.episode > episodes_) {
        episodes_ = e.episode;
        env_steps_ += e.steps;
        ++after;
      }
    });
    if (after > 0) {
      log::info("{}: {} episodes logged after the checkpoint are kept; episodes go on from {}", spec_.role, after,
                episodes_ + 1);
    }
  }
  best_.emplace(spec_.dir / "best_eval.txt", spec_.role, spec_.loop.best_steps_limit);
  if (spec_.loop.recheck_best && resume && fs::exists(spec_.dir / "best.ckpt")) {
    load_incumbent();
  }
  start_ = std::chrono::steady_clock::now();
  last_checkpoint_ = last_row_ = base_seconds_;
  row_updates_ = algorithm_.updates();
  row_env_steps_ = env_steps_;
  const int64_t every = spec_.loop.eval_every_updates;
  next_eval_ = every > 0 ? (algorithm_.updates() / every + 1) * every : INT64_MAX;
  return meta;
}

double TrainingRun::elapsed() const {
  return base_seconds_ + std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double TrainingRun::epsilon() const {
  const ExplorationConfig& x = spec_.exploration;
  return linear_epsilon(algorithm_.updates(), x.epsilon_start, x.epsilon_end, x.epsilon_anneal_updates);
}

void TrainingRun::record_episode(const FinishedEpisode& e) {
  ++episodes_;
  if (!e.scripted) {  // the training rates are the agent's own
    recent_.add(e.ret, e.steps, e.status == env_.success_status());
  }
  EpisodeRow row;
  row.episode = episodes_;
  row.wall_seconds = elapsed();
  row.updates = algorithm_.updates();
  row.actor = e.actor;
  row.ret = e.ret;
  row.steps = e.steps;
  row.outcome = env_.status_name(e.status);
  row.weights_version = e.weights_version;
  row.scripted = e.scripted;
  logs_->episode(row);
}

bool TrainingRun::update(Sampler& sampler) {
  const std::optional<UpdateStats> stats = update_from(sampler, algorithm_);
  if (stats) {
    last_stats_ = *stats;
  }
  return stats.has_value();
}

bool TrainingRun::evaluation_due() const {
  return algorithm_.updates() >= next_eval_;
}

bool TrainingRun::evaluate_if_due() {
  if (!evaluation_due()) {
    return false;
  }
  evaluate();
  next_eval_ += spec_.loop.eval_every_updates;
  return true;
}

void TrainingRun::evaluate() {
  const TrainLoopConfig& loop = spec_.loop;
  if (loop.eval_episodes <= 0) {
    return;
  }
  algorithm_.sync_acting();  // moves the actor average too, as the weight broadcasts do
  GreedyActorPolicy policy(algorithm_, eval_env_.action_space(), spec_.exploration, algorithm_.evaluated_copy());
  const int64_t at = algorithm_.updates();
  last_eval_ = pamdp::evaluate(eval_env_, policy, loop.eval_episodes, screening_seed(spec_.seed, at));
  last_eval_updates_ = at;
  log::info("{}: greedy evaluation at {} updates: success {:.3f} over {} episodes, return {:.3f}", spec_.role, at,
            last_eval_->goal_rate, last_eval_->episodes, last_eval_->avg_return);
  if (on_eval) {
    on_eval(*last_eval_);
  }
  // The confirmation's starts: the candidate plays them, and best.ckpt's policy replays them.
  const auto on_confirmation_starts = [&](Policy& p) {
    return pamdp::evaluate(eval_env_, p, loop.confirm_episodes, confirmation_seed(spec_.seed, at));
  };
  std::function<EvalResult()> confirm;
  if (loop.confirm_episodes > 0) {
    confirm = [&] { return on_confirmation_starts(policy); };
  }
  std::function<EvalResult()> recheck;
  if (loop.recheck_best && loop.confirm_episodes > 0 && incumbent_) {
    recheck = [&] {
      GreedyActorPolicy kept(*incumbent_, eval_env_.action_space(), spec_.exploration, incumbent_->evaluated_copy());
      return on_confirmation_starts(kept);
    };
  }
  // The actor (with everything else) of the best greedy evaluation so far: what `pamdp eval
  // --checkpoint RUN/best.ckpt` should be given when the final policy is worse than an earlier one.
  if (best_->offer(*last_eval_, at, confirm, nullptr, recheck)) {
    save_to(spec_.dir / "best.ckpt");
    if (loop.recheck_best) {
      load_incumbent();
    }
  }
}

void TrainingRun::load_incumbent() {
  if (!incumbent_) {
    incumbent_ = make_incumbent();
  }
  load_checkpoint((spec_.dir / "best.ckpt").string(), *incumbent_);
}

MetricsRow TrainingRun::next_metrics_row() {
  const double now = elapsed();
  const double dt = std::max(1e-9, now - last_row_);
  MetricsRow row;
  row.wall_seconds = now;
  row.updates = algorithm_.updates();
  row.env_steps = env_steps_;
  row.episodes = episodes_;
  row.epsilon = epsilon();
  row.success_rate_100 = recent_.success_rate();
  row.mean_return_100 = recent_.mean_return();
  row.mean_steps_100 = recent_.mean_steps();
  row.critic_loss = last_stats_.critic_loss;
  row.q_mean = last_stats_.q_mean;
  row.updates_per_s = static_cast<double>(algorithm_.updates() - row_updates_) / dt;
  row.env_steps_per_s = static_cast<double>(env_steps_ - row_env_steps_) / dt;
  row.eval = last_eval_;
  last_row_ = now;
  row_updates_ = algorithm_.updates();
  row_env_steps_ = env_steps_;
  return row;
}

bool TrainingRun::checkpoint_due() const {
  const double every = spec_.loop.checkpoint_every_seconds;
  return every > 0.0 && elapsed() - last_checkpoint_ >= every;
}

CheckpointMeta TrainingRun::meta_now() {
  CheckpointMeta meta;
  meta.config_toml = spec_.config_toml;
  meta.env_steps = env_steps_;
  meta.episodes = episodes_;
  meta.elapsed_seconds = elapsed();
  if (on_save) {
    on_save(meta);
  }
  return meta;
}

void TrainingRun::save_to(const fs::path& file) {
  const CheckpointMeta meta = meta_now();
  save_checkpoint(file.string(), algorithm_, meta);
}

void TrainingRun::save() {
  if (before_checkpoint) {
    before_checkpoint();
  }
  save_to(spec_.dir / "checkpoint.ckpt");
  last_checkpoint_ = elapsed();
}

void TrainingRun::finish() {
  save();
  logs_->flush();
}

}  // namespace pamdp
