// The actor role of the distributed system (docs/protocol.md): steps K envs round robin with
// its own copy of the actor network, explores ε-greedily, keeps each env's episode until it
// ends, computes Monte-Carlo returns and ships the transitions to the replay shards in
// TransitionBatches; reports every episode to the learner; picks up PolicyWeights from the
// learner's PUB socket between steps; heartbeats and re-joins when the cluster map changes.
//
// Semantics follow the single-process trainer (app/trainer.cpp), demonstrations included: the stored action is the full
// output vector as executed (the random draw under ε, squashed when bound = squashing), returns
// are discounted with gamma to the episode end, and the last transition of an episode is terminal
// (also when the episode is cut at the env's max_episode_steps()).
//
// ε: 1 until the first PolicyWeights arrive; then linear_epsilon(weights.updates, …) or, with
// apex_epsilon, apex_epsilon(actor_index, max(num_actors_hint, actor_index + 1), base, alpha).
//
// Sending: batches go to the shards round robin, starting at actor_index % shards. Each shard
// answers every batch it reads with an InsertAck, and reads none while its rate limiter holds
// inserts back; an actor keeps at most batches_in_flight batches unacknowledged per shard
// (credit-based flow control, as Reverb's writers' max_in_flight_items). A shard whose window
// (or queue) is full holds the env loop (backpressure: waits in send_attempt_ms slices, answering
// weights and heartbeats in between, counted in send_blocked_ms). So what is in flight, and how
// stale the policy behind it, is bounded by actors x shards x batches_in_flight batches, whatever
// the sockets buffer. A lost connection to a shard (killed, or restarted on the same endpoint)
// empties its window: those batches are gone (batches_lost). A shard that acknowledges nothing,
// or whose queue takes nothing, for peer_timeout_ms while another is available is skipped for
// peer_timeout_ms, then probed.
// With no shard in the map the loop waits for a map that has one. EpisodeReports and heartbeats
// never block: one the join socket will not queue is dropped (reports_dropped).
// Re-joins keep the actor index of the first join (it seeds the streams, picks the Ape-X ε and
// tags the batches); later maps update the shards, the weights endpoint and num_actors_hint.
//
// Ownership: owns its envs, the link and its sockets; the Context and the counters must outlive
// it. Threading: run() on one thread; the counters may be read from any thread; `stop` may be set
// from any thread or a signal handler. Cost: a step is one env step plus one forward pass of the
// actor (batch 1; skipped at ε = 1) and allocates nothing (tests/actor_alloc_test.cpp); control
// sockets are looked at about once a millisecond, at most 64 messages each per look.
// Errors: bad messages are dropped and counted (malformed_messages), logged at most once per
// second; a mis-built loop (envs of different shapes, a bad config) throws std::invalid_argument
// from the constructor.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "actor/exploration.hpp"
#include "actor/learner_link.hpp"
#include "core/peer_stats.hpp"
#include "core/policy.hpp"
#include "core/transport.hpp"
#include "envs/env.hpp"

namespace pamdp {

struct ActorLoopConfig {
  ExplorationConfig exploration;  // resolved against the envs' action space
  double gamma = 0.99;
  int batch_transitions = 64;  // most rows per TransitionBatch (cluster.actor_batch_transitions)
  int heartbeat_ms = 1000;
  int peer_timeout_ms = 5000;
  bool apex_epsilon = false;  // per-actor fixed ε instead of the learner's linear schedule
  double apex_base = 0.4;
  double apex_alpha = 7.0;
  uint64_t seed = 1;          // mixed with the actor index: actors explore differently
  int batches_in_flight = 2;  // unacknowledged batches per shard (cluster.actor_batches_in_flight)
  int shard_send_hwm = 8;     // batches queued per shard before sends block (at least batches_in_flight)
  int send_attempt_ms = 20;   // one blocking send attempt; control sockets are served in between
  int tick_ms = 1000;         // on_tick period
  std::optional<net::CurveClientKeys> curve;
  // With exploration.demo_fraction > 0: makes the teacher that plays the demonstrations, one per
  // env and player (a team game takes Env::agents() of them). An episode is a demonstration with probability
  // demo_share(updates, demo_fraction, demo_anneal_updates, demo_fraction_end), drawn at its start as `pamdp train`
  // draws it; its transitions go to the shards like the agent's, and its EpisodeReport says `scripted` (weights version
  // 0).
  std::function<std::unique_ptr<Policy>()> make_teacher;
  // Cloning (ddpg.demo_bc_weight > 0): a demonstration's rows also go to the shards'
  // demonstration table (TransitionBatch.table = 1), as `pamdp train` keeps them in a second
  // buffer; with exploration.demo_relabel, the agent's own steps go there too, each labelled with
  // the teacher's action for the same state.
  bool demo_table = false;
};

// Counter order in the actor's Heartbeat: env_steps, episodes, batches_sent, transitions_sent,
// weights_version, malformed_messages, send_blocked_ms.
struct ActorCounters {
  std::atomic<int64_t> env_steps{0};
  std::atomic<int64_t> episodes{0};
  std::atomic<int64_t> batches_sent{0};
  std::atomic<int64_t> transitions_sent{0};
  std::atomic<int64_t> weights_version{0};  // 0 = no weights yet (acting with ε = 1)
  std::atomic<int64_t> malformed_messages{0};
  std::atomic<int64_t> send_blocked_ms{0};
  std::atomic<int64_t> batches_acknowledged{0};      // InsertAcks' worth: batches the shards have read
  std::atomic<int64_t> transitions_acknowledged{0};  // transitions the shards said they stored (InsertAck.inserted)
  std::atomic<int64_t> batches_lost{0};              // unacknowledged when their shard's connection died
  std::atomic<int64_t> reports_dropped{0};           // EpisodeReports the join socket would not take
  std::atomic<double> epsilon{1.0};                  // ε the next step uses
  // Learner updates between the weights this actor acts with and the newest update count it has
  // heard of (heartbeat answers, weights); 0 before the first weights.
  std::atomic<int64_t> weights_age_updates{0};
  // Traffic and liveness per peer: "learner" (join socket and weights) and "replay:ENDPOINT".
  net::PeerTable peers;
};

class ActorLoop {
 public:
  // `map` is what link.join() returned. Connects to the shards and the weights endpoint; sends
  // nothing until run(). Every env must have the same observation size and action space.
  ActorLoop(net::Context& ctx, LearnerLink link, const ClusterInfo& map, std::vector<std::unique_ptr<Env>> envs,
            ActorLoopConfig config, ActorCounters& counters);
  ~ActorLoop();
  ActorLoop(const ActorLoop&) = delete;
  ActorLoop& operator=(const ActorLoop&) = delete;

  // Acts until `stop` is set. Episodes in progress are dropped; a partly filled batch gets one
  // short send attempt.
  void run(const std::atomic<bool>& stop);

  // Called on the run() thread about every tick_ms (progress lines); may be empty.
  std::function<void(const ActorCounters&, double epsilon)> on_tick;
  // Called on the run() thread at the end of every episode the agent played (metrics; not for
  // demonstrations, which the learner also leaves out of its rates) with the env's terminal
  // status, the undiscounted return and the steps; may be empty; must not allocate.
  std::function<void(int status, double ret, int steps)> on_episode;

  [[nodiscard]] uint32_t actor_index() const;
  // ε the next step uses. Run thread only.
  [[nodiscard]] double epsilon() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pamdp
