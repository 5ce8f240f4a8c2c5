// The replay shard of the distributed system (docs/protocol.md, "Replay").
//
// ReplayShard: the storage and pacing of one shard, a FIFO ReplayBuffer behind a RateLimiter.
// Memory for the ring and for the largest reply is allocated in the constructor; insert() and
// sample() copy floats and allocate nothing. Not thread-safe.
//
// ShardServer: one thread's event loop around a ReplayShard. It binds a ROUTER "insert"
// (TransitionBatch from actors, each answered with an InsertAck once read) and a ROUTER "sample" (SampleRequest from
// the learner, SampleReply possibly later), and keeps a DEALER on the learner's join socket (JoinRequest until a
// ClusterMap comes, then Heartbeat every heartbeat_ms; it joins again when the learner answers with another map version
// or stays silent for peer_timeout_ms). The shard itself is built from the first ClusterMap's config_toml through a
// caller-given function, so this library knows nothing of TOML or experiment configs. A later map with another capacity
// or other widths rebuilds the shard (dropping its data); other rate settings apply at once,
// with the limiter's counters kept.
//   - Every received frame is verified (wire::open_envelope, payload type, wire::valid_batch);
//     a bad one is dropped, counted (malformed) and logged at most once per second per kind.
//   - Backpressure: while the rate limiter holds inserts back the insert socket is not read, so
//     no InsertAck goes out and the actors, which keep at most a few batches unacknowledged
//     per shard, stop sending and stepping. Sample requests that cannot be
//     served yet wait in a FIFO queue of at most kMaxWaitingRequests; while it is full the
//     sample socket is not read either.
//   - Steady-state inserting and sampling allocate nothing (one reused FlatBufferBuilder, a
//     preallocated reply and request queue; ZeroMQ mallocs message bodies internally):
//     tests/replay_alloc_test.cpp counts operator new on the shard's thread.
//   - Cost per TransitionBatch of n rows: verify + validate (one pass over the floats) and one
//     copy into the ring; per SampleReply of n rows: n random rows copied twice (ring ->
//     reply scratch -> builder) and one send.
//   - Snapshot: when a path is set, the shard loads it (if the file exists) when it is built and
//     writes it when run() returns.
// Threading: construct on any thread, then run() on one thread; destroy only after run() has
// returned. stop() and counters() may be called from any thread; stop() is async-signal-safe.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/peer_stats.hpp"
#include "core/rng.hpp"
#include "core/transport.hpp"
#include "core/wire.hpp"
#include "replay/rate_limiter.hpp"
#include "replay/replay_buffer.hpp"

namespace pamdp {

// Everything about a shard that the experiment (the learner's ClusterMap) decides.
struct ShardConfig {
  int64_t capacity = 0;  // transitions (replay.capacity / replay.shards)
  // The demonstration table (cloning, ddpg.demo_bc_weight > 0): transitions it holds, FIFO, not
  // paced by the rate limiter; 0: no such table (a batch for it is refused as malformed).
  int64_t demo_capacity = 0;
  int obs_dim = 0;
  int action_dim = 0;  // the full actor output vector
  RateLimiterConfig limiter;
  uint64_t seed = 1;  // sampling stream (the server mixes in its endpoint)
  int heartbeat_ms = 1000;
  int peer_timeout_ms = 5000;
  bool operator==(const ShardConfig&) const = default;
};

class ReplayShard {
 public:
  // Allocates capacity rows and a reply of up to max_sample_batch rows. Throws
  // std::invalid_argument if a size is < 1.
  ReplayShard(const ShardConfig& config, int max_sample_batch);

  [[nodiscard]] bool can_insert(int64_t n) const { return limiter_.can_insert(n); }
  // Also false while the shard is empty. n must be in [1, max_sample_batch].
  [[nodiscard]] bool can_sample(int64_t n) const;
  // Stores validated rows (wire::valid_batch with this shard's widths). Requires
  // can_insert(rows.count); misuse aborts.
  void insert(const wire::TransitionRows& rows);
  // Draws n transitions uniformly with replacement. Requires can_sample(n). The rows view the
  // shard's reply scratch and stay valid until the next sample().
  wire::TransitionRows sample(int n);

  // The demonstration table (config.demo_capacity > 0), outside the rate limiter.
  [[nodiscard]] bool has_demo_table() const { return demos_.has_value(); }
  [[nodiscard]] int64_t demo_size() const { return demos_ ? demos_->size() : 0; }
  // Requires has_demo_table() and validated rows; misuse aborts.
  void insert_demos(const wire::TransitionRows& rows);
  // Requires demo_size() > 0 and n in [1, max_sample_batch]. The rows view a scratch of their own
  // (valid with sample()'s at once) until the next sample_demos().
  wire::TransitionRows sample_demos(int n);

  // Loads a snapshot written by save_snapshot (throws std::runtime_error naming the file and
  // the problem: unreadable, corrupt, other capacity or widths). The demonstration table, if any,
  // is in PATH.demos beside it, loaded when that file exists. The limiter resumes balanced:
  // the stored transitions count as inserts (past the warm-up) and as many samples as the
  // ratio allows, so sampling continues at the ratio instead of replaying old data at will.
  void load_snapshot(const std::string& path);
  void save_snapshot(const std::string& path) const;  // atomic write; throws on I/O errors
  // Keeps the counters, changes the ratio (a new ClusterMap with other limiter settings).
  void set_limiter_config(const RateLimiterConfig& config);

  [[nodiscard]] const ShardConfig& config() const { return config_; }
  [[nodiscard]] const ReplayBuffer& buffer() const { return buffer_; }
  [[nodiscard]] const RateLimiter& limiter() const { return limiter_; }
  [[nodiscard]] int max_sample_batch() const { return max_sample_batch_; }

 private:
  ShardConfig config_;
  int max_sample_batch_;
  ReplayBuffer buffer_;
  RateLimiter limiter_;
  Rng rng_;
  BatchBuffers reply_;              // column per sample = row-major rows on the wire
  std::vector<uint8_t> terminals_;  // the wire's 0/1 bytes
  std::optional<ReplayBuffer> demos_;
  std::optional<BatchBuffers> demo_reply_;
  std::vector<uint8_t> demo_terminals_;
};

struct ShardServerOptions {
  std::string join_endpoint;                      // the learner's join ROUTER, e.g. tcp://learner:5555 (required)
  std::string insert_bind = "tcp://127.0.0.1:0";  // loopback by default (docs/protocol.md, "Security")
  std::string sample_bind = "tcp://127.0.0.1:0";
  std::string advertise_host = "127.0.0.1";  // replaces * / 0.0.0.0 in the advertised endpoints
  std::string name = "replay";               // for the learner's logs
  std::string snapshot_path;                 // empty: no snapshot
  std::string metrics_url;                   // told to the learner in the JoinRequest; may be empty
  uint32_t max_batch_transitions = 4096;     // largest TransitionBatch and SampleRequest accepted
  int join_retry_ms = 1000;                  // JoinRequest cadence until the first ClusterMap
  int poll_ms = 50;                          // the longest stop() waits to be noticed
  int insert_recv_hwm = 16;                  // batches ZeroMQ queues per actor before its sends block
  // Frames above this size make ZeroMQ drop the sender's connection before anything reads them.
  // Fixed at bind time, before the widths are known (a 4096-row HFO batch is 2.1 MB).
  int64_t max_insert_message_bytes = int64_t{8} << 20;
  // Also write the snapshot every this many ms while serving (0: only when stopping), so that a
  // shard killed without a chance to stop loses at most this much of its data. The write blocks
  // the shard's loop for as long as it takes (capacity rows, atomic rename).
  int snapshot_every_ms = 0;
  // run() gives up (throws, naming the join endpoint) if the learner has not answered the first
  // JoinRequest within this many ms; 0: keep trying until stopped.
  int join_timeout_ms = 0;
  // CURVE (pamdp keygen): server keys for the two bound sockets, client keys for the join
  // connection. Both or neither; the caller runs a net::CurveAuthenticator on the context.
  std::optional<net::CurveServerKeys> curve_server;
  std::optional<net::CurveClientKeys> curve_client;
};

// Counters, readable from any thread (each field is read atomically, not all together).
struct ShardCounters {
  int64_t inserted = 0;             // transitions stored by this process
  int64_t demo_inserted = 0;        // demonstrations stored (the demonstration table)
  int64_t sampled = 0;              // transitions drawn for replies
  int64_t malformed = 0;            // messages dropped as malformed, all sockets
  int64_t requests_waiting = 0;     // sample requests queued now
  int64_t insert_blocked_ms = 0;    // time the rate limiter held inserts back
  int64_t replies_dropped = 0;      // replies ZeroMQ could not queue (learner gone or stalled)
  int64_t transitions_dropped = 0;  // transitions in those replies
  int64_t size = 0;                 // transitions held now
  int64_t capacity = 0;             // transitions the ring holds; 0 before joining
  int64_t inserts_held = 0;         // 1 while the rate limiter holds inserts back
  int64_t map_version = 0;          // of the last ClusterMap; 0 before joining
  int64_t joins = 0;                // ClusterMaps taken (1 + re-joins)
  int64_t restored = 0;             // transitions restored from the snapshot at start
  // Replay-table transitions gone by the table's own rule: overwritten by the FIFO ring when
  // full, or dropped with the table when a new map changes its capacity or widths. So at any
  // time inserted + restored == size + evicted: what was acknowledged is held or counted here.
  int64_t evicted = 0;
  int64_t batches_duplicate = 0;    // batches refused as stored already (same writer and sequence)
  int64_t batches_stale = 0;        // batches refused as older than the deduplication window
  int64_t acks_dropped = 0;         // InsertAcks ZeroMQ could not queue (actor gone); later ones cover them
  int64_t connections_refused = 0;  // failed handshakes at the insert and sample sockets (no or wrong CURVE key)
};

// Builds the shard settings from a ClusterMap's config_toml; throws std::runtime_error if the
// config does not describe a usable shard. Called on the server's thread.
using ShardConfigFromMap = std::function<ShardConfig(const std::string& config_toml)>;

class ShardServer {
 public:
  static constexpr int kMaxWaitingRequests = 64;
  // Traffic and liveness per peer: "learner" and "actor:#INDEX" (core/peer_stats.hpp).
  [[nodiscard]] net::PeerTable& peers() { return peers_; }

  // Binds both ROUTERs and connects to the learner. Throws std::runtime_error for a bad
  // endpoint or a port in use. `ctx` must outlive the server.
  ShardServer(net::Context& ctx, ShardServerOptions options, ShardConfigFromMap config_from_map);
  ~ShardServer();
  ShardServer(const ShardServer&) = delete;
  ShardServer& operator=(const ShardServer&) = delete;

  // Connectable endpoints as advertised to the learner (valid after construction).
  [[nodiscard]] const std::string& insert_endpoint() const { return insert_endpoint_; }
  [[nodiscard]] const std::string& sample_endpoint() const { return sample_endpoint_; }

  // Serves until stop(); call once. Throws std::runtime_error if the learner's first config
  // does not describe a shard (a later one that does not is logged and ignored), or if the
  // snapshot cannot be read (wrong shape, corrupt) or written.
  void run();
  void stop() noexcept { stop_.store(true, std::memory_order_relaxed); }
  [[nodiscard]] ShardCounters counters() const;

  // Heartbeat.counters layout sent to the learner.
  enum HeartbeatCounter { kHbInserted, kHbSampled, kHbMalformed, kHbWaiting, kHbBlockedMs, kHbSize, kHbCount };

 private:
  struct WaitingRequest {
    std::array<uint8_t, 256> identity{};  // ZeroMQ routing ids are at most 255 bytes
    uint8_t identity_size = 0;
    uint64_t request_id = 0;
    uint32_t batch_size = 0;
    uint32_t demo_batch_size = 0;
  };
  // Once-per-second logging per kind of event, with the number of events in between.
  struct LogGate {
    std::chrono::steady_clock::duration interval = std::chrono::seconds(1);
    std::optional<std::chrono::steady_clock::time_point> last;
    int64_t suppressed = 0;  // events since the last line
    bool open(std::chrono::steady_clock::time_point now);
  };
  using Clock = std::chrono::steady_clock;

  void send_join(Clock::time_point now);
  void send_heartbeat(Clock::time_point now);
  void read_join_socket(Clock::time_point now);
  void take_cluster_map(const wire::ClusterMap& map, Clock::time_point now);
  void read_insert_socket(Clock::time_point now);
  // Stores a verified batch in its table; returns the transitions stored (0: refused, counted).
  uint32_t insert_batch(const wire::TransitionBatch& batch, uint32_t obs, uint32_t act, Clock::time_point now);
  // Sends an InsertAck to the sender of the frame just read.
  void acknowledge(uint64_t sequence, uint32_t inserted);
  void read_sample_socket(Clock::time_point now);
  void serve_waiting_requests(Clock::time_point now);
  void malformed(LogGate& gate, const char* socket, const char* why, Clock::time_point now);
  // A frame over its socket's limit (net::Socket::too_big): counted as malformed, and per peer.
  void oversized(LogGate& gate, const char* socket, const std::string& peer, size_t bytes, int64_t limit,
                 Clock::time_point now);
  void publish_counters();

  ShardServerOptions options_;
  ShardConfigFromMap config_from_map_;
  net::Socket insert_;
  net::Socket sample_;
  net::Socket join_;
  net::HandshakeMonitor handshakes_;  // after the sockets: stops watching before they close
  std::string insert_endpoint_;
  std::string sample_endpoint_;
  // One poller per set of sockets worth reading: join always, insert only while the limiter
  // admits inserts, sample only while the waiting queue has room.
  net::Poller poll_all_, poll_join_insert_, poll_join_sample_, poll_join_;

  std::unique_ptr<ReplayShard> shard_;
  flatbuffers::FlatBufferBuilder fbb_{1 << 16};
  flatbuffers::FlatBufferBuilder ack_fbb_{64};
  net::Message identity_;
  net::Message frame_;
  std::array<WaitingRequest, kMaxWaitingRequests> waiting_{};
  int waiting_head_ = 0;
  int waiting_count_ = 0;

  bool joined_ = false;
  uint64_t map_version_ = 0;
  int heartbeat_ms_ = 1000;
  int peer_timeout_ms_ = 5000;
  Clock::time_point next_join_{};
  Clock::time_point next_heartbeat_{};
  Clock::time_point last_heard_learner_{};
  Clock::time_point last_tick_{};
  Clock::time_point next_snapshot_{};
  Clock::time_point started_{};
  bool inserts_held_ = false;
  Clock::duration blocked_{};
  LogGate log_insert_, log_sample_, log_join_, log_reply_, log_waiting_, log_silent_, log_duplicate_;
  // Deduplication per writer (TransitionBatch.writer), as IPsec's anti-replay window: the newest
  // sequence stored and which of the kWindow sequences below it were stored. A batch is refused
  // as a duplicate only if its own sequence was stored. An older one not stored yet is a late
  // first arrival and is stored: after a partition, a batch held in the old connection's
  // retransmissions can arrive after newer ones sent on the new connection (the soak saw one 165
  // sequences late). One older than the window cannot be checked and is refused as stale; its
  // actor had already counted it lost with its connection. Reserved at kMaxWriters; when full,
  // the writer heard from least recently is forgotten. A linear scan: a shard has tens of writers.
  static constexpr uint64_t kWindow = 1024;
  struct WriterMark {
    uint64_t writer = 0;
    uint64_t newest = 0;
    uint64_t last_seen = 0;                       // the batch count when last heard, for forgetting the oldest
    std::array<uint64_t, kWindow / 64> stored{};  // bit d: sequence newest - d was stored
  };
  static constexpr size_t kMaxWriters = 4096;
  std::vector<WriterMark> writers_;
  uint64_t batches_seen_ = 0;
  // True (and counted, as a duplicate or as stale) if the writer's batch must not be stored.
  bool duplicate(uint64_t writer, uint64_t sequence, Clock::time_point now);
  void mark_stored(uint64_t writer, uint64_t sequence);
  std::array<int64_t, kHbCount> hb_counters_{};

  net::PeerTable peers_;
  net::PeerCounters* learner_ = &peers_.peer("learner");  // join socket and sample socket
  bool learner_silent_ = false;
  net::PeerCounters& actor_peer(uint32_t actor_id);

  std::atomic<bool> stop_{false};
  bool ran_ = false;
  std::atomic<int64_t> inserted_{0}, sampled_{0}, malformed_{0}, waiting_now_{0}, blocked_ms_{0}, replies_dropped_{0},
      size_{0}, map_version_pub_{0}, joins_{0}, transitions_dropped_{0}, capacity_{0}, inserts_held_pub_{0},
      restored_{0}, demo_inserted_{0}, acks_dropped_{0}, evicted_{0}, batches_duplicate_{0}, batches_stale_{0};
};

}  // namespace pamdp
