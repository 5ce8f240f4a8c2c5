// The full configuration of a training run: env, DDPG, exploration, replay and the training
// loop. Loaded from one TOML file plus `--set key=value` overrides, validated once; an unknown
// key or an out-of-range value is an error naming the key and the valid choices. Every run
// writes the resolved config to its run directory (to_toml), so it can be repeated exactly.
// The defaults are the paper preset, deploy/configs/paper.toml (a test keeps them equal).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "actor/exploration.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/hfo/scripted_team.hpp"
#include "envs/hfo/soccer_sim.hpp"
#include "envs/registry.hpp"
#include "learner/algorithm.hpp"
#include "learner/ddpg.hpp"
#include "learner/training_run.hpp"

namespace pamdp::app {

// The env of a run: a registered env (envs/registry.hpp) and the env.* settings. `params` holds
// every registered env's keys, whichever env is named, so that a config file written by one build
// reads back the same; the env reads its own.
struct EnvConfig {
  std::string name = "hfo";
  EnvParams params = env_registry().defaults();
};

// Whether the env gives the embedded simulator's features, the ones the scripted offense reads
// (hfo, or hfo-server in the embedded encoding).
inline bool gives_embedded_features(const EnvConfig& env) {
  const auto& gives = env_registry().find(env.name).gives_embedded_hfo_features;
  return gives && gives(env.params);
}

struct ReplayConfig {
  int64_t capacity = 500000;
  int64_t warmup = 10000;  // transitions stored before the first update
  int shards = 2;          // distributed: capacity and warm-up are split evenly across shards
};

// The distributed system (docs/protocol.md). Endpoints are ZeroMQ addresses.
struct ClusterConfig {
  // Loopback by default. Any other address needs CURVE (curve = true) or insecure = true, or the
  // learner refuses to start (docs/protocol.md, "Security").
  std::string learner_bind = "tcp://127.0.0.1:5555";  // join socket (ROUTER)
  std::string weights_bind = "tcp://127.0.0.1:5556";  // weights broadcast (PUB)
  std::string advertise_host = "127.0.0.1";           // how peers reach this machine's bound ports
  int64_t publish_every_updates = 100;
  int actor_batch_transitions = 64;  // most transitions per TransitionBatch; each episode end sends one
  int actor_batches_in_flight = 2;   // unacknowledged TransitionBatches per actor and shard
  // Samples per inserted transition the shards allow (0: updates_per_step * batch_size, the
  // single-process ratio), and how far inserts may run ahead of / behind it, in transitions.
  double samples_per_insert = 0.0;
  int64_t rate_limit_slack = 2000;
  int requests_in_flight_per_shard = 2;
  int heartbeat_ms = 1000;
  int peer_timeout_ms = 5000;
  bool curve = false;                   // CURVE encryption + authentication on every socket
  std::string curve_keys_dir = "keys";  // written by pamdp keygen
  // Binds beyond loopback without CURVE, for a trusted private network: warned once at start-up
  // and exported as pamdp_security_insecure = 1. Shards and actors take --insecure.
  bool insecure = false;
};

// The /metrics endpoint of `pamdp learner` and `pamdp train` (actors and shards take
// --metrics-bind / --metrics-port, since many run on one machine). Port 0 = any free port; the URL
// is logged and written to the run directory's metrics_urls.txt.
struct MetricsConfig {
  std::string bind = "127.0.0.1";  // an address of this machine; 0.0.0.0 for every interface
  int port = 0;
};

// TrainLoopConfig (train.*) is the run lifecycle's: learner/training_run.hpp.

struct ExperimentConfig {
  uint64_t seed = 1;
  EnvConfig env;
  DdpgConfig ddpg;
  // The registered algorithms' own keys ("pdqn.q_tau"), every one whichever algorithm runs.
  AlgorithmParams algorithm_params = algorithm_registry().defaults();
  ExplorationConfig exploration;
  std::vector<std::string> masked_actions = {"TACKLE"};
  // Actions taken only where the env's feature says they can act (exploration.gated_actions;
  // HFO: KICK only with the kickable bit on), by name; the env declares which it can gate.
  std::vector<std::string> gated_actions;
  // Random-action sampling ranges overriding the action-space bounds, by parameter name
  // (the paper's code explores dash power in [-100, 100]).
  std::vector<std::pair<std::string, std::pair<float, float>>> random_param_ranges = {
      {"dash_power", {-100.0F, 100.0F}}};
  // The scripted offense's shot when it demonstrates and labels (exploration.demo_shot), and
  // in `pamdp eval --agreement` on a checkpoint trained with it.
  hfo::ShotAim demo_shot = hfo::ShotAim::kBestCourse;
  // In a team (env.offense_agents > 1) the scripted team player teaches; it passes when an
  // opponent comes this close to the ball (metres; exploration.demo_pass_within; 0 never passes).
  double demo_pass_within = hfo::ScriptedTeamPlayer::kPassWhenOpponentWithin;
  ReplayConfig replay;
  TrainLoopConfig train;
  ClusterConfig cluster;
  MetricsConfig metrics;
};

// Names of the enum-valued settings, shared by the config file and the command-line options.
template <typename E>
using Choices = std::vector<std::pair<std::string, E>>;
const Choices<hfo::StartDistribution>& start_choices();
const Choices<hfo::Referee>& referee_choices();
const Choices<hfo::BodyAtReset>& body_at_reset_choices();
const Choices<std::string>& env_choices();        // the registered envs' names
const Choices<std::string>& algorithm_choices();  // the registered algorithms' names
const Choices<hfo::ShotAim>& shot_aim_choices();

// Loads `path` (empty: defaults) and applies overrides ("ddpg.gamma=0.95"). Throws
// std::runtime_error with the key, the problem and the valid choices.
ExperimentConfig load_experiment_config(const std::string& path, const std::vector<std::string>& overrides);
ExperimentConfig parse_experiment_config(const std::string& toml_text, const std::string& source_name,
                                         const std::vector<std::string>& overrides);
std::string to_toml(const ExperimentConfig& config);

// The run's learner (train.algorithm) for an env's shapes. `device` overrides ddpg.device: kCpu
// for a learner that only acts (pamdp eval, the Python bindings).
std::unique_ptr<Algorithm> make_learner(const ExperimentConfig& config, int obs_dim, const ActionSpace& space,
                                        uint64_t seed, std::optional<UpdateDevice> device = std::nullopt);

}  // namespace pamdp::app
