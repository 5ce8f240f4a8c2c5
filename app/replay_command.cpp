#include "app/replay_command.hpp"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "app/cli_checks.hpp"
#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/network_security.hpp"
#include "app/role_metrics.hpp"
#include "core/log.hpp"
#include "core/transport.hpp"

namespace pamdp::app {
namespace {

// A signal may arrive before the server exists; the flag covers that window.
std::atomic<bool> g_stop_requested{false};
std::atomic<ShardServer*> g_server{nullptr};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<ShardServer*>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

extern "C" void on_replay_signal(int /*sig*/) {
  g_stop_requested.store(true);
  if (ShardServer* s = g_server.load()) {
    s->stop();
  }
}

struct ReplayCliOptions {
  std::string join;
  std::string insert_bind = "tcp://127.0.0.1:0";
  std::string sample_bind = "tcp://127.0.0.1:0";
  std::string advertise_host = "127.0.0.1";
  std::string snapshot;
  double snapshot_every_s = 0.0;
  double join_timeout_s = 30.0;
  std::string name;
  std::string curve_keys;
  bool insecure = false;
  std::string metrics_bind = "127.0.0.1";
  int metrics_port = 0;
};

std::string default_name() {
  char host[256] = {};
  if (gethostname(host, sizeof(host) - 1) != 0) {
    host[0] = '\0';
  }
  return "replay@" + std::string(host[0] != '\0' ? host : "localhost") + ":" + std::to_string(getpid());
}

void run_replay(const ReplayCliOptions& o) {
  const SecurityOptions security{
      "pamdp replay", "--curve-keys keys here, the learner with --set cluster.curve=true",
      "--insecure here (and --set cluster.insecure=true on the learner)",
      "use --insert-bind and --sample-bind tcp://127.0.0.1:0 (the default) and a learner on this machine"};
  const std::vector<ClusterEndpoint> binds{{"--insert-bind", o.insert_bind}, {"--sample-bind", o.sample_bind}};
  std::vector<ClusterEndpoint> endpoints = binds;
  endpoints.push_back({"--join", o.join});
  const bool insecure = check_network_exposure(security, endpoints, !o.curve_keys.empty(), o.insecure);
  check_advertise_host(security, "--advertise-host", o.advertise_host, binds);
  ShardServerOptions options;
  options.join_endpoint = o.join;
  options.insert_bind = o.insert_bind;
  options.sample_bind = o.sample_bind;
  options.advertise_host = o.advertise_host;
  options.snapshot_path = o.snapshot;
  options.snapshot_every_ms = static_cast<int>(o.snapshot_every_s * 1000.0);
  options.join_timeout_ms = static_cast<int>(o.join_timeout_s * 1000.0);
  options.name = o.name.empty() ? default_name() : o.name;

  net::Context ctx;
  std::unique_ptr<net::CurveAuthenticator> auth;
  if (!o.curve_keys.empty()) {
    const net::CurveKeyring keys = net::load_curve_keyring(o.curve_keys, /*need_server=*/true);
    options.curve_server = keys.server;
    options.curve_client = keys.client;
    auth = std::make_unique<net::CurveAuthenticator>(ctx, std::vector<std::string>{keys.client.public_key});
  }
  auto endpoint =
      std::make_unique<MetricsEndpoint>("replay", options.name, o.metrics_bind, o.metrics_port, o.advertise_host);
  options.metrics_url = endpoint->url();
  export_security_mode(endpoint->registry(), security, insecure, endpoints);
  std::optional<ShardServer> bound;
  try {
    bound.emplace(ctx, options, shard_config_from_toml);
  } catch (const std::runtime_error& e) {
    // The socket layer names the endpoint; the user changes it with the flag that gave it.
    const std::string what = e.what();
    if (what.find("cannot bind") == std::string::npos) {
      throw;
    }
    const char* flag = what.find("'" + o.sample_bind + "'") != std::string::npos ? "--sample-bind" : "--insert-bind";
    throw std::runtime_error("pamdp replay: " + what + "; choose another with " + flag +
                             " tcp://127.0.0.1:PORT (port 0: any free port, the default)");
  }
  ShardServer& server = *bound;
  register_shard_metrics(endpoint->registry(), server);
  register_peer_metrics(endpoint->registry(), server.peers());
  // The endpoint's scrapes read the server: stop serving them before the server goes.
  const struct StopMetricsFirst {
    std::unique_ptr<MetricsEndpoint>& e;
    ~StopMetricsFirst() { e.reset(); }
  } stop_metrics_first{endpoint};
  std::printf("pamdp replay: inserts at %s, samples at %s; joining the learner at %s; metrics at %s\n",
              server.insert_endpoint().c_str(), server.sample_endpoint().c_str(), o.join.c_str(),
              options.metrics_url.c_str());
  std::fflush(stdout);

  g_server.store(&server);
  std::signal(SIGINT, on_replay_signal);
  std::signal(SIGTERM, on_replay_signal);
  if (g_stop_requested.load()) {
    server.stop();
  }
  try {
    server.run();
  } catch (...) {
    g_server.store(nullptr);
    throw;
  }
  g_server.store(nullptr);
  const ShardCounters c = server.counters();
  std::printf("pamdp replay: stopped; %lld transitions inserted, %lld sampled, %lld held, %lld malformed messages\n",
              static_cast<long long>(c.inserted), static_cast<long long>(c.sampled), static_cast<long long>(c.size),
              static_cast<long long>(c.malformed));
  std::fflush(stdout);
}

}  // namespace

ShardConfig shard_config_from_experiment(const ExperimentConfig& config) {
  const int64_t shards = config.replay.shards;
  ShardConfig s;
  s.capacity = config.replay.capacity / shards;
  if (s.capacity < 1) {
    throw std::runtime_error("replay.capacity " + std::to_string(config.replay.capacity) +
                             " split over replay.shards " + std::to_string(shards) +
                             " leaves no room per shard; raise replay.capacity");
  }
  // Cloning keeps the demonstrations in a table of their own, as `pamdp train` keeps them in a
  // second buffer of the same capacity.
  s.demo_capacity = config.ddpg.demo_bc_weight > 0.0 ? s.capacity : 0;
  const std::unique_ptr<Env> env = make_env(config.env);
  s.obs_dim = env->observation_size();
  s.action_dim = env->action_space().output_width();
  s.limiter.samples_per_insert = config.cluster.samples_per_insert > 0.0
                                     ? config.cluster.samples_per_insert
                                     : config.train.updates_per_step * static_cast<double>(config.ddpg.batch_size);
  if (!(s.limiter.samples_per_insert > 0.0)) {
    throw std::runtime_error(
        "samples per insert is 0: set cluster.samples_per_insert, or train.updates_per_step and ddpg.batch_size > 0");
  }
  s.limiter.min_size = config.replay.warmup / shards;
  s.limiter.slack = config.cluster.rate_limit_slack;
  s.seed = config.seed;
  s.heartbeat_ms = config.cluster.heartbeat_ms;
  s.peer_timeout_ms = config.cluster.peer_timeout_ms;
  return s;
}

ShardConfig shard_config_from_toml(const std::string& config_toml) {
  return shard_config_from_experiment(parse_experiment_config(config_toml, "the learner's cluster map", {}));
}

void register_replay(CLI::App& app) {
  auto o = std::make_shared<ReplayCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "replay", "run one replay shard: joins the learner, stores actors' transitions, serves the learner's samples");
  cmd->add_option("--join", o->join, "the learner's join endpoint, e.g. tcp://LEARNER:5555")
      ->required()
      ->check(zmq_endpoint());
  cmd->add_option(
         "--insert-bind", o->insert_bind,
         "where actors insert (ROUTER); port 0 = any free port; beyond loopback needs --curve-keys or --insecure")
      ->check(zmq_endpoint())
      ->capture_default_str();
  cmd->add_option(
         "--sample-bind", o->sample_bind,
         "where the learner samples (ROUTER); port 0 = any free port; beyond loopback needs --curve-keys or --insecure")
      ->check(zmq_endpoint())
      ->capture_default_str();
  cmd->add_option("--advertise-host", o->advertise_host, "the host name peers use to reach this machine's ports")
      ->capture_default_str();
  cmd->add_option("--snapshot", o->snapshot,
                  "replay snapshot file: loaded when the shard starts (if present), written when it stops");
  cmd->add_option("--snapshot-every", o->snapshot_every_s,
                  "also write the snapshot every this many seconds (0: only when stopping; a shard killed with "
                  "SIGKILL keeps what the last write held)")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  cmd->add_option("--join-timeout", o->join_timeout_s,
                  "exit with an error if the learner has not answered within this many seconds (0: keep trying)")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  cmd->add_option("--name", o->name, "name in the learner's logs (default replay@HOST:PID)");
  cmd->add_option("--curve-keys", o->curve_keys,
                  "directory written by pamdp keygen: encrypt and authenticate every socket with CURVE "
                  "(the learner must run with cluster.curve = true)");
  cmd->add_flag("--insecure", o->insecure,
                "allow binds and a learner beyond loopback without CURVE, on a trusted private network only (warned "
                "once, exported as pamdp_security_insecure)");
  cmd->add_option("--metrics-bind", o->metrics_bind,
                  "address of this machine to serve /metrics on (0.0.0.0: every interface)")
      ->capture_default_str();
  cmd->add_option("--metrics-port", o->metrics_port, "port of /metrics (0: any free port, logged)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  // Lets the global --log-level come after the subcommand name too.
  cmd->fallthrough();
  cmd->callback([o] { run_replay(*o); });
}

}  // namespace pamdp::app
