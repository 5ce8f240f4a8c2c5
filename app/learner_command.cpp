// `pamdp learner`: the learner process of the distributed system (docs/protocol.md).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/actor_policy.hpp"
#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "app/network_security.hpp"
#include "app/role_metrics.hpp"
#include "app/run_logs.hpp"
#include "app/run_options.hpp"
#include "app/run_support.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/transport.hpp"
#include "learner/checkpoint.hpp"
#include "learner/evaluation.hpp"
#include "learner/learner_server.hpp"
#include "learner/update_backend.hpp"

namespace pamdp::app {
namespace {

namespace fs = std::filesystem;

LearnerServer* g_server = nullptr;
extern "C" void on_learner_signal(int /*sig*/) {
  if (g_server != nullptr) {
    g_server->stop();
  }
}

using LearnerCliOptions = RunCliOptions;

void run_learner(const LearnerCliOptions& o) {
  ExperimentConfig c;
  std::string run_dir;
  const bool resume = !o.resume.empty();
  if (resume) {
    if (!o.config.empty()) {
      throw std::runtime_error("--resume uses the config saved in the run directory; drop --config");
    }
    run_dir = o.resume;
    if (!fs::exists(fs::path(run_dir) / "config.toml") || !fs::exists(fs::path(run_dir) / "checkpoint.ckpt")) {
      throw std::runtime_error("--resume " + run_dir + ": no config.toml and checkpoint.ckpt there");
    }
    c = load_experiment_config((fs::path(run_dir) / "config.toml").string(), o.sets);
  } else {
    c = load_experiment_config(o.config, o.sets);
    if (o.seed >= 0) {
      c.seed = static_cast<uint64_t>(o.seed);
    }
    if (o.run_dir.empty()) {
      run_dir = timestamped_run_dir("cluster-seed" + std::to_string(c.seed));
    } else {
      run_dir = o.run_dir;
    }
    if (fs::exists(fs::path(run_dir) / "checkpoint.ckpt")) {
      throw std::runtime_error("run directory '" + run_dir + "' already holds a run; use --resume " + run_dir);
    }
  }
  if (c.exploration.demo_fraction > 0.0) {
    throw std::runtime_error(
        "exploration.demo_fraction = " + std::to_string(c.exploration.demo_fraction) +
        ": demonstrations are played by pamdp train only, the cluster's actors do not play them; set "
        "exploration.demo_fraction = 0 (--set exploration.demo_fraction=0) or train with pamdp train");
  }
  // Before anything is written or bound: no cluster socket on the network without CURVE unless
  // asked for.
  const SecurityOptions security{
      "learner",
      "--set cluster.curve=true --set cluster.curve_keys_dir=keys here and --curve-keys keys on every "
      "pamdp replay and pamdp actor",
      "--set cluster.insecure=true here and --insecure on every pamdp replay and pamdp actor",
      "bind tcp://127.0.0.1:PORT (the default)"};
  const std::vector<ClusterEndpoint> binds{{"cluster.learner_bind", c.cluster.learner_bind},
                                           {"cluster.weights_bind", c.cluster.weights_bind}};
  const bool insecure = check_network_exposure(security, binds, c.cluster.curve, c.cluster.insecure);
  check_advertise_host(security, "cluster.advertise_host", c.cluster.advertise_host, binds);
  fs::create_directories(run_dir);
  const std::string config_text = to_toml(c);
  if (!resume) {
    write_file_atomically((fs::path(run_dir) / "config.toml").string(), config_text.data(), config_text.size());
  }

  auto env = make_env(c.env);
  auto eval_env = make_eval_env(c);
  const ExplorationConfig exploration = resolve_exploration(c, env->action_space());
  Ddpg ddpg(env->observation_size(), env->action_space(), c.ddpg, c.seed);
  CheckpointMeta meta;
  if (resume) {
    meta = load_checkpoint((fs::path(run_dir) / "checkpoint.ckpt").string(), ddpg);
  } else if (!c.train.init_from.empty()) {
    warm_start_from_checkpoint(c.train.init_from, ddpg);
    log::info("learner: networks warm-started from {}", c.train.init_from);
  }
  meta.config_toml = config_text;
  if (ddpg.averages_actor()) {
    log::info("learner: evaluations and best.ckpt play the actor average (ddpg.actor_average_tau = {})",
              c.ddpg.actor_average_tau);
  }
  // Built after the checkpoint is loaded: a GPU backend starts from the host state.
  const std::unique_ptr<UpdateBackend> backend = make_update_backend(ddpg, c.ddpg.device);

  LearnerServerConfig sc;
  sc.join_bind = c.cluster.learner_bind;
  sc.weights_bind = c.cluster.weights_bind;
  sc.advertise_host = c.cluster.advertise_host;
  sc.config_toml = config_text;
  sc.publish_every_updates = c.cluster.publish_every_updates;
  sc.requests_in_flight_per_shard = c.cluster.requests_in_flight_per_shard;
  sc.heartbeat_ms = c.cluster.heartbeat_ms;
  sc.peer_timeout_ms = c.cluster.peer_timeout_ms;
  sc.max_updates = c.train.max_updates;
  sc.max_seconds = c.train.max_seconds;
  sc.weights_version = meta.weights_version;
  o.apply_metrics_overrides(c);
  MetricsEndpoint endpoint("learner", "learner", c.metrics.bind, c.metrics.port, c.cluster.advertise_host);
  LearnerMetrics learner_metrics(endpoint.registry(), *env, exploration);
  export_security_mode(endpoint.registry(), security, insecure, binds);
  sc.metrics_url = endpoint.url();

  net::Context ctx;
  std::unique_ptr<net::CurveAuthenticator> auth;  // before the server: outlives its sockets
  if (c.cluster.curve) {
    const net::CurveKeyring keys = net::load_curve_keyring(c.cluster.curve_keys_dir, /*need_server=*/true);
    sc.curve = keys.server;
    sc.curve_client = keys.client;
    auth = std::make_unique<net::CurveAuthenticator>(ctx, std::vector<std::string>{keys.client.public_key});
  }
  LearnerServer server(ctx, *backend, sc);
  g_server = &server;
  std::signal(SIGINT, on_learner_signal);
  std::signal(SIGTERM, on_learner_signal);

  // Resumed: the metrics rows past the checkpoint go (the resumed learner redoes those updates and
  // logs them again); the episode rows stay (see below).
  std::optional<ResumePoint> resume_at;
  if (resume) {
    resume_at = ResumePoint{static_cast<int64_t>(ddpg.updates()), std::nullopt};
  }
  RunLogs logs(
      run_dir,
      {"samples_per_s", "shards", "actors_joined", "weights_version", "malformed_messages", "waiting_for_data_ms"},
      resume_at);
  BestEval best(fs::path(run_dir) / "best_eval.txt", "learner");

  RecentEpisodes recent;
  int64_t episode_count = meta.episodes;
  int64_t env_steps = meta.env_steps;  // steps of the episodes reported so far
  // The run's clock goes on from the last episode logged, which a learner killed after its
  // checkpoint logged later than the checkpoint's time: episodes.csv's wall_seconds never go back.
  double logged_seconds = meta.elapsed_seconds;
  if (resume) {
    // One pass over episodes.csv. The last-100 training rates go on from the episodes logged
    // before. The episodes the actors reported after the last checkpoint were played, and their
    // transitions are in the replay shards: count them, and number the next episodes after them.
    const std::string_view success = env->status_name(env->success_status());
    int64_t after = 0;
    for_each_logged_episode(run_dir, [&](const LoggedEpisode& e) {
      recent.add(e.ret, e.steps, e.outcome == success);
      logged_seconds = std::max(logged_seconds, e.wall_seconds);
      if (e.episode > episode_count) {
        episode_count = e.episode;
        env_steps += e.steps;
        ++after;
      }
    });
    if (after > 0) {
      log::info("learner: {} episodes logged after the checkpoint are kept; episodes go on from {}", after,
                episode_count + 1);
    }
  }
  UpdateStats last_stats;
  EvalResult last_eval;
  bool have_eval = false;
  const auto start = std::chrono::steady_clock::now();
  const double base_seconds = logged_seconds;
  auto elapsed = [&] {
    return base_seconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  double last_checkpoint = elapsed();
  int64_t last_updates = ddpg.updates();
  int64_t last_samples = 0;
  double last_tick = elapsed();
  int64_t last_env_steps = env_steps;
  double last_print = -1e9;

  auto save = [&] {
    meta.elapsed_seconds = elapsed();
    meta.episodes = episode_count;
    meta.env_steps = env_steps;
    meta.weights_version = server.counters().weights_version;
    backend->sync_to_host();
    save_checkpoint((fs::path(run_dir) / "checkpoint.ckpt").string(), ddpg, meta);
    last_checkpoint = elapsed();
  };

  server.on_metrics_urls = [&](const std::vector<std::string>& urls) {
    write_metrics_urls((fs::path(run_dir) / "metrics_urls.txt").string(), urls);
  };
  server.on_episode = [&](const EpisodeSummary& e) {
    learner_metrics.on_episode(e);
    ++episode_count;
    const bool success = e.status == env->success_status();
    recent.add(e.ret, e.steps, success);
    env_steps += e.steps;
    EpisodeRow row;
    row.episode = episode_count;
    row.wall_seconds = elapsed();
    row.updates = ddpg.updates();
    row.actor = e.actor_id;
    row.ret = e.ret;
    row.steps = e.steps;
    row.outcome = env->status_name(e.status);
    row.weights_version = e.policy_version;
    logs.episode(row);
  };
  server.on_update = [&](const UpdateStats& s) {
    learner_metrics.on_update(s, ddpg.updates());
    last_stats = s;
    const int64_t every = c.train.eval_every_updates;
    if (every > 0 && c.train.eval_episodes > 0 && ddpg.updates() % every == 0) {
      backend->sync_actor_to_host();  // moves the actor average too, as the weight broadcasts do
      GreedyActorPolicy policy(ddpg, env->action_space(), exploration, evaluated_copy(ddpg));
      last_eval = evaluate(*eval_env, policy, c.train.eval_episodes, screening_seed(c.seed, ddpg.updates()));
      have_eval = true;
      learner_metrics.on_eval(last_eval);
      std::function<EvalResult()> confirm;
      if (c.train.confirm_episodes > 0) {
        confirm = [&] {
          return evaluate(*eval_env, policy, c.train.confirm_episodes, confirmation_seed(c.seed, ddpg.updates()));
        };
      }
      if (best.offer(last_eval, ddpg.updates(), confirm)) {
        CheckpointMeta best_meta = meta;
        best_meta.elapsed_seconds = elapsed();
        best_meta.episodes = episode_count;
        best_meta.env_steps = env_steps;
        backend->sync_to_host();
        save_checkpoint((fs::path(run_dir) / "best.ckpt").string(), ddpg, best_meta);
      }
    }
  };
  server.on_tick = [&](const LearnerCounters& k) {
    learner_metrics.on_tick(k, ddpg.updates(), server.metrics_urls().size());
    const double now = elapsed();
    const double dt = std::max(1e-9, now - last_tick);
    const double ups = static_cast<double>(ddpg.updates() - last_updates) / dt;
    const double sps = static_cast<double>(k.samples_received - last_samples) / dt;
    last_tick = now;
    last_updates = ddpg.updates();
    last_samples = k.samples_received;
    if (now - last_checkpoint >= c.train.checkpoint_every_seconds && c.train.checkpoint_every_seconds > 0) {
      save();
    }
    MetricsRow row;
    row.wall_seconds = now;
    row.updates = ddpg.updates();
    row.env_steps = env_steps;
    row.episodes = episode_count;
    // The schedule the weights carry (actors started with --apex-epsilon use their own fixed ε).
    row.epsilon = linear_epsilon(ddpg.updates(), exploration.epsilon_start, exploration.epsilon_end,
                                 exploration.epsilon_anneal_updates);
    row.success_rate_100 = recent.success_rate();
    row.mean_return_100 = recent.mean_return();
    row.mean_steps_100 = recent.mean_steps();
    row.critic_loss = last_stats.critic_loss;
    row.q_mean = last_stats.q_mean;
    row.updates_per_s = ups;
    row.env_steps_per_s = static_cast<double>(env_steps - last_env_steps) / dt;
    last_env_steps = env_steps;
    if (have_eval) {
      row.eval = last_eval;
    }
    const double extras[] = {sps,
                             static_cast<double>(k.shards),
                             static_cast<double>(k.actors_joined),
                             static_cast<double>(k.weights_version),
                             static_cast<double>(k.malformed_messages),
                             static_cast<double>(k.waiting_for_data_ms)};
    logs.metrics(row, extras);
    if (!o.quiet && now - last_print >= c.train.log_every_seconds) {
      last_print = now;
      std::printf(
          "[%7.1fs] updates %lld | episodes %lld | success(last %zu) %.2f | return %.3f | %.0f updates/s | %.0f "
          "samples/s | shards %lld | actors %lld | weights v%lld%s%s\n",
          now, static_cast<long long>(ddpg.updates()), static_cast<long long>(episode_count), recent.size(),
          recent.success_rate(), recent.mean_return(), ups, sps, static_cast<long long>(k.shards),
          static_cast<long long>(k.actors_joined), static_cast<long long>(k.weights_version),
          k.shards == 0 ? " | waiting: no replay shard has joined" : "",
          (k.shards > 0 && ups == 0.0) ? " | waiting: shards have too little data (warm-up / rate limit)" : "");
      std::fflush(stdout);
    }
  };

  if (!o.quiet) {
    std::printf("pamdp learner: env %s, run directory %s%s\n  join:    %s\n  weights: %s\n", c.env.name.c_str(),
                run_dir.c_str(), resume ? " (resumed)" : "", server.join_endpoint().c_str(),
                server.weights_endpoint().c_str());
    std::fflush(stdout);
  }
  server.run();
  server.on_tick(server.counters());  // a last metrics row with the final counters
  save();
  g_server = nullptr;
  std::printf("learner stopped: %lld updates, %lld episodes; checkpoint %s/checkpoint.ckpt\n",
              static_cast<long long>(ddpg.updates()), static_cast<long long>(episode_count), run_dir.c_str());
}

}  // namespace

void register_learner(CLI::App& app) {
  auto o = std::make_shared<LearnerCliOptions>();
  CLI::App* cmd = app.add_subcommand("learner",
                                     "the learner of the distributed system: samples replay shards, "
                                     "runs DDPG updates, broadcasts weights");
  add_run_options(*cmd, *o,
                  {"TOML config (default: the paper preset)",
                   "override one config key, e.g. --set cluster.learner_bind=tcp://127.0.0.1:6000",
                   "where config, metrics and checkpoints go"});
  cmd->footer(env_help_footer());
  cmd->callback([o] { run_learner(*o); });
}

}  // namespace pamdp::app
