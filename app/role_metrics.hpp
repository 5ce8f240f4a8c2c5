// The live metrics of each role (docs/architecture.md, "Metrics"): which counters and gauges a
// process registers, and how the role's own counters reach them. Every class registers its
// metrics in its constructor (start-up); the update calls are relaxed atomic stores and adds
// that allocate nothing, so they may sit in env loops and update paths. Values that a role keeps
// in atomics of its own (ActorCounters, ShardServer::counters()) are copied by collect hooks on
// the HTTP thread instead, so those roles' hot paths do nothing extra.
//
// Names are shared where the meaning is: pamdp_env_steps_total is counted by actors and by
// `pamdp train`; the learner's view of every actor's episodes is pamdp_cluster_*; role-only
// metrics carry the role (pamdp_actor_*, pamdp_replay_*, pamdp_learner_*). Every process also
// exposes pamdp_process_info{role, name} = 1, which is how `pamdp monitor` tells roles apart.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "actor/actor_loop.hpp"
#include "core/metrics.hpp"
#include "core/metrics_http.hpp"
#include "core/peer_stats.hpp"
#include "envs/env.hpp"
#include "learner/ddpg.hpp"
#include "learner/evaluation.hpp"
#include "learner/learner_server.hpp"
#include "replay/shard_server.hpp"

namespace pamdp::app {

// A process's registry and its HTTP endpoint. Starts serving at construction and logs the URL.
class MetricsEndpoint {
 public:
  // Throws std::runtime_error if bind:port cannot be served (see MetricsHttpServer).
  MetricsEndpoint(const std::string& role, const std::string& name, const std::string& bind, int port,
                  const std::string& advertise_host);
  [[nodiscard]] metrics::Registry& registry() { return registry_; }
  [[nodiscard]] const std::string& url() const { return server_->url(); }

 private:
  metrics::Registry registry_;
  std::unique_ptr<metrics::MetricsHttpServer> server_;  // after the registry: destroyed first
};

// Writes urls one per line to path atomically (metrics_urls.txt of a run directory).
void write_metrics_urls(const std::string& path, const std::vector<std::string>& urls);

// The rate of a counter, per second over the last second or more, computed when scraped.
void register_rate(metrics::Registry& r, const metrics::Counter& counter, const std::string& name,
                   const std::string& help);

// Episodes of one env kind: counts, outcomes and the last-100 window. One thread calls add().
class EpisodeMetrics {
 public:
  // prefix: "pamdp_" (episodes this process played) or "pamdp_cluster_" (the learner's view).
  EpisodeMetrics(metrics::Registry& r, const std::string& prefix, const Env& env);
  void add(int status, double ret, int steps);

 private:
  static constexpr size_t kWindow = 100;
  int success_status_;
  metrics::Counter& episodes_;
  metrics::Counter& goals_;
  metrics::Counter* other_outcome_;
  std::vector<metrics::Counter*> outcomes_;  // by status code
  metrics::Gauge& return_mean_;
  metrics::Gauge& goal_rate_;
  metrics::Gauge& steps_mean_;
  std::array<double, kWindow> returns_{};
  std::array<int, kWindow> steps_{};
  std::array<uint8_t, kWindow> goals_window_{};
  size_t count_ = 0;
  size_t next_ = 0;
};

// DDPG updates (learner and train).
// The periodic greedy evaluation (train.eval_every_updates): its latest result and how many ran.
class EvalMetrics {
 public:
  explicit EvalMetrics(metrics::Registry& r);
  void add(const EvalResult& e);

 private:
  metrics::Counter& evals_;
  metrics::Gauge& goal_rate_;
  metrics::Gauge& steps_to_goal_;
  metrics::Gauge& return_mean_;
};

class UpdateMetrics {
 public:
  explicit UpdateMetrics(metrics::Registry& r);
  void add(const UpdateStats& s, int64_t updates_total);

 private:
  metrics::Counter& updates_;
  metrics::Gauge& critic_loss_;
  metrics::Gauge& q_mean_;
  metrics::Gauge& at_bound_;
};

// `pamdp actor`: copies ActorCounters when scraped; on_episode() for outcomes and returns.
class ActorMetrics {
 public:
  ActorMetrics(metrics::Registry& r, const ActorCounters& counters, const Env& env);
  void on_episode(int status, double ret, int steps) { episodes_.add(status, ret, steps); }

 private:
  EpisodeMetrics episodes_;
};

// `pamdp replay`: copies ShardServer::counters() when scraped. `server` must outlive the registry's
// last render (destroy the endpoint first).
void register_shard_metrics(metrics::Registry& r, const ShardServer& server);

// Per-peer series of a PeerTable (core/peer_stats.hpp), each labelled peer="NAME":
//   pamdp_peer_messages_received_total, pamdp_peer_bytes_received_total,
//   pamdp_peer_messages_sent_total, pamdp_peer_bytes_sent_total, pamdp_peer_reconnects_total,
//   pamdp_peer_silence_seconds (since its last message; -1 before the first).
// Watches the table (PeerTable::watch): its peers now and later. Both must outlive the registry's use.
void register_peer_metrics(metrics::Registry& r, net::PeerTable& table);

// `pamdp learner`: update statistics, episode reports and the once-a-second counters.
class LearnerMetrics {
 public:
  LearnerMetrics(metrics::Registry& r, const Env& env, const ExplorationConfig& exploration);
  void on_update(const UpdateStats& s, int64_t updates_total) { updates_.add(s, updates_total); }
  // The agent's episodes; demonstrations are left out, as `pamdp train` leaves them out.
  void on_episode(const EpisodeSummary& e) {
    if (!e.scripted) {
      episodes_.add(e.status, e.ret, static_cast<int>(e.steps));
    }
  }
  void on_tick(const LearnerCounters& c, int64_t updates_total, size_t metrics_urls);
  void on_eval(const EvalResult& e) { evals_.add(e); }

 private:
  ExplorationConfig exploration_;
  UpdateMetrics updates_;
  EvalMetrics evals_;
  EpisodeMetrics episodes_;
  metrics::Counter& samples_;
  metrics::Counter& bad_;
  metrics::Counter& actors_joined_;
  metrics::Counter& waiting_;
  metrics::Counter& refused_;
  metrics::Counter& reports_refused_;
  metrics::Gauge& weights_version_;
  metrics::Gauge& shards_;
  metrics::Gauge& actors_;
  metrics::Gauge& epsilon_;
  metrics::Gauge& urls_;
};

// `pamdp train`: one env, an in-process replay buffer and the updates, all on one thread.
class TrainMetrics {
 public:
  TrainMetrics(metrics::Registry& r, const Env& env, int64_t replay_capacity);
  void on_step(double epsilon) {
    env_steps_.add(1);
    epsilon_.set(epsilon);
  }
  void on_update(const UpdateStats& s, int64_t updates_total, int batch_size) {
    updates_.add(s, updates_total);
    sampled_.add(batch_size);
  }
  // After the episode's transitions went into the replay buffer. A demonstration (`agent` false)
  // counts as inserted transitions only, not in the episode outcomes and rates.
  void on_episode(int status, double ret, int steps, int64_t replay_size, bool agent = true);
  void on_eval(const EvalResult& e) { evals_.add(e); }

 private:
  EpisodeMetrics episodes_;
  UpdateMetrics updates_;
  EvalMetrics evals_;
  metrics::Counter& env_steps_;
  metrics::Gauge& epsilon_;
  metrics::Counter& inserted_;
  metrics::Counter& sampled_;
  metrics::Gauge& size_;
  metrics::Gauge& fill_;
  double capacity_;
};

}  // namespace pamdp::app
