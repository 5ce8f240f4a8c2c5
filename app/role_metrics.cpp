#include "app/role_metrics.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <mutex>
#include <string_view>

#include "core/files.hpp"
#include "core/log.hpp"

namespace pamdp::app {
namespace {

using metrics::Counter;
using metrics::Gauge;
using metrics::Registry;
using Clock = std::chrono::steady_clock;

// Outcome codes at or above this share the "other" series (envs use a handful of small codes).
constexpr int kMaxStatus = 64;

constexpr const char* kRefusedHelp =
    "Connections to this process's bound cluster sockets refused in the handshake (no CURVE, a wrong server key, a "
    "client key the cluster did not issue, not ZeroMQ)";

double seconds_since_epoch() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

MetricsEndpoint::MetricsEndpoint(const std::string& role, const std::string& name, const std::string& bind, int port,
                                 const std::string& advertise_host) {
  registry_
      .gauge("pamdp_process_info", "This process's role in the cluster (learner, replay, actor, train) and name",
             {{"role", role}, {"name", name}})
      .set(1.0);
  registry_.gauge("pamdp_process_start_time_seconds", "Start time of the process since the Unix epoch")
      .set(seconds_since_epoch());
  server_ = std::make_unique<metrics::MetricsHttpServer>(registry_, bind, port, advertise_host);
  log::info("{}: metrics at {}", role, server_->url());
}

void write_metrics_urls(const std::string& path, const std::vector<std::string>& urls) {
  std::string text;
  for (const std::string& u : urls) {
    text += u;
    text += '\n';
  }
  write_file_atomically(path, text.data(), text.size());
}

void register_rate(Registry& r, const Counter& counter, const std::string& name, const std::string& help) {
  Gauge& rate = r.gauge(name, help);
  struct State {
    Clock::time_point at = Clock::now();
    int64_t value = 0;
  };
  auto state = std::make_shared<State>();
  state->value = counter.value();
  r.on_collect([&rate, &counter, state] {
    const auto now = Clock::now();
    const double dt = std::chrono::duration<double>(now - state->at).count();
    if (dt >= 1.0) {
      const int64_t v = counter.value();
      rate.set(static_cast<double>(v - state->value) / dt);
      state->value = v;
      state->at = now;
    }
  });
}

// ---------------------------------------------------------------------------------------------

EpisodeMetrics::EpisodeMetrics(Registry& r, const std::string& prefix, const Env& env)
    : success_status_(env.success_status()),
      episodes_(r.counter(prefix + "episodes_total", "Episodes finished")),
      goals_(r.counter(prefix + "goals_total", "Episodes that ended in the env's success outcome (HFO: GOAL)")),
      other_outcome_(nullptr),
      outcomes_(kMaxStatus, nullptr),
      return_mean_(r.gauge(prefix + "episode_return_mean_100", "Mean undiscounted return of the last 100 episodes")),
      goal_rate_(r.gauge(prefix + "goal_rate_100", "Fraction of the last 100 episodes that ended in success")),
      steps_mean_(r.gauge(prefix + "episode_steps_mean_100", "Mean length in steps of the last 100 episodes")) {
  const std::string name = prefix + "episode_outcomes_total";
  const std::string help = "Episodes finished, by terminal outcome";
  for (const int status : env.outcomes()) {
    if (status > 0 && status < kMaxStatus) {
      outcomes_[static_cast<size_t>(status)] =
          &r.counter(name, help, {{"outcome", std::string(env.status_name(status))}});
    }
  }
  other_outcome_ = &r.counter(name, help, {{"outcome", "OTHER"}});
}

void EpisodeMetrics::add(int status, double ret, int steps) {
  episodes_.add(1);
  const bool goal = status == success_status_;
  if (goal) {
    goals_.add(1);
  }
  Counter* c = status >= 0 && status < kMaxStatus ? outcomes_[static_cast<size_t>(status)] : nullptr;
  (c != nullptr ? c : other_outcome_)->add(1);
  returns_[next_] = ret;
  steps_[next_] = steps;
  goals_window_[next_] = goal ? 1 : 0;
  next_ = (next_ + 1) % kWindow;
  count_ = std::min(count_ + 1, kWindow);
  double sum_ret = 0.0;
  double sum_steps = 0.0;
  int sum_goals = 0;
  for (size_t i = 0; i < count_; ++i) {
    sum_ret += returns_[i];
    sum_steps += steps_[i];
    sum_goals += goals_window_[i];
  }
  const auto n = static_cast<double>(count_);
  return_mean_.set(sum_ret / n);
  steps_mean_.set(sum_steps / n);
  goal_rate_.set(sum_goals / n);
}

UpdateMetrics::UpdateMetrics(Registry& r)
    : updates_(r.counter("pamdp_updates_total", "DDPG updates done (the learner's update count)")),
      critic_loss_(r.gauge("pamdp_critic_loss", "Critic loss (1/2B) sum (Q - y)^2 of the newest update")),
      q_mean_(r.gauge("pamdp_q_mean", "Mean Q(s, a) over the newest update's batch")),
      at_bound_(r.gauge("pamdp_actor_params_at_bound_ratio",
                        "Fraction of the continuous parameters the actor outputs for the newest batch that are at "
                        "or past a bound of their range")) {
  register_rate(r, updates_, "pamdp_updates_per_second", "DDPG updates per second over the last second or more");
}

void UpdateMetrics::add(const UpdateStats& s, int64_t updates_total) {
  updates_.set(updates_total);
  critic_loss_.set(s.critic_loss);
  q_mean_.set(s.q_mean);
  at_bound_.set(s.params_at_bound_fraction);
}

// ---------------------------------------------------------------------------------------------

ActorMetrics::ActorMetrics(Registry& r, const ActorCounters& c, const Env& env) : episodes_(r, "pamdp_", env) {
  Counter* steps = &r.counter("pamdp_env_steps_total", "Env steps taken");
  Counter* transitions = &r.counter("pamdp_actor_transitions_sent_total", "Transitions sent to replay shards");
  Counter* batches = &r.counter("pamdp_actor_batches_sent_total", "TransitionBatch messages sent to replay shards");
  Counter* blocked = &r.counter("pamdp_actor_send_blocked_seconds_total",
                                "Time the env loop waited for a shard to take a batch (backpressure)");
  Counter* acked = &r.counter("pamdp_actor_batches_acknowledged_total",
                              "TransitionBatches the replay shards have acknowledged (read)");
  Counter* acked_transitions =
      &r.counter("pamdp_actor_transitions_acknowledged_total",
                 "Transitions the replay shards acknowledged as stored (InsertAck.inserted); each is in a shard's "
                 "table or counted there as evicted");
  Counter* lost = &r.counter("pamdp_actor_batches_lost_total",
                             "TransitionBatches unacknowledged when the connection to their shard died");
  Counter* dropped =
      &r.counter("pamdp_actor_reports_dropped_total", "Episode reports the learner's socket would not take");
  Counter* bad = &r.counter("pamdp_bad_messages_total", "Received messages dropped as malformed");
  Gauge* version = &r.gauge("pamdp_actor_weights_version", "Version of the weights this actor acts with (0: none yet)");
  Gauge* age =
      &r.gauge("pamdp_actor_weights_age_updates",
               "Learner updates between the weights this actor acts with and the newest update count it heard of");
  Gauge* eps = &r.gauge("pamdp_epsilon", "Exploration epsilon of the next step");
  r.on_collect([=, &c] {
    constexpr auto rl = std::memory_order_relaxed;
    steps->set(c.env_steps.load(rl));
    transitions->set(c.transitions_sent.load(rl));
    batches->set(c.batches_sent.load(rl));
    blocked->set(c.send_blocked_ms.load(rl) / 1000);
    acked->set(c.batches_acknowledged.load(rl));
    acked_transitions->set(c.transitions_acknowledged.load(rl));
    lost->set(c.batches_lost.load(rl));
    dropped->set(c.reports_dropped.load(rl));
    bad->set(c.malformed_messages.load(rl));
    version->set(static_cast<double>(c.weights_version.load(rl)));
    age->set(static_cast<double>(c.weights_age_updates.load(rl)));
    eps->set(c.epsilon.load(rl));
  });
  // After the copy above: hooks run in registration order.
  register_rate(r, *steps, "pamdp_env_steps_per_second", "Env steps per second over the last second or more");
}

void register_shard_metrics(Registry& r, const ShardServer& server) {
  Counter* inserted = &r.counter("pamdp_replay_transitions_inserted_total", "Transitions stored");
  Counter* sampled =
      &r.counter("pamdp_replay_transitions_sampled_total", "Transitions drawn for the learner's samples");
  Counter* dropped = &r.counter("pamdp_replay_transitions_dropped_total",
                                "Sampled transitions in replies that could not be queued to the learner");
  Counter* replies_dropped =
      &r.counter("pamdp_replay_sample_replies_dropped_total", "Sample replies that could not be queued to the learner");
  Counter* acks_dropped = &r.counter("pamdp_replay_insert_acks_dropped_total",
                                     "Insert acknowledgements that could not be queued to an actor");
  Counter* bad = &r.counter("pamdp_bad_messages_total", "Received messages dropped as malformed");
  Counter* refused = &r.counter("pamdp_connections_refused_total", kRefusedHelp);
  Counter* waits = &r.counter("pamdp_replay_rate_limiter_insert_wait_seconds_total",
                              "Time the samples-per-insert rate limiter held inserts back");
  Counter* joins = &r.counter("pamdp_replay_joins_total", "Cluster maps taken from the learner (1 + re-joins)");
  Gauge* held = &r.gauge("pamdp_replay_inserts_held", "1 while the rate limiter holds inserts back");
  Gauge* waiting = &r.gauge("pamdp_replay_sample_requests_waiting", "Sample requests waiting for the rate limiter");
  Gauge* size = &r.gauge("pamdp_replay_size_transitions", "Transitions held");
  Gauge* capacity = &r.gauge("pamdp_replay_capacity_transitions", "Transitions the ring holds (0 before joining)");
  Gauge* fill = &r.gauge("pamdp_replay_fill_ratio", "Transitions held / capacity");
  Gauge* restored =
      &r.gauge("pamdp_replay_restored_transitions", "Transitions restored from the snapshot at start (--snapshot)");
  Counter* evicted =
      &r.counter("pamdp_replay_transitions_evicted_total",
                 "Transitions gone by the table's rule: overwritten when full, or dropped with the table "
                 "on a new capacity (inserted + restored = size + evicted)");
  Counter* duplicates = &r.counter("pamdp_replay_batches_duplicate_total",
                                   "Batches refused because the same writer's batch was stored already");
  Counter* stale = &r.counter("pamdp_replay_batches_stale_total",
                              "Batches refused as older than the deduplication window (their actor counted them lost)");
  r.on_collect([=, &server] {
    const ShardCounters c = server.counters();
    inserted->set(c.inserted);
    sampled->set(c.sampled);
    dropped->set(c.transitions_dropped);
    replies_dropped->set(c.replies_dropped);
    acks_dropped->set(c.acks_dropped);
    bad->set(c.malformed);
    refused->set(c.connections_refused);
    waits->set(c.insert_blocked_ms / 1000);
    joins->set(c.joins);
    held->set(static_cast<double>(c.inserts_held));
    waiting->set(static_cast<double>(c.requests_waiting));
    size->set(static_cast<double>(c.size));
    capacity->set(static_cast<double>(c.capacity));
    fill->set(c.capacity > 0 ? static_cast<double>(c.size) / static_cast<double>(c.capacity) : 0.0);
    restored->set(static_cast<double>(c.restored));
    evicted->set(c.evicted);
    duplicates->set(c.batches_duplicate);
    stale->set(c.batches_stale);
  });
  register_rate(r, *inserted, "pamdp_replay_inserts_per_second", "Transitions stored per second");
  register_rate(r, *sampled, "pamdp_replay_samples_per_second", "Transitions sampled per second");
}

// ---------------------------------------------------------------------------------------------

void register_peer_metrics(Registry& r, net::PeerTable& table) {
  struct Series {
    const net::PeerCounters* peer;
    Counter* messages_in;
    Counter* bytes_in;
    Counter* messages_out;
    Counter* bytes_out;
    Counter* reconnects;
    Counter* refused_for_size;
    Gauge* silence;
  };
  struct State {
    std::mutex mutex;
    std::vector<Series> series;
  };
  auto state = std::make_shared<State>();
  table.watch([&r, state](net::PeerCounters& p) {
    const metrics::Labels l{{"peer", p.name}};
    Series s{&p,
             &r.counter("pamdp_peer_messages_received_total", "Messages received from the peer", l),
             &r.counter("pamdp_peer_bytes_received_total", "Bytes received from the peer", l),
             &r.counter("pamdp_peer_messages_sent_total", "Messages sent to the peer", l),
             &r.counter("pamdp_peer_bytes_sent_total", "Bytes sent to the peer", l),
             &r.counter("pamdp_peer_reconnects_total",
                        "Connections to the peer lost and made again, or joins from a new connection", l),
             &r.counter("pamdp_peer_frames_refused_for_size_total",
                        "Frames from the peer over the receiving socket's size limit, refused unread", l),
             &r.gauge("pamdp_peer_silence_seconds", "Seconds since the peer's last message (-1: none yet)", l)};
    const std::lock_guard lock(state->mutex);
    state->series.push_back(s);
  });
  r.on_collect([state] {
    const auto now = std::chrono::steady_clock::now();
    constexpr auto rl = std::memory_order_relaxed;
    const std::lock_guard lock(state->mutex);
    for (const Series& s : state->series) {
      s.messages_in->set(s.peer->messages_in.load(rl));
      s.bytes_in->set(s.peer->bytes_in.load(rl));
      s.messages_out->set(s.peer->messages_out.load(rl));
      s.bytes_out->set(s.peer->bytes_out.load(rl));
      s.reconnects->set(s.peer->reconnects.load(rl));
      s.refused_for_size->set(s.peer->refused_for_size.load(rl));
      s.silence->set(s.peer->silence_seconds(now));
    }
  });
}

// ---------------------------------------------------------------------------------------------

EvalMetrics::EvalMetrics(Registry& r)
    : evals_(r.counter("pamdp_evaluations_total", "Greedy evaluations run (train.eval_every_updates)")),
      goal_rate_(r.gauge("pamdp_eval_goal_rate", "Success rate of the latest greedy evaluation")),
      steps_to_goal_(
          r.gauge("pamdp_eval_steps_to_goal_mean", "Average steps to success of the latest greedy evaluation")),
      return_mean_(r.gauge("pamdp_eval_return_mean", "Mean return of the latest greedy evaluation")) {}

void EvalMetrics::add(const EvalResult& e) {
  evals_.add(1);
  goal_rate_.set(e.goal_rate);
  steps_to_goal_.set(e.avg_steps_to_goal);
  return_mean_.set(e.avg_return);
}

LearnerMetrics::LearnerMetrics(Registry& r, const Env& env, const ExplorationConfig& exploration)
    : exploration_(exploration),
      updates_(r),
      evals_(r),
      episodes_(r, "pamdp_cluster_", env),
      samples_(r.counter("pamdp_learner_samples_received_total", "Sampled transitions received from the shards")),
      bad_(r.counter("pamdp_bad_messages_total", "Received messages dropped as malformed")),
      actors_joined_(r.counter("pamdp_learner_actors_joined_total", "Actors that joined (each counted once)")),
      waiting_(r.counter("pamdp_learner_waiting_for_data_seconds_total",
                         "Time the learner had no sampled batch to update on")),
      refused_(r.counter("pamdp_connections_refused_total", kRefusedHelp)),
      reports_refused_(r.counter("pamdp_learner_episode_reports_refused_total",
                                 "Episode reports dropped because the sender has not joined as an actor")),
      weights_version_(r.gauge("pamdp_learner_weights_version", "Version of the newest published weights")),
      shards_(r.gauge("pamdp_learner_peers_connected", "Peers in the cluster now", {{"role", "replay"}})),
      actors_(r.gauge("pamdp_learner_peers_connected", "Peers in the cluster now", {{"role", "actor"}})),
      epsilon_(r.gauge("pamdp_learner_epsilon", "Epsilon of the exploration schedule at the learner's update count")),
      urls_(r.gauge("pamdp_learner_metrics_urls", "Metrics endpoints the learner knows (metrics_urls.txt)")) {}

void LearnerMetrics::on_tick(const LearnerCounters& c, int64_t updates_total, size_t metrics_urls) {
  samples_.set(c.samples_received);
  bad_.set(c.malformed_messages);
  actors_joined_.set(c.actors_joined);
  waiting_.set(c.waiting_for_data_ms / 1000);
  refused_.set(c.connections_refused);
  reports_refused_.set(c.episode_reports_refused);
  weights_version_.set(static_cast<double>(c.weights_version));
  shards_.set(static_cast<double>(c.shards));
  actors_.set(static_cast<double>(c.actors_alive));
  epsilon_.set(linear_epsilon(updates_total, exploration_.epsilon_start, exploration_.epsilon_end,
                              exploration_.epsilon_anneal_updates));
  urls_.set(static_cast<double>(metrics_urls));
}

// ---------------------------------------------------------------------------------------------

TrainMetrics::TrainMetrics(Registry& r, const Env& env, int64_t replay_capacity)
    : episodes_(r, "pamdp_", env),
      updates_(r),
      evals_(r),
      env_steps_(r.counter("pamdp_env_steps_total", "Env steps taken")),
      epsilon_(r.gauge("pamdp_epsilon", "Exploration epsilon of the newest step")),
      inserted_(r.counter("pamdp_replay_transitions_inserted_total", "Transitions stored")),
      sampled_(r.counter("pamdp_replay_transitions_sampled_total", "Transitions drawn for updates")),
      size_(r.gauge("pamdp_replay_size_transitions", "Transitions held")),
      fill_(r.gauge("pamdp_replay_fill_ratio", "Transitions held / capacity")),
      capacity_(static_cast<double>(replay_capacity)) {
  r.gauge("pamdp_replay_capacity_transitions", "Transitions the buffer holds").set(capacity_);
  register_rate(r, env_steps_, "pamdp_env_steps_per_second", "Env steps per second over the last second or more");
}

void TrainMetrics::on_episode(int status, double ret, int steps, int64_t replay_size, bool agent) {
  if (agent) {
    episodes_.add(status, ret, steps);
  }
  inserted_.add(steps);
  size_.set(static_cast<double>(replay_size));
  fill_.set(capacity_ > 0.0 ? static_cast<double>(replay_size) / capacity_ : 0.0);
}

}  // namespace pamdp::app
