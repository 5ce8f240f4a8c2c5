// `pamdp learner`: the learner process of the distributed system (docs/protocol.md).
#include <algorithm>
#include <array>
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
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "app/network_security.hpp"
#include "app/role_metrics.hpp"
#include "app/run_options.hpp"
#include "app/run_support.hpp"
#include "core/log.hpp"
#include "core/transport.hpp"
#include "learner/learner_server.hpp"
#include "learner/training_run.hpp"

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
  if (o.quiet) {
    log::quiet();
  }
  ResolvedRun resolved = resolve_run(o, "learner", "cluster-");
  ExperimentConfig& c = resolved.config;
  const std::string& run_dir = resolved.run_dir;
  const bool resume = resolved.resume;
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
  const std::string config_text = to_toml(c);
  auto env = make_env(c.env);
  auto eval_env = make_eval_env(c);
  const ExplorationConfig exploration = resolve_exploration(c, env->action_space());
  const std::unique_ptr<Algorithm> algorithm = make_learner(c, env->observation_size(), env->action_space(), c.seed);
  RunSpec spec;
  spec.dir = run_dir;
  spec.role = "learner";
  spec.config_toml = config_text;
  spec.seed = c.seed;
  spec.loop = c.train;
  spec.exploration = exploration;
  spec.extra_metric_columns = {"samples_per_s",      "shards", "actors_joined", "weights_version", "malformed_messages",
                               "waiting_for_data_ms"};
  // With cloning, metrics.csv also says how much of it the Q-filter lets through (as train's).
  const bool clones = algorithm->clones_demonstrations();
  if (clones) {
    spec.extra_metric_columns.insert(spec.extra_metric_columns.end(), {"bc_accepted_fraction", "bc_loss"});
  }
  // Actors played the episodes reported after the last checkpoint, and their transitions are in
  // the replay shards: their rows stay, and the next episodes are numbered after them.
  spec.keeps_episodes_after_checkpoint = true;
  TrainingRun run(spec, *algorithm, *env, *eval_env);
  // best.ckpt played again (train.recheck_best): the run's own learner, its weights from the file.
  run.make_incumbent = [&] {
    return make_learner(c, env->observation_size(), env->action_space(), c.seed, UpdateDevice::kCpu);
  };
  const CheckpointMeta meta = run.start(resume);

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
  sc.clone_demos = clones;
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
  std::optional<LearnerServer> bound;
  try {
    bound.emplace(ctx, *algorithm, sc);
  } catch (const std::runtime_error& e) {
    // The socket layer names the endpoint; the user changes it through a config key.
    const std::string what = e.what();
    const char* key =
        what.find("'" + sc.weights_bind + "'") != std::string::npos ? "cluster.weights_bind" : "cluster.learner_bind";
    throw std::runtime_error("learner: " + what + "; choose another with --set " + key +
                             "=tcp://127.0.0.1:PORT (port 0: any free port; deploy/local-cluster.sh: --port)");
  }
  LearnerServer& server = *bound;
  register_peer_metrics(endpoint.registry(), server.peers());
  g_server = &server;
  std::signal(SIGINT, on_learner_signal);
  std::signal(SIGTERM, on_learner_signal);

  run.on_save = [&server](CheckpointMeta& m) { m.weights_version = server.counters().weights_version; };
  run.on_eval = [&](const EvalResult& r) { learner_metrics.on_eval(r); };
  int64_t last_samples = 0;
  double last_print = -1e9;

  server.on_metrics_urls = [&](const std::vector<std::string>& urls) {
    write_metrics_urls((fs::path(run_dir) / "metrics_urls.txt").string(), urls);
  };
  // train.max_episodes ends the run here as it ends `pamdp train`'s: after the episode report that
  // reaches it (a resumed run counts the episodes before it), with the same final checkpoint.
  const auto episodes_done = [&] { return c.train.max_episodes > 0 && run.episodes() >= c.train.max_episodes; };
  server.on_episode = [&](const EpisodeSummary& e) {
    learner_metrics.on_episode(e);
    run.record_env_steps(e.steps);
    run.record_episode({e.status, e.ret, e.steps, e.actor_id, e.policy_version, e.scripted});
    if (episodes_done()) {
      server.stop();
    }
  };
  if (episodes_done()) {
    server.stop();
  }
  server.on_tick = [&](const LearnerCounters& k) {
    learner_metrics.on_tick(k, algorithm->updates(), server.metrics_urls().size());
    if (run.checkpoint_due()) {
      run.save();
    }
    const double dt = std::max(1e-9, run.elapsed() - run.last_row_seconds());
    const MetricsRow row = run.next_metrics_row();
    const double sps = static_cast<double>(k.samples_received - last_samples) / dt;
    last_samples = k.samples_received;
    const UpdateStats& last = run.last_update();
    const std::array<double, 8> extras{sps,
                                       static_cast<double>(k.shards),
                                       static_cast<double>(k.actors_joined),
                                       static_cast<double>(k.weights_version),
                                       static_cast<double>(k.malformed_messages),
                                       static_cast<double>(k.waiting_for_data_ms),
                                       last.bc_accepted_fraction,
                                       last.bc_loss};
    run.logs().metrics(row, std::span<const double>(extras).first(clones ? 8 : 6));
    if (!o.quiet && row.wall_seconds - last_print >= c.train.log_every_seconds) {
      last_print = row.wall_seconds;
      const RecentEpisodes& recent = run.recent();
      std::printf(
          "[%7.1fs] updates %lld | episodes %lld | success(last %zu) %.2f | return %.3f | %.0f updates/s | %.0f "
          "samples/s | shards %lld | actors %lld | weights v%lld%s%s\n",
          row.wall_seconds, static_cast<long long>(row.updates), static_cast<long long>(row.episodes), recent.size(),
          recent.success_rate(), recent.mean_return(), row.updates_per_s, sps, static_cast<long long>(k.shards),
          static_cast<long long>(k.actors_joined), static_cast<long long>(k.weights_version),
          k.shards == 0 ? " | waiting: no replay shard has joined" : "",
          (k.shards > 0 && row.updates_per_s == 0.0) ? " | waiting: shards have too little data (warm-up / rate limit)"
                                                     : "");
      std::fflush(stdout);
    }
  };

  if (!o.quiet) {
    std::printf("pamdp learner: env %s, run directory %s%s\n  join:    %s\n  weights: %s\n", c.env.name.c_str(),
                run_dir.c_str(), resume ? " (resumed)" : "", server.join_endpoint().c_str(),
                server.weights_endpoint().c_str());
    std::fflush(stdout);
  }
  // The run's updates draw from the shards; the server serves the sockets while they wait.
  while (run.update(server)) {
    learner_metrics.on_update(run.last_update(), algorithm->updates());
    run.evaluate_if_due();
  }
  server.on_tick(server.counters());  // a last metrics row with the final counters
  run.finish();
  g_server = nullptr;
  std::printf("learner stopped: %lld updates, %lld episodes; checkpoint %s/checkpoint.ckpt\n",
              static_cast<long long>(algorithm->updates()), static_cast<long long>(run.episodes()), run_dir.c_str());
}

}  // namespace

void register_learner(CLI::App& app) {
  auto o = std::make_shared<LearnerCliOptions>();
  CLI::App* cmd = app.add_subcommand("learner",
                                     "the learner of the distributed system: samples replay shards, "
                                     "runs the learner's updates (train.algorithm), broadcasts weights");
  add_run_options(*cmd, *o,
                  {"TOML config (default: the paper preset)",
                   "override one config key, e.g. --set cluster.learner_bind=tcp://127.0.0.1:6000",
                   "where config, metrics and checkpoints go"});
  cmd->footer(env_help_footer() + "\n\n" + algorithm_help_footer());
  cmd->callback([o] { run_learner(*o); });
}

}  // namespace pamdp::app
