// An actor's connection to the learner's join socket (docs/protocol.md, "Joining"): one DEALER
// that carries the join handshake, heartbeats and their answers, re-joins and episode reports.
//
// join() is the blocking start-up handshake: it sends JoinRequest{role=Actor} and waits, with
// bounded retries, for the ClusterMap; the caller parses the map's config, builds its envs and
// hands the link to an ActorLoop, which then uses the non-blocking calls.
//
// Ownership: owns its socket; the Context must outlive it. Movable, not copyable.
// Threading: one thread at a time (a Socket belongs to one thread).
// Cost: the send_* calls and receive() never block and, once the internal FlatBufferBuilder has
// grown, allocate nothing outside ZeroMQ except receive() of a ClusterMap (strings; rare).
// Errors: a learner that does not answer is an expected failure (join() returns nullopt, sends
// return false); a bad endpoint throws std::runtime_error from the constructor.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/transport.hpp"

namespace pamdp {
namespace net {
struct PeerCounters;
}

// What an actor needs from a ClusterMap, copied out of the received buffer.
struct ClusterInfo {
  uint64_t version = 0;
  std::string config_toml;
  std::vector<std::string> shard_endpoints;  // insert endpoints, in the learner's order
  std::string weights_endpoint;
  uint32_t actor_index = 0;
  uint32_t num_actors_hint = 0;
  uint64_t weights_version = 0;
};

struct LearnerLinkConfig {
  std::string join_endpoint;  // the learner's join ROUTER, e.g. tcp://learner:5555
  std::string name;           // shown in the learner's logs (host:pid)
  uint32_t actor_envs = 1;    // environments this actor steps (told to the learner)
  // join(): ask again, on a fresh socket, after this long without a map (a learner that comes up
  // late then sees one request, not a backlog of them).
  int join_retry_ms = 2000;
  int join_timeout_ms = 0;  // join() gives up after this long; 0 = until stopped
  std::string metrics_url;  // told to the learner in every JoinRequest; may be empty
  std::optional<net::CurveClientKeys> curve;
};

class LearnerLink {
 public:
  // Connects the DEALER (connecting does not wait for the learner).
  LearnerLink(net::Context& ctx, LearnerLinkConfig config);
  ~LearnerLink();
  LearnerLink(LearnerLink&&) noexcept;
  LearnerLink& operator=(LearnerLink&&) noexcept;
  LearnerLink(const LearnerLink&) = delete;
  LearnerLink& operator=(const LearnerLink&) = delete;

  // Blocks until the learner answers with a ClusterMap (returned), `stop` is set or
  // join_timeout_ms passes (nullopt; the reason is logged). Checks `stop` every 50 ms.
  [[nodiscard]] std::optional<ClusterInfo> join(const std::atomic<bool>& stop);

  // Non-blocking sends; false if the message could not be queued (learner gone, queue full).
  bool send_join_request();
  bool send_heartbeat(uint64_t map_version, std::span<const int64_t> counters);
  bool send_episode_report(uint32_t actor_id, uint64_t episode, float ret, uint32_t steps, int32_t status,
                           uint64_t policy_version, bool scripted = false);

  enum class Received { kNothing, kClusterMap, kHeartbeat, kMalformed };
  // Takes one message from the learner without blocking. kClusterMap fills `map`; kHeartbeat
  // sets `learner_map_version` to the map version in the learner's answer; kMalformed means a
  // frame that did not verify or a payload an actor does not expect (the caller counts it).
  Received receive(ClusterInfo& map, uint64_t& learner_map_version);
  // Waits until receive() has something (or timeout_ms passes); false on timeout.
  bool wait_readable(int timeout_ms);

  // The learner's update count in its newest heartbeat answer (0 before the first).
  [[nodiscard]] int64_t learner_updates() const;
  // Counts every message sent and received from now on into `peer` (may be nullptr: stop).
  void count_traffic(net::PeerCounters* peer);
  // Malformed messages seen by join() (receive() leaves the counting to its caller).
  [[nodiscard]] int64_t malformed_during_join() const;
  [[nodiscard]] const LearnerLinkConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pamdp
