// Traffic and liveness per peer of one process (docs/reliability.md, "A bad network"): messages
// and bytes in and out, reconnects, frames refused for size, and when the peer was last heard
// from. /metrics exports them with a `peer` label (app/role_metrics.hpp, register_peer_metrics).
//
// The network thread counts (relaxed atomics: no lock, no allocation); the metrics thread reads.
// PeerTable::peer() adds a peer on first sight, taking a lock and allocating once per peer; a
// caller keeps the reference for its hot path. Peers are never removed (a vanished one shows as
// silent); past max_peers new names share one entry, "other", so the series stay bounded.
#pragma once
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>

namespace pamdp::net {

struct PeerCounters {
  explicit PeerCounters(std::string n) : name(std::move(n)) {}
  const std::string name;  // "learner", "actor:HOST-PID", "replay:HOST-PID", "replay:tcp://HOST:PORT"
  std::atomic<int64_t> messages_in{0};
  std::atomic<int64_t> bytes_in{0};
  std::atomic<int64_t> messages_out{0};
  std::atomic<int64_t> bytes_out{0};
  std::atomic<int64_t> reconnects{0};        // connections lost and made again, or joins from a new connection
  std::atomic<int64_t> last_in_ns{0};        // steady_clock of the last message from it; 0 = never
  std::atomic<int64_t> refused_for_size{0};  // frames over the receiving socket's limit, not read

  void received(size_t bytes) {
    messages_in.fetch_add(1, std::memory_order_relaxed);
    bytes_in.fetch_add(static_cast<int64_t>(bytes), std::memory_order_relaxed);
    last_in_ns.store(std::chrono::steady_clock::now().time_since_epoch().count(), std::memory_order_relaxed);
  }
  void sent(size_t bytes) {
    messages_out.fetch_add(1, std::memory_order_relaxed);
    bytes_out.fetch_add(static_cast<int64_t>(bytes), std::memory_order_relaxed);
  }
  void reconnected() { reconnects.fetch_add(1, std::memory_order_relaxed); }
  // A frame over the receiving socket's limit (net::Socket::too_big): received, then refused unread.
  void refused_oversized(size_t bytes) {
    received(bytes);
    refused_for_size.fetch_add(1, std::memory_order_relaxed);
  }
  // Seconds since the last message; -1 if none yet.
  [[nodiscard]] double silence_seconds(std::chrono::steady_clock::time_point now) const;
};

class PeerTable {
 public:
  explicit PeerTable(size_t max_peers = 256) : max_peers_(max_peers) {}
  PeerTable(const PeerTable&) = delete;
  PeerTable& operator=(const PeerTable&) = delete;
  // The counters of `name`, added on first sight (then on_added runs, on this thread). The
  // reference stays valid for the table's lifetime.
  PeerCounters& peer(std::string_view name);
  // Whether `name` has been seen (its counters exist).
  [[nodiscard]] bool knows(std::string_view name) const;
  // Calls `on_added` for every peer known now and, from now on, for each new one (on the thread
  // that adds it). For registering metrics; set once, before traffic from other threads.
  void watch(std::function<void(PeerCounters&)> on_added);

 private:
  std::function<void(PeerCounters&)> on_added_;
  size_t max_peers_;
  mutable std::mutex mutex_;
  std::deque<PeerCounters> peers_;  // a deque: references stay valid as it grows
};

}  // namespace pamdp::net
