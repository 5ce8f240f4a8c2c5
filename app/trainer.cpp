#include "app/trainer.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <stdexcept>
#include <vector>

#include "actor/exploration.hpp"
#include "app/actor_policy.hpp"
#include "app/env_factory.hpp"
#include "app/progress.hpp"
#include "app/role_metrics.hpp"
#include "app/run_logs.hpp"
#include "app/run_support.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "learner/checkpoint.hpp"
#include "learner/ddpg.hpp"
#include "learner/update_backend.hpp"
#include "replay/episode_buffer.hpp"
#include "replay/replay_buffer.hpp"
#include "replay/replay_snapshot.hpp"

namespace pamdp::app {
namespace {

namespace fs = std::filesystem;

class Trainer {
 public:
  Trainer(const ExperimentConfig& c, TrainOptions o)
      : c_(c),
        o_(std::move(o)),
        env_(make_env(c.env)),
        eval_env_(make_eval_env(c)),
        space_(env_->action_space()),
        exploration_(resolve_exploration(c, space_)),
        obs_dim_(env_->observation_size()),
        width_(space_.output_width()),
        ddpg_(obs_dim_, space_, c.ddpg, mix_seeds(c.seed, 1)),
        backend_(make_update_backend(ddpg_, c.ddpg.device)),
        replay_(c.replay.capacity, obs_dim_, width_),
        explore_(space_, exploration_, mix_seeds(c.seed, 2)),
        demo_(c.demo_shot),
        sample_rng_(mix_seeds(c.seed, 3)),
        batch_(obs_dim_, width_, c.ddpg.batch_size),
        episode_(env_->max_episode_steps(), obs_dim_, width_),
        obs_(static_cast<size_t>(obs_dim_)),
        next_obs_(static_cast<size_t>(obs_dim_)),
        net_out_(static_cast<size_t>(width_)),
        stored_(static_cast<size_t>(width_)) {
    if (c.ddpg.demo_bc_weight > 0.0) {
      cpu_backend_ = dynamic_cast<CpuUpdateBackend*>(backend_.get());
      if (cpu_backend_ == nullptr) {
        throw std::logic_error("train: cloning demonstrations needs the CPU update backend");
      }
      demo_replay_.emplace(c.replay.capacity, obs_dim_, width_);
      demo_batch_.emplace(obs_dim_, width_, c.ddpg.batch_size);
      if (c.exploration.demo_relabel) {
        labelled_.emplace(env_->max_episode_steps(), obs_dim_, width_);
        label_.resize(static_cast<size_t>(width_));
      }
    }
  }

  TrainSummary run();

 private:
  void resume();
  void save();
  void log_tick(bool force);
  void run_eval();
  void save_best();
  // The scripted offense's action for obs_ as an actor output (score 1 for its action, -1 for
  // the others, its parameters; the other parameters are the actor's own, net_out_).
  int demo_action(std::span<float> out);
  // A full sampled batch as the update reads it (no copy).
  [[nodiscard]] BatchView view_of(const BatchBuffers& b) const;
  [[nodiscard]] bool should_stop() const;
  [[nodiscard]] double elapsed() const {
    return base_seconds_ + std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

  ExperimentConfig c_;
  TrainOptions o_;
  std::unique_ptr<Env> env_;
  std::unique_ptr<Env> eval_env_;
  const ActionSpace& space_;
  ExplorationConfig exploration_;
  int obs_dim_;
  int width_;
  Ddpg ddpg_;
  // Runs the updates (CPU or GPU). With the GPU the host actor that acts here is refreshed from
  // the device every cluster.publish_every_updates updates (the staleness distributed actors
  // see) and at every episode end, a schedule fixed by update and episode counts, so a resumed
  // run still replays the same actions; on the CPU every sync is a no-op.
  std::unique_ptr<UpdateBackend> backend_;
  ReplayBuffer replay_;
  // With ddpg.demo_bc_weight > 0: the demonstrated transitions again, kept for cloning (they
  // also go into replay_), and the backend, which is then the CPU one.
  std::optional<ReplayBuffer> demo_replay_;
  std::optional<BatchBuffers> demo_batch_;
  // With exploration.demo_relabel: the agent's steps of the running episode with the scripted
  // offense's action in place of the agent's, flushed into demo_replay_ at its end.
  std::optional<EpisodeBuffer> labelled_;
  std::vector<float> label_;
  CpuUpdateBackend* cpu_backend_ = nullptr;
  EpsilonGreedy explore_;
  hfo::ScriptedOffense demo_;  // plays exploration.demo_fraction of the episodes
  Rng sample_rng_;
  BatchBuffers batch_;
  EpisodeBuffer episode_;
  std::vector<float> obs_, next_obs_, net_out_, stored_;

  int64_t env_steps_ = 0;
  int64_t episodes_ = 0;
  double update_credit_ = 0.0;
  double base_seconds_ = 0.0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  RecentEpisodes recent_;
  UpdateStats last_stats_;
  EvalResult last_eval_;
  bool have_eval_ = false;
  int64_t next_eval_ = 0;
  double last_checkpoint_ = 0.0;
  double last_log_ = 0.0;
  int64_t log_updates_ = 0;
  int64_t log_steps_ = 0;
  std::optional<RunLogs> logs_;
  std::optional<BestEval> best_;
  std::optional<ProgressBar> bar_;
};

void Trainer::resume() {
  const std::string ck = (fs::path(o_.run_dir) / "checkpoint.ckpt").string();
  const CheckpointMeta meta = load_checkpoint(ck, ddpg_);
  backend_->load_from_host();
  if (meta.rng_states.size() != 2) {
    throw std::runtime_error("checkpoint '" + ck + "' holds " + std::to_string(meta.rng_states.size()) +
                             " random streams; a train run writes 2");
  }
  explore_.rng().set_state(meta.rng_states[0]);
  sample_rng_.set_state(meta.rng_states[1]);
  env_steps_ = meta.env_steps;
  episodes_ = meta.episodes;
  update_credit_ = meta.update_credit;
  base_seconds_ = meta.elapsed_seconds;
  load_replay_snapshot((fs::path(o_.run_dir) / "replay.bin").string(), replay_);
  if (demo_replay_) {
    load_replay_snapshot((fs::path(o_.run_dir) / "demo_replay.bin").string(), *demo_replay_);
  }
}

void Trainer::save() {
  CheckpointMeta meta;
  meta.config_toml = to_toml(c_);
  meta.env_steps = env_steps_;
  meta.episodes = episodes_;
  meta.elapsed_seconds = elapsed();
  meta.update_credit = update_credit_;
  meta.rng_states = {explore_.rng().state(), sample_rng_.state()};
  // Replay first: a checkpoint on disk always has a replay snapshot at least as new.
  save_replay_snapshot((fs::path(o_.run_dir) / "replay.bin").string(), replay_);
  if (demo_replay_) {
    save_replay_snapshot((fs::path(o_.run_dir) / "demo_replay.bin").string(), *demo_replay_);
  }
  backend_->sync_to_host();
  save_checkpoint((fs::path(o_.run_dir) / "checkpoint.ckpt").string(), ddpg_, meta);
  last_checkpoint_ = elapsed();
}

bool Trainer::should_stop() const {
  if (o_.stop != nullptr && o_.stop->load()) {
    return true;
  }
  if (ddpg_.updates() >= c_.train.max_updates) {
    return true;
  }
  if (c_.train.max_episodes > 0 && episodes_ >= c_.train.max_episodes) {
    return true;
  }
  return c_.train.max_seconds > 0.0 && elapsed() >= c_.train.max_seconds;
}

void Trainer::run_eval() {
  if (c_.train.eval_episodes <= 0) {
    return;
  }
  backend_->sync_actor_to_host();
  GreedyActorPolicy policy(ddpg_, space_, exploration_, evaluated_copy(ddpg_));
  last_eval_ = evaluate(*eval_env_, policy, c_.train.eval_episodes, screening_seed(c_.seed, ddpg_.updates()));
  have_eval_ = true;
  if (o_.metrics != nullptr) {
    o_.metrics->on_eval(last_eval_);
  }
  if (!best_) {
    return;
  }
  std::function<EvalResult()> confirm;
  if (c_.train.confirm_episodes > 0) {
    confirm = [&] {
      return evaluate(*eval_env_, policy, c_.train.confirm_episodes, confirmation_seed(c_.seed, ddpg_.updates()));
    };
  }
  if (best_->offer(last_eval_, ddpg_.updates(), confirm)) {
    save_best();
  }
}

// The actor (with everything else) of the best greedy evaluation so far: what `pamdp eval
// --checkpoint RUN/best.ckpt` should be given when the final policy is worse than an earlier one.
void Trainer::save_best() {
  CheckpointMeta meta;
  meta.config_toml = to_toml(c_);
  meta.env_steps = env_steps_;
  meta.episodes = episodes_;
  meta.elapsed_seconds = elapsed();
  meta.update_credit = update_credit_;
  meta.rng_states = {explore_.rng().state(), sample_rng_.state()};
  backend_->sync_to_host();
  save_checkpoint((fs::path(o_.run_dir) / "best.ckpt").string(), ddpg_, meta);
}

void Trainer::log_tick(bool force) {
  const double now = elapsed();
  if (!force && now - last_log_ < c_.train.log_every_seconds) {
    return;
  }
  const double dt = std::max(1e-9, now - last_log_);
  const double ups = static_cast<double>(ddpg_.updates() - log_updates_) / dt;
  const double sps = static_cast<double>(env_steps_ - log_steps_) / dt;
  last_log_ = now;
  log_updates_ = ddpg_.updates();
  log_steps_ = env_steps_;
  const double eps = linear_epsilon(ddpg_.updates(), exploration_.epsilon_start, exploration_.epsilon_end,
                                    exploration_.epsilon_anneal_updates);
  MetricsRow row;
  row.wall_seconds = now;
  row.updates = ddpg_.updates();
  row.env_steps = env_steps_;
  row.episodes = episodes_;
  row.epsilon = eps;
  row.success_rate_100 = recent_.success_rate();
  row.mean_return_100 = recent_.mean_return();
  row.mean_steps_100 = recent_.mean_steps();
  row.critic_loss = last_stats_.critic_loss;
  row.q_mean = last_stats_.q_mean;
  row.updates_per_s = ups;
  row.env_steps_per_s = sps;
  if (have_eval_) {
    row.eval = last_eval_;
  }
  const std::array<double, 2> bc{last_stats_.bc_accepted_fraction, last_stats_.bc_loss};
  // Flushes the episode log too, so a killed run keeps it up to this row.
  logs_->metrics(row, demo_replay_ ? std::span<const double>(bc) : std::span<const double>{});
  if (!o_.quiet) {
    if (bar_) {
      bar_->clear();
    }
    std::printf(
        "[%7.1fs] updates %lld | episodes %lld | success(last %zu) %.2f | return %.3f | eps %.3f | loss %.4g | Q %.3f "
        "| "
        "%.0f updates/s | %.0f steps/s",
        now, static_cast<long long>(ddpg_.updates()), static_cast<long long>(episodes_), recent_.size(),
        recent_.success_rate(), recent_.mean_return(), eps, static_cast<double>(last_stats_.critic_loss),
        static_cast<double>(last_stats_.q_mean), ups, sps);
    if (have_eval_) {
      std::printf(" | eval %.2f", last_eval_.goal_rate);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
}

// The scripted offense's action for obs_, written into stored_ as the actor's output vector would
// carry it: score 1 for its action and -1 for the others, its parameters, and the actor's own
// output (net_out_) for the parameters of the other actions. Returns the action id.
BatchView Trainer::view_of(const BatchBuffers& b) const {
  const int B = c_.ddpg.batch_size;
  return {
      Eigen::Map<const Eigen::MatrixXf>(b.states.data(), obs_dim_, B),
      Eigen::Map<const Eigen::MatrixXf>(b.actions.data(), width_, B),
      Eigen::Map<const Eigen::VectorXf>(b.rewards.data(), B),
      Eigen::Map<const Eigen::MatrixXf>(b.next_states.data(), obs_dim_, B),
      Eigen::Map<const Eigen::VectorXf>(b.terminal.data(), B),
      Eigen::Map<const Eigen::VectorXf>(b.mc_returns.data(), B),
  };
}

int Trainer::demo_action(std::span<float> out) {
  const ParamAction a = demo_.act(obs_);
  const int num_actions = space_.num_actions();
  std::copy(net_out_.begin(), net_out_.end(), out.begin());
  for (int k = 0; k < num_actions; ++k) {
    out[static_cast<size_t>(k)] = k == a.id ? 1.0F : -1.0F;
  }
  for (const int p : space_.actions[static_cast<size_t>(a.id)].param_indices) {
    out[static_cast<size_t>(num_actions + p)] = a.params[static_cast<size_t>(p)];
  }
  return a.id;
}

TrainSummary Trainer::run() {
  fs::create_directories(o_.run_dir);
  const fs::path dir(o_.run_dir);
  if (o_.resume) {
    resume();
  } else {
    if (!c_.train.init_from.empty()) {
      warm_start_from_checkpoint(c_.train.init_from, ddpg_);
      backend_->load_from_host();
      log::info("train: networks warm-started from {}", c_.train.init_from);
    }
    const std::string text = to_toml(c_);
    write_file_atomically((dir / "config.toml").string(), text.data(), text.size());
  }
  if (ddpg_.averages_actor()) {
    log::info("train: evaluations and best.ckpt play the actor average (ddpg.actor_average_tau = {})",
              c_.ddpg.actor_average_tau);
  }
  std::optional<ResumePoint> resume_at;
  if (o_.resume) {
    resume_at = ResumePoint{static_cast<int64_t>(ddpg_.updates()), static_cast<int64_t>(episodes_)};
  }
  // With cloning, metrics.csv also says how much of it the Q-filter lets through.
  logs_.emplace(dir,
                demo_replay_ ? std::vector<std::string>{"bc_accepted_fraction", "bc_loss"} : std::vector<std::string>{},
                resume_at);
  if (o_.resume) {
    // The last-100 training rates go on from the episodes logged before the checkpoint, the
    // scripted offense's left out as in run().
    const std::string_view success = env_->status_name(env_->success_status());
    for (const LoggedEpisode& e : last_logged_episodes(dir, 1000)) {
      if (!e.scripted) {
        recent_.add(e.ret, e.steps, e.outcome == success);
      }
    }
  }
  best_.emplace(dir / "best_eval.txt");
  if (!o_.quiet) {
    bar_.emplace("updates", c_.train.max_updates);
  }
  start_ = std::chrono::steady_clock::now();
  last_log_ = last_checkpoint_ = base_seconds_;
  log_updates_ = ddpg_.updates();
  log_steps_ = env_steps_;
  const int64_t every = c_.train.eval_every_updates;
  next_eval_ = every > 0 ? (ddpg_.updates() / every + 1) * every : INT64_MAX;
  const int num_actions = space_.num_actions();

  while (!should_stop()) {
    // One episode.
    env_->reset(mix_seeds(c_.seed, 100000 + static_cast<uint64_t>(episodes_)), obs_);
    episode_.clear();
    // The draw is skipped when demonstrations are off, so runs without them keep their streams.
    const double share = demo_share(ddpg_.updates(), exploration_.demo_fraction, exploration_.demo_anneal_updates);
    const bool demo = share > 0.0 && explore_.rng().uniform() < share;
    const bool label = labelled_ && !demo;  // the agent plays, its steps get the teacher's labels
    if (demo || label) {
      demo_.begin_episode();
    }
    float ep_return = 0.0F;
    int steps = 0;
    StepResult sr;
    do {
      const double eps = linear_epsilon(ddpg_.updates(), exploration_.epsilon_start, exploration_.epsilon_end,
                                        exploration_.epsilon_anneal_updates);
      ddpg_.act(obs_, net_out_);
      const int id = demo ? demo_action(stored_) : explore_.select(net_out_, eps, stored_);
      if (label) {
        demo_action(label_);  // before the step: the label is for the state the agent acted in
      }
      sr = env_->step({id, std::span<const float>(stored_).subspan(static_cast<size_t>(num_actions))}, next_obs_);
      episode_.push(obs_, stored_, sr.reward, next_obs_);
      if (label) {
        labelled_->push(obs_, label_, sr.reward, next_obs_);
      }
      ep_return += sr.reward;
      ++steps;
      ++env_steps_;
      if (o_.metrics != nullptr) {
        o_.metrics->on_step(eps);
      }
      std::swap(obs_, next_obs_);

      update_credit_ += c_.train.updates_per_step;
      // Limits are checked at episode ends only (see should_stop), so a run stopped at N updates
      // and resumed passes through exactly the states of a run that never stopped.
      while (update_credit_ >= 1.0 && replay_.size() >= c_.replay.warmup) {
        replay_.sample(sample_rng_, c_.ddpg.batch_size, batch_);
        const int B = c_.ddpg.batch_size;
        if (demo_replay_ && demo_replay_->size() > 0) {
          demo_replay_->sample(sample_rng_, B, *demo_batch_);
          last_stats_ = cpu_backend_->update(view_of(batch_), view_of(*demo_batch_));
        } else {
          last_stats_ = backend_->update(view_of(batch_));
        }
        if (o_.metrics != nullptr) {
          o_.metrics->on_update(last_stats_, ddpg_.updates(), B);
        }
        update_credit_ -= 1.0;
        if (ddpg_.updates() % std::max<int64_t>(1, c_.cluster.publish_every_updates) == 0) {
          backend_->sync_actor_to_host();
        }
      }
      if (replay_.size() < c_.replay.warmup) {
        update_credit_ = std::min(update_credit_, 1.0);  // no debt piles up during warm-up
      }
      log_tick(false);
    } while (!sr.terminal() && static_cast<size_t>(steps) < episode_.capacity());

    flush_episode(episode_, c_.ddpg.gamma, replay_, demo && demo_replay_ ? &*demo_replay_ : nullptr);
    if (label) {
      flush_episode(*labelled_, c_.ddpg.gamma, *demo_replay_);
    }
    backend_->sync_actor_to_host();
    ++episodes_;
    const bool success = sr.status == env_->success_status();
    if (!demo) {  // the training rates are the agent's own
      recent_.add(ep_return, steps, success);
    }
    if (o_.metrics != nullptr) {
      o_.metrics->on_episode(sr.status, ep_return, steps, static_cast<int64_t>(replay_.size()), !demo);
    }
    EpisodeRow ep;
    ep.episode = episodes_;
    ep.wall_seconds = elapsed();
    ep.updates = ddpg_.updates();
    ep.ret = ep_return;
    ep.steps = steps;
    ep.outcome = env_->status_name(sr.status);
    // One process: always the newest weights; none (0) for an episode the scripted offense played.
    ep.weights_version = demo ? 0 : static_cast<uint64_t>(ddpg_.updates());
    ep.scripted = demo;
    logs_->episode(ep);
    if (bar_) {
      bar_->update(ddpg_.updates());
    }
    if (ddpg_.updates() >= next_eval_) {
      run_eval();
      next_eval_ += c_.train.eval_every_updates;
      log_tick(true);
    }
    if (c_.train.checkpoint_every_seconds > 0.0 && elapsed() - last_checkpoint_ >= c_.train.checkpoint_every_seconds) {
      save();
    }
  }
  save();
  if (bar_) {
    bar_->finish();
  }
  logs_->flush();
  TrainSummary s;
  run_eval();
  if (have_eval_) {
    s.final_eval = last_eval_;
  }
  log_tick(true);
  s.updates = ddpg_.updates();
  s.env_steps = env_steps_;
  s.episodes = episodes_;
  s.seconds = elapsed();
  return s;
}

}  // namespace

TrainSummary train(const ExperimentConfig& config, const TrainOptions& options) {
  Trainer t(config, options);
  return t.run();
}

}  // namespace pamdp::app
