// The learner role of the distributed system (docs/protocol.md): binds the join socket
// (ROUTER) and the weights broadcast (PUB), hands out the cluster map, keeps several sample
// requests in flight on every replay shard, hands the replies to the run's updates as a Sampler
// (learner/sampler.hpp), publishes weights every N updates, and collects episode reports.
//
// One thread calls next() (or run()); stop() may be called from any thread or a signal handler. Received
// buffers are verified before use; a bad message is counted and dropped. The update path reads
// sampled rows in place from the received buffers (row-major rows are the column-major
// obs x batch matrices the update wants), so it copies nothing per sample.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/peer_stats.hpp"
#include "core/transport.hpp"
#include "learner/algorithm.hpp"
#include "learner/sampler.hpp"

namespace pamdp {

struct FbbHolder;

struct LearnerServerConfig {
  std::string join_bind = "tcp://127.0.0.1:5555";  // loopback by default (docs/protocol.md, "Security")
  std::string weights_bind = "tcp://127.0.0.1:5556";
  std::string advertise_host = "127.0.0.1";
  std::string config_toml;  // handed to every peer in the cluster map
  int64_t publish_every_updates = 100;
  int requests_in_flight_per_shard = 2;
  int heartbeat_ms = 1000;
  int peer_timeout_ms = 5000;
  int64_t max_updates = INT64_MAX;
  double max_seconds = 0.0;                          // 0 = no limit
  std::string metrics_url;                           // this learner's own, first in metrics_urls()
  std::optional<net::CurveServerKeys> curve;         // CURVE on both bound sockets when set
  std::optional<net::CurveClientKeys> curve_client;  // for the learner's own connections to shards
  int64_t weights_version = 0;                       // last version published (a resumed run goes on from it)
  // Cloning (ddpg.demo_bc_weight > 0): every sample request also asks for a batch from the
  // shards' demonstration table, and an update whose reply carries one clones it
  // (Algorithm::update(batch, &demos)); until a shard holds demonstrations, plain updates.
  bool clone_demos = false;
};

struct LearnerCounters {
  int64_t updates = 0;
  int64_t samples_received = 0;
  int64_t demo_samples_received = 0;  // demonstrations cloned (clone_demos)
  int64_t malformed_messages = 0;
  int64_t episodes = 0;
  int64_t weights_version = 0;
  int64_t shards = 0;
  int64_t actors_joined = 0;
  int64_t actors_alive = 0;  // actors heard from within peer_timeout_ms
  int64_t waiting_for_data_ms = 0;
  int64_t connections_refused = 0;      // failed handshakes at the join and weights sockets (no or wrong CURVE key)
  int64_t episode_reports_refused = 0;  // dropped: the sender has not joined this learner as an actor
};

struct EpisodeSummary {
  uint32_t actor_id;
  float ret;
  uint32_t steps;
  int32_t status;
  uint64_t policy_version;  // weights version the actor played the episode with
  bool scripted = false;    // a demonstration: the teacher played it
};

class LearnerServer final : public Sampler {
 public:
  // `algorithm` is owned by the caller and must outlive the server. Its acting networks are
  // synced to the host before each broadcast.
  LearnerServer(net::Context& ctx, Algorithm& algorithm, LearnerServerConfig config);
  ~LearnerServer() override;

  // Resolved, connectable endpoints (valid after construction).
  [[nodiscard]] const std::string& join_endpoint() const { return join_endpoint_; }
  [[nodiscard]] const std::string& weights_endpoint() const { return weights_endpoint_; }

  // Called on the learner thread for every episode report. May be empty.
  std::function<void(const EpisodeSummary&)> on_episode;
  // Called by run() after every update. May be empty.
  std::function<void(const UpdateStats&)> on_update;
  // Called about once per second with the counters (progress lines, metrics).
  std::function<void(const LearnerCounters&)> on_tick;
  // Called on the learner thread when the cluster's metrics URLs change (a peer joins with one,
  // or is silent for peer_timeout_ms), and once when run() starts.
  std::function<void(const std::vector<std::string>& urls)> on_metrics_urls;

  // The next shard reply as a minibatch, valid until the next call; the caller updates on it at
  // once (the counters count it as an update). Serves the sockets meanwhile: joins, heartbeats,
  // episode reports, ticks, dead shards, and the weights every publish_every_updates updates
  // counted since the previous call. Waits as long as no shard has data; nullptr, after a last
  // broadcast, once stop(), max_updates or max_seconds ends the run.
  const Sample* next() override;
  // next() and an update on every sample (on_update after each), until next() ends the run.
  void run();
  void stop() { stop_.store(true); }
  [[nodiscard]] const LearnerCounters& counters() const { return counters_; }
  // Handshakes refused at the join and weights sockets so far; any thread (counters() copies it
  // once a second).
  [[nodiscard]] int64_t connections_refused() const { return handshakes_.refused(); }
  // The learner's own metrics URL first, then the live peers' (shards, then actors), as served
  // to `pamdp monitor` (MetricsUrlsRequest). Learner thread only.
  [[nodiscard]] const std::vector<std::string>& metrics_urls() const { return metrics_urls_; }
  void publish_weights();
  // Traffic and liveness per peer ("actor:NAME", "replay:NAME"), for /metrics; counted on the
  // learner thread.
  [[nodiscard]] net::PeerTable& peers() { return peers_table_; }

 private:
  struct Shard;
  // Every actor and shard that joined, by join-socket identity, for liveness and metrics URLs.
  struct Peer {
    bool actor = false;
    std::string metrics_url;
    std::chrono::steady_clock::time_point last_heard;
    net::PeerCounters* traffic = nullptr;  // in peers_table_, by the name it joined with
  };
  void handle_join_socket();
  void refresh_peers(bool drop_silent);
  // One reply read from the shard: the minibatch it carries, or nullptr (none, or malformed).
  const Sample* take_reply(Shard& shard);
  void begin();
  [[nodiscard]] bool limit_reached() const;
  // After a round's shards were read: the join socket, requests, dead shards, ticks.
  void end_round();
  void request_samples(Shard& shard);
  void drop_dead_shards();
  // After shards_ changed: a new map version, and the shard count the counters report.
  void shards_changed();
  void send_map(std::span<const uint8_t> identity, uint32_t actor_index);
  void count_sent(std::span<const uint8_t> identity, size_t bytes);
  void note_malformed(const char* what);

  net::Context& ctx_;
  Algorithm& algorithm_;
  LearnerServerConfig config_;
  net::Socket join_;
  net::Socket weights_;
  net::HandshakeMonitor handshakes_;  // after the sockets: stops watching before they close
  std::string join_endpoint_;
  std::string weights_endpoint_;
  std::vector<std::unique_ptr<Shard>> shards_;
  uint64_t map_version_ = 1;
  uint64_t next_request_id_ = 1;
  uint32_t next_actor_index_ = 0;
  std::map<std::vector<uint8_t>, uint32_t> actor_index_;  // join-socket identity -> actor index
  LearnerCounters counters_;
  std::atomic<bool> stop_{false};
  std::chrono::steady_clock::time_point last_malformed_log_{};
  std::unique_ptr<FbbHolder> fbb_;
  int64_t last_published_at_ = -1;
  std::vector<float> terminal_scratch_;
  std::vector<float> demo_terminal_scratch_;
  net::Message reply_;
  std::optional<std::chrono::steady_clock::time_point> republish_at_;
  std::map<std::string, Peer> peers_;  // by join-socket identity (bytes)
  net::PeerTable peers_table_;
  std::vector<std::string> metrics_urls_;
  // The sampling loop's state between next() calls: one poll is a round, whose readable shards
  // are read in turn, one reply per call.
  Sample sample_;
  net::Poller poller_;
  uint64_t poller_version_ = 0;
  size_t polled_ = 0;
  size_t cursor_ = 0;
  bool round_open_ = false;
  bool round_sampled_ = false;
  bool started_ = false;
  bool finished_ = false;
  bool waiting_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_tick_;
  std::chrono::steady_clock::time_point waiting_since_;
};

}  // namespace pamdp
