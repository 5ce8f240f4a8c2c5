// `pamdp actor`: joins a learner, takes the experiment config from its cluster map, builds the
// envs and runs the acting loop (actor/actor_loop.hpp) until SIGINT or SIGTERM.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "actor/actor_loop.hpp"
#include "actor/learner_link.hpp"
#include "app/cli_checks.hpp"
#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "app/network_security.hpp"
#include "app/role_metrics.hpp"
#include "core/log.hpp"
#include "core/transport.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/hfo/settings.hpp"
#include "envs/registry.hpp"

namespace pamdp::app {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_actor_signal(int /*sig*/) {
  g_stop.store(true);
}

struct ActorCliOptions {
  std::string join;
  int envs = 1;
  int64_t seed = -1;
  bool apex_epsilon = false;
  std::string name;
  std::string curve_keys;
  bool insecure = false;
  double join_timeout_s = 30.0;
  double progress_every_s = 5.0;
  std::string metrics_bind = "127.0.0.1";
  int metrics_port = 0;
  std::string server_host;  // overrides env.server_host (env.name = "hfo-server")
  int server_port = 0;      // overrides env.server_port; 0 = the cluster's
  int server_agents = 0;    // overrides env.server_agents; 0 = the cluster's
};

std::string default_name() {
  char host[256] = {};
  if (gethostname(host, sizeof(host) - 1) != 0) {
    host[0] = '\0';
  }
  return std::string(host[0] != '\0' ? host : "actor") + ":" + std::to_string(getpid());
}

void run_actor(const ActorCliOptions& o) {
  // An actor binds nothing, but without CURVE what it sends and the weights it acts with cross the
  // network in the clear and unauthenticated.
  const SecurityOptions security{"pamdp actor", "--curve-keys keys here, the learner with --set cluster.curve=true",
                                 "--insecure here (and --set cluster.insecure=true on the learner)",
                                 "join a learner on this machine (--join tcp://127.0.0.1:PORT)",
                                 "its transitions and the weights it acts with would cross the network unauthenticated "
                                 "and in the clear, open to anyone on the path"};
  const std::vector<ClusterEndpoint> endpoints{{"--join", o.join}};
  const bool insecure = check_network_exposure(security, endpoints, !o.curve_keys.empty(), o.insecure);
  std::signal(SIGINT, on_actor_signal);
  std::signal(SIGTERM, on_actor_signal);
  net::Context ctx;
  LearnerLinkConfig link_config;
  link_config.join_endpoint = o.join;
  link_config.name = o.name.empty() ? default_name() : o.name;
  link_config.actor_envs = static_cast<uint32_t>(o.envs);
  link_config.join_timeout_ms = static_cast<int>(o.join_timeout_s * 1000.0);
  std::optional<net::CurveClientKeys> curve;
  if (!o.curve_keys.empty()) {
    curve = net::load_curve_keyring(o.curve_keys, /*need_server=*/false).client;
    link_config.curve = curve;
  }
  // Served from the start: the URL goes to the learner with the JoinRequest. The counters are
  // declared first, so that they outlive the endpoint's last scrape.
  ActorCounters counters;
  MetricsEndpoint endpoint("actor", link_config.name, o.metrics_bind, o.metrics_port, "");
  link_config.metrics_url = endpoint.url();
  export_security_mode(endpoint.registry(), security, insecure, endpoints);
  LearnerLink link(ctx, link_config);
  const std::optional<ClusterInfo> map = link.join(g_stop);
  if (!map) {
    if (g_stop.load()) {
      return;
    }
    throw std::runtime_error("no cluster map from the learner at " + o.join + " within " +
                             std::to_string(link_config.join_timeout_ms) +
                             " ms; start `pamdp learner` first or check the address (--join tcp://HOST:PORT), or wait "
                             "longer with --join-timeout");
  }
  ExperimentConfig config = parse_experiment_config(map->config_toml, "the cluster map from " + o.join, {});
  // Every actor has an HFO server of its own; the cluster's config names one port for all.
  if (!o.server_host.empty()) {
    config.env.params.set("server_host", o.server_host);
  }
  if (o.server_port > 0) {
    config.env.params.set("server_port", int64_t{o.server_port});
  }
  if (o.server_agents > 0) {
    if (!config.env.params.contains("server_agents")) {
      throw std::runtime_error("--server-agents: the cluster plays env '" + config.env.name +
                               "'; only env 'hfo-server' has agents on a server (leave out --server-agents)");
    }
    config.env.params.set("server_agents", int64_t{o.server_agents});
  }
  const EnvRegistration& registration = env_registry().find(config.env.name);
  if (registration.max_per_process > 0 && o.envs > registration.max_per_process) {
    throw std::runtime_error("--envs " + std::to_string(o.envs) + ": env '" + config.env.name + "' " +
                             registration.max_per_process_note);
  }

  std::vector<std::unique_ptr<Env>> envs;
  envs.reserve(static_cast<size_t>(o.envs));
  for (int k = 0; k < o.envs; ++k) {
    envs.push_back(make_env(config.env));
  }
  ActorLoopConfig loop_config;
  loop_config.exploration = resolve_exploration(config, envs.front()->action_space());
  loop_config.gamma = config.ddpg.gamma;
  loop_config.batch_transitions = config.cluster.actor_batch_transitions;
  loop_config.batches_in_flight = config.cluster.actor_batches_in_flight;
  loop_config.heartbeat_ms = config.cluster.heartbeat_ms;
  loop_config.peer_timeout_ms = config.cluster.peer_timeout_ms;
  loop_config.apex_epsilon = o.apex_epsilon;
  loop_config.seed = o.seed >= 0 ? static_cast<uint64_t>(o.seed) : config.seed;
  loop_config.curve = curve;
  if (config.exploration.demo_fraction > 0.0) {
    // The learner's config was checked: demonstrations come with an env the scripted offense reads.
    loop_config.make_teacher = [config] { return make_teacher(config); };
  }
  loop_config.demo_table = config.ddpg.demo_bc_weight > 0.0;

  ActorMetrics actor_metrics(endpoint.registry(), counters, *envs.front());
  register_peer_metrics(endpoint.registry(), counters.peers);
  ActorLoop loop(ctx, std::move(link), *map, std::move(envs), loop_config, counters);
  loop.on_episode = [&actor_metrics](int status, double ret, int steps) {
    actor_metrics.on_episode(status, ret, steps);
  };
  const auto start = std::chrono::steady_clock::now();
  auto last = start;
  int64_t last_steps = 0;
  loop.on_tick = [&](const ActorCounters& c, double eps) {
    const auto now = std::chrono::steady_clock::now();
    const double dt = std::chrono::duration<double>(now - last).count();
    if (dt < o.progress_every_s) {
      return;
    }
    const int64_t steps = c.env_steps.load();
    std::printf(
        "[%7.1fs] actor %u | %.0f steps/s | steps %lld | episodes %lld | weights v%lld | eps %.3f | batches %lld | "
        "blocked %.1f s | malformed %lld\n",
        std::chrono::duration<double>(now - start).count(), loop.actor_index(),
        static_cast<double>(steps - last_steps) / dt, static_cast<long long>(steps),
        static_cast<long long>(c.episodes.load()), static_cast<long long>(c.weights_version.load()), eps,
        static_cast<long long>(c.batches_sent.load()), static_cast<double>(c.send_blocked_ms.load()) / 1000.0,
        static_cast<long long>(c.malformed_messages.load()));
    std::fflush(stdout);
    last = now;
    last_steps = steps;
  };
  const std::string server = registration.location ? registration.location(config.env.params) : std::string();
  std::printf("pamdp actor: actor %u, %d %s env(s)%s, %zu shard(s), learner %s\n", loop.actor_index(), o.envs,
              config.env.name.c_str(), server.c_str(), map->shard_endpoints.size(), o.join.c_str());
  std::fflush(stdout);
  loop.run(g_stop);
  std::printf("done: %lld env steps, %lld episodes, %lld batches (%lld transitions) sent, weights v%lld\n",
              static_cast<long long>(counters.env_steps.load()), static_cast<long long>(counters.episodes.load()),
              static_cast<long long>(counters.batches_sent.load()),
              static_cast<long long>(counters.transitions_sent.load()),
              static_cast<long long>(counters.weights_version.load()));
}

}  // namespace

void register_actor(CLI::App& app) {
  auto o = std::make_shared<ActorCliOptions>();
  CLI::App* cmd = app.add_subcommand("actor", "act in envs for a distributed learner (docs/protocol.md)");
  cmd->add_option("--join", o->join, "the learner's join endpoint, e.g. tcp://LEARNER:5555")
      ->required()
      ->check(zmq_endpoint());
  cmd->add_option("--envs", o->envs, "environments stepped round robin")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed (default: the experiment's seed), mixed with the actor index")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--apex-epsilon", o->apex_epsilon,
                "per-actor fixed epsilon 0.4^(1 + 7 i / (N - 1)) (Ape-X) instead of the learner's schedule");
  cmd->add_option("--name", o->name, "name in the learner's logs (default HOST:PID)");
  cmd->add_option("--curve-keys", o->curve_keys,
                  "directory with client.keys from pamdp keygen: CURVE on every connection (the learner must run "
                  "with cluster.curve = true)");
  cmd->add_flag("--insecure", o->insecure,
                "allow a learner beyond loopback without CURVE, on a trusted private network only (warned once, "
                "exported as pamdp_security_insecure)");
  cmd->add_option("--join-timeout", o->join_timeout_s,
                  "exit with an error if the learner has not answered within this many seconds (0: keep trying)")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  cmd->add_option("--progress-every", o->progress_every_s, "seconds between progress lines")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--metrics-bind", o->metrics_bind,
                  "address of this machine to serve /metrics on (0.0.0.0: every interface)")
      ->capture_default_str();
  cmd->add_option("--metrics-port", o->metrics_port, "port of /metrics (0: any free port, logged)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  cmd->add_option("--server-host", o->server_host,
                  "env 'hfo-server': host of this actor's HFO server (default: the cluster's env.server_host)");
  cmd->add_option("--server-port", o->server_port,
                  "env 'hfo-server': port of this actor's HFO server (default: the cluster's env.server_port)")
      ->check(CLI::Range(1, 65535));
  cmd->add_option("--server-agents", o->server_agents,
                  "env 'hfo-server': how many of its server's agents (env.offense_agents) this actor plays, in "
                  "lockstep (default: the cluster's env.server_agents)")
      ->check(CLI::Range(1, 4));
  cmd->add_option("--log-level", "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->each([](const std::string& level) { log::set_level(level); });
  cmd->callback([o] { run_actor(*o); });
}

}  // namespace pamdp::app
