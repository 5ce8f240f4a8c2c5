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

#include "actor/episode_player.hpp"
#include "actor/exploration.hpp"
#include "app/env_factory.hpp"
#include "app/progress.hpp"
#include "app/role_metrics.hpp"
#include "app/run_support.hpp"
#include "core/log.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/hfo/settings.hpp"
#include "learner/algorithm.hpp"
#include "learner/checkpoint.hpp"
#include "learner/sampler.hpp"
#include "learner/training_run.hpp"
#include "replay/episode_buffer.hpp"
#include "replay/replay_buffer.hpp"
#include "replay/replay_snapshot.hpp"

namespace pamdp::app {
namespace {

namespace fs = std::filesystem;

// The teachers of demonstrations and labels, one per player (the config check refuses
// demonstrations on an env whose features they cannot read).
std::vector<std::unique_ptr<Policy>> make_teachers(const ExperimentConfig& c, const Env& env) {
  std::vector<std::unique_ptr<Policy>> out;
  for (int i = 0; i < env.agents(); ++i) {
    out.push_back(make_teacher(c));
  }
  return out;
}

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
        algorithm_(make_learner(c, obs_dim_, space_, mix_seeds(c.seed, 1))),
        replay_(c.replay.capacity, obs_dim_, width_),
        explore_(space_, exploration_, mix_seeds(c.seed, 2)),
        teachers_(make_teachers(c, *env_)),
        sample_rng_(mix_seeds(c.seed, 3)),
        player_(*env_, teachers_, algorithm_->clones_demonstrations() && c.exploration.demo_relabel),
        act_([this](std::span<const float> obs, std::span<float> out) { algorithm_->act(obs, out); }),
        run_(run_spec(c, o_.run_dir, exploration_, algorithm_->clones_demonstrations()), *algorithm_, *env_,
             *eval_env_) {
    if (algorithm_->clones_demonstrations()) {
      demo_replay_.emplace(c.replay.capacity, obs_dim_, width_);
    }
    sampler_.emplace(replay_, demo_replay_ ? &*demo_replay_ : nullptr, sample_rng_, c.ddpg.batch_size, c.replay.warmup);
  }

  TrainSummary run();

 private:
  static RunSpec run_spec(const ExperimentConfig& c, const std::string& dir, const ExplorationConfig& exploration,
                          bool clones) {
    RunSpec spec;
    spec.dir = dir;
    spec.role = "train";
    spec.config_toml = to_toml(c);
    spec.seed = c.seed;
    spec.loop = c.train;
    spec.exploration = exploration;
    // With cloning, metrics.csv also says how much of it the Q-filter lets through.
    if (clones) {
      spec.extra_metric_columns = {"bc_accepted_fraction", "bc_loss"};
    }
    return spec;
  }
  void log_tick(bool force);
  [[nodiscard]] bool should_stop() const;

  ExperimentConfig c_;
  TrainOptions o_;
  std::unique_ptr<Env> env_;
  std::unique_ptr<Env> eval_env_;
  const ActionSpace& space_;
  ExplorationConfig exploration_;
  int obs_dim_;
  int width_;
  // The learner (train.algorithm), updating on the CPU or GPU. With the GPU the host policy that
  // acts here is refreshed from the device every cluster.publish_every_updates updates (the
  // staleness distributed actors see) and at every episode end, a schedule fixed by update and
  // episode counts, so a resumed run still replays the same actions; on the CPU every sync is a
  // no-op.
  std::unique_ptr<Algorithm> algorithm_;
  ReplayBuffer replay_;
  // When the learner clones (ddpg.demo_bc_weight > 0): the demonstrated transitions again, and
  // with exploration.demo_relabel the agent's steps labelled with the scripted offense's actions,
  // kept for cloning (the demonstrations also go into replay_).
  std::optional<ReplayBuffer> demo_replay_;
  EpsilonGreedy explore_;
  // The scripted offense (one per player of a team) plays exploration.demo_fraction of the
  // episodes and labels with demo_relabel.
  std::vector<std::unique_ptr<Policy>> teachers_;
  Rng sample_rng_;
  std::optional<LocalSampler> sampler_;  // the updates' minibatches: replay_, and demo_replay_ to clone
  EpisodePlayer player_;                 // the episodes, played as the actors play them
  EpisodePlayer::Act act_;               // the learner's acting networks

  double update_credit_ = 0.0;
  TrainingRun run_;  // last: built from the members above
  std::optional<ProgressBar> bar_;
};

bool Trainer::should_stop() const {
  if (o_.stop != nullptr && o_.stop->load()) {
    return true;
  }
  if (algorithm_->updates() >= c_.train.max_updates) {
    return true;
  }
  if (c_.train.max_episodes > 0 && run_.episodes() >= c_.train.max_episodes) {
    return true;
  }
  return c_.train.max_seconds > 0.0 && run_.elapsed() >= c_.train.max_seconds;
}

void Trainer::log_tick(bool force) {
  if (!force && run_.elapsed() - run_.last_row_seconds() < c_.train.log_every_seconds) {
    return;
  }
  const MetricsRow row = run_.next_metrics_row();
  const UpdateStats& last = run_.last_update();
  const std::array<double, 2> bc{last.bc_accepted_fraction, last.bc_loss};
  // Flushes the episode log too, so a killed run keeps it up to this row.
  run_.logs().metrics(row, demo_replay_ ? std::span<const double>(bc) : std::span<const double>{});
  if (!o_.quiet) {
    if (bar_) {
      bar_->clear();
    }
    const RecentEpisodes& recent = run_.recent();
    std::printf(
        "[%7.1fs] updates %lld | episodes %lld | success(last %zu) %.2f | return %.3f | eps %.3f | loss %.4g | Q %.3f "
        "| %.0f updates/s | %.0f steps/s",
        row.wall_seconds, static_cast<long long>(row.updates), static_cast<long long>(row.episodes), recent.size(),
        recent.success_rate(), recent.mean_return(), *row.epsilon, row.critic_loss, row.q_mean, row.updates_per_s,
        row.env_steps_per_s);
    if (row.eval) {
      std::printf(" | eval %.2f", row.eval->goal_rate);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
}

TrainSummary Trainer::run() {
  run_.on_eval = [this](const EvalResult& r) {
    if (o_.metrics != nullptr) {
      o_.metrics->on_eval(r);
    }
  };
  run_.on_save = [this](CheckpointMeta& meta) {
    meta.update_credit = update_credit_;
    meta.rng_states = {explore_.rng().state(), sample_rng_.state()};
  };
  // Replay first: a checkpoint on disk always has a replay snapshot at least as new.
  const fs::path dir(o_.run_dir);
  run_.before_checkpoint = [this, dir] {
    save_replay_snapshot((dir / "replay.bin").string(), replay_);
    if (demo_replay_) {
      save_replay_snapshot((dir / "demo_replay.bin").string(), *demo_replay_);
    }
  };
  // best.ckpt played again (train.recheck_best): the run's own learner, its weights from the file.
  run_.make_incumbent = [this] { return make_learner(c_, obs_dim_, space_, c_.seed, UpdateDevice::kCpu); };
  if (o_.resume) {
    // The replay snapshots first: one that does not fit this run's memory is refused before
    // start() touches the run directory (a resume that changed the config rewrites config.toml).
    const auto restore = [](const fs::path& file, ReplayBuffer& buffer) {
      try {
        load_replay_snapshot(file.string(), buffer);
      } catch (const std::runtime_error& e) {
        // The memory's shape comes from replay.capacity and the env: only a --set can change them.
        if (std::string(e.what()).find("was written for capacity") == std::string::npos) {
          throw;
        }
        throw std::runtime_error(std::string(e.what()) +
                                 "; a resumed run keeps the replay.capacity and env settings it began with: resume "
                                 "without the --set that changed them (config.toml has the run's own), or start a "
                                 "new run with another --run-dir");
      }
    };
    restore(dir / "replay.bin", replay_);
    if (demo_replay_) {
      restore(dir / "demo_replay.bin", *demo_replay_);
    }
  }
  const CheckpointMeta meta = run_.start(o_.resume);
  if (o_.resume) {
    const std::string ck = (dir / "checkpoint.ckpt").string();
    if (meta.rng_states.size() != 2) {
      throw std::runtime_error("checkpoint '" + ck + "' holds " + std::to_string(meta.rng_states.size()) +
                               " random streams; a train run writes 2");
    }
    explore_.rng().set_state(meta.rng_states[0]);
    sample_rng_.set_state(meta.rng_states[1]);
    update_credit_ = meta.update_credit;
  }
  if (!o_.quiet) {
    bar_.emplace("updates", c_.train.max_updates);
  }
  while (!should_stop()) {
    // One episode. The demonstration draw is skipped when demonstrations are off, so runs
    // without them keep their streams.
    env_->set_training_updates(algorithm_->updates());
    player_.begin(mix_seeds(c_.seed, 100000 + static_cast<uint64_t>(run_.episodes())),
                  demo_share(algorithm_->updates(), exploration_.demo_fraction, exploration_.demo_anneal_updates,
                             exploration_.demo_fraction_end),
                  explore_.rng());
    int status = 0;
    do {
      const double eps = linear_epsilon(algorithm_->updates(), exploration_.epsilon_start, exploration_.epsilon_end,
                                        exploration_.epsilon_anneal_updates);
      status = player_.step(act_, explore_, eps).status;
      // A team's cycle is one decision step per player, each a transition.
      run_.record_env_steps(player_.players());
      if (o_.metrics != nullptr) {
        for (int i = 0; i < player_.players(); ++i) {
          o_.metrics->on_step(eps);
        }
      }

      update_credit_ += c_.train.updates_per_step * player_.players();
      // Limits are checked at episode ends only (see should_stop), so a run stopped by a signal,
      // train.max_seconds or train.max_episodes and resumed passes through exactly the states of
      // a run that never stopped. train.max_updates is a count, not a time: no update past it,
      // while the episode it falls in plays to its end.
      while (update_credit_ >= 1.0 && algorithm_->updates() < c_.train.max_updates && run_.update(*sampler_)) {
        if (o_.metrics != nullptr) {
          o_.metrics->on_update(run_.last_update(), algorithm_->updates(), c_.ddpg.batch_size);
        }
        update_credit_ -= 1.0;
        if (algorithm_->updates() % std::max<int64_t>(1, c_.cluster.publish_every_updates) == 0) {
          algorithm_->sync_acting();
        }
      }
      if (replay_.size() < c_.replay.warmup) {
        update_credit_ = std::min(update_credit_, 1.0);  // no debt piles up during warm-up
      }
      log_tick(false);
    } while (!player_.ended());

    const bool demo = player_.demo();
    for (int i = 0; i < player_.players(); ++i) {  // a team's players, each its own episode
      flush_episode(player_.episode(i), c_.ddpg.gamma, replay_, demo && demo_replay_ ? &*demo_replay_ : nullptr);
      if (EpisodeBuffer* labels = player_.labels(i)) {
        flush_episode(*labels, c_.ddpg.gamma, *demo_replay_);
      }
    }
    algorithm_->sync_acting();
    if (o_.metrics != nullptr) {
      o_.metrics->on_episode(status, player_.episode_return(), player_.steps(), static_cast<int64_t>(replay_.size()),
                             !demo);
    }
    // One process: always the newest weights; none (0) for an episode the scripted offense played.
    run_.record_episode({status, player_.episode_return(), player_.steps(), 0,
                         demo ? 0 : static_cast<uint64_t>(algorithm_->updates()), demo});
    if (bar_) {
      bar_->update(algorithm_->updates());
    }
    if (run_.evaluate_if_due()) {
      log_tick(true);
    }
    if (run_.checkpoint_due()) {
      run_.save();
    }
  }
  run_.finish();
  if (bar_) {
    bar_->finish();
  }
  TrainSummary s;
  // The final evaluation, unless the loop's last episode ended with one at this very update
  // (and its row): a second would repeat it, and its row would read 0 updates/s.
  if (!run_.last_eval() || run_.last_eval_updates() != algorithm_->updates()) {
    run_.evaluate();
    log_tick(true);
  }
  if (run_.last_eval()) {
    s.final_eval = *run_.last_eval();
  }
  s.updates = algorithm_->updates();
  s.env_steps = run_.env_steps();
  s.episodes = run_.episodes();
  s.seconds = run_.elapsed();
  return s;
}

}  // namespace

TrainSummary train(const ExperimentConfig& config, const TrainOptions& options) {
  Trainer t(config, options);
  return t.run();
}

}  // namespace pamdp::app
