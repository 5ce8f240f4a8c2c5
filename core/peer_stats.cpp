#include "core/peer_stats.hpp"

#include <utility>
#include <vector>

namespace pamdp::net {

double PeerCounters::silence_seconds(std::chrono::steady_clock::time_point now) const {
  const int64_t last = last_in_ns.load(std::memory_order_relaxed);
  if (last == 0) {
    return -1.0;
  }
  const std::chrono::steady_clock::time_point then{std::chrono::steady_clock::duration(last)};
  return std::chrono::duration<double>(now - then).count();
}

PeerCounters& PeerTable::peer(std::string_view name) {
  PeerCounters* added = nullptr;
  std::function<void(PeerCounters&)> on_added;
  {
    const std::lock_guard lock(mutex_);
    for (PeerCounters& p : peers_) {
      if (p.name == name) {
        return p;
      }
    }
    if (peers_.size() >= max_peers_) {
      for (PeerCounters& p : peers_) {
        if (p.name == "other") {
          return p;
        }
      }
      name = "other";
    }
    added = &peers_.emplace_back(std::string(name));
    on_added = on_added_;  // read under the lock: watch() may set it from another thread
  }
  // Outside the lock: on_added takes the metrics registry's lock, whose collect hooks read peers.
  if (on_added) {
    on_added(*added);
  }
  return *added;
}

void PeerTable::watch(std::function<void(PeerCounters&)> on_added) {
  std::vector<PeerCounters*> known;
  {
    const std::lock_guard lock(mutex_);
    on_added_ = on_added;
    for (PeerCounters& p : peers_) {
      known.push_back(&p);
    }
  }
  for (PeerCounters* p : known) {
    on_added(*p);
  }
}

bool PeerTable::knows(std::string_view name) const {
  const std::lock_guard lock(mutex_);
  for (const PeerCounters& p : peers_) {
    if (p.name == name) {
      return true;
    }
  }
  return false;
}

}  // namespace pamdp::net
