#include "actor/learner_link.hpp"

#include "core/peer_stats.hpp"

#include <chrono>
#include <utility>

#include "core/log.hpp"
#include "core/wire.hpp"

namespace pamdp {
namespace {

using Clock = std::chrono::steady_clock;

// A ClusterMap carries the whole experiment config; anything near this size is not ours.
constexpr int64_t kMaxControlMessageBytes = 4 << 20;
constexpr int kStopCheckMs = 50;

int64_t ms_since(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t).count();
}

net::Socket make_dealer(net::Context& ctx, const LearnerLinkConfig& c) {
  net::Socket s(ctx, net::SocketType::kDealer);
  s.set_max_message_bytes(kMaxControlMessageBytes);
  if (c.curve) {
    s.make_curve_client(*c.curve);
  }
  s.connect(c.join_endpoint);
  return s;
}

bool copy_map(const wire::ClusterMap* m, ClusterInfo& out) {
  if (m->config_toml() == nullptr || m->weights_endpoint() == nullptr || m->weights_endpoint()->size() == 0) {
    return false;
  }
  out.shard_endpoints.clear();
  if (m->shard_endpoints() != nullptr) {
    for (const flatbuffers::String* e : *m->shard_endpoints()) {
      if (e == nullptr || e->size() == 0) {
        return false;
      }
      out.shard_endpoints.push_back(e->str());
    }
  }
  out.version = m->version();
  out.config_toml = m->config_toml()->str();
  out.weights_endpoint = m->weights_endpoint()->str();
  out.actor_index = m->actor_index();
  out.num_actors_hint = m->num_actors_hint();
  out.weights_version = m->weights_version();
  return true;
}

}  // namespace

struct LearnerLink::Impl {
  net::Context* ctx;
  LearnerLinkConfig config;
  net::Socket dealer;
  flatbuffers::FlatBufferBuilder fbb{4096};
  net::Message msg;
  int64_t malformed_during_join = 0;
  int64_t learner_updates = 0;
  net::PeerCounters* peer = nullptr;  // count_traffic()

  bool send() {
    const std::span<const uint8_t> bytes = wire::bytes_of(fbb);
    if (!dealer.send(bytes, 0)) {
      return false;
    }
    if (peer != nullptr) {
      peer->sent(bytes.size());
    }
    return true;
  }

  Impl(net::Context& c, LearnerLinkConfig cfg) : ctx(&c), config(std::move(cfg)), dealer(make_dealer(c, config)) {}
};

LearnerLink::LearnerLink(net::Context& ctx, LearnerLinkConfig config)
    : impl_(std::make_unique<Impl>(ctx, std::move(config))) {}
LearnerLink::~LearnerLink() = default;
LearnerLink::LearnerLink(LearnerLink&&) noexcept = default;
LearnerLink& LearnerLink::operator=(LearnerLink&&) noexcept = default;

const LearnerLinkConfig& LearnerLink::config() const {
  return impl_->config;
}
int64_t LearnerLink::learner_updates() const {
  return impl_->learner_updates;
}
void LearnerLink::count_traffic(net::PeerCounters* peer) {
  impl_->peer = peer;
}

int64_t LearnerLink::malformed_during_join() const {
  return impl_->malformed_during_join;
}

bool LearnerLink::send_join_request() {
  wire::build_join_request(impl_->fbb, wire::Role::Actor, impl_->config.name, "", "", impl_->config.actor_envs,
                           impl_->config.metrics_url);
  return impl_->send();
}

bool LearnerLink::send_heartbeat(uint64_t map_version, std::span<const int64_t> counters) {
  wire::build_heartbeat(impl_->fbb, wire::Role::Actor, impl_->config.name, map_version, counters);
  return impl_->send();
}

bool LearnerLink::send_episode_report(uint32_t actor_id, uint64_t episode, float ret, uint32_t steps, int32_t status,
                                      uint64_t policy_version, bool scripted) {
  wire::build_episode_report(impl_->fbb, actor_id, episode, ret, steps, status, policy_version, scripted);
  return impl_->send();
}

bool LearnerLink::wait_readable(int timeout_ms) {
  return impl_->dealer.wait_readable(timeout_ms);
}

LearnerLink::Received LearnerLink::receive(ClusterInfo& map, uint64_t& learner_map_version) {
  if (!impl_->dealer.recv(impl_->msg, 0)) {
    return Received::kNothing;
  }
  if (impl_->dealer.too_big(impl_->msg)) {
    if (impl_->peer != nullptr) {
      impl_->peer->refused_oversized(impl_->msg.size());
    }
    return Received::kMalformed;
  }
  if (impl_->peer != nullptr) {
    impl_->peer->received(impl_->msg.size());
  }
  const wire::Envelope* env = wire::open_envelope(impl_->msg.bytes());
  if (env == nullptr) {
    return Received::kMalformed;
  }
  switch (env->payload_type()) {
    case wire::Payload::Heartbeat: {
      const wire::Heartbeat* hb = env->payload_as_Heartbeat();
      learner_map_version = hb->map_version();
      // The learner's counters: updates first (learner_server.cpp).
      if (hb->counters() != nullptr && hb->counters()->size() > 0) {
        impl_->learner_updates = hb->counters()->Get(0);
      }
      return Received::kHeartbeat;
    }
    case wire::Payload::ClusterMap:
      return copy_map(env->payload_as_ClusterMap(), map) ? Received::kClusterMap : Received::kMalformed;
    default: return Received::kMalformed;
  }
}

std::optional<ClusterInfo> LearnerLink::join(const std::atomic<bool>& stop) {
  const LearnerLinkConfig& c = impl_->config;
  const auto start = Clock::now();
  auto last_malformed_log = start;
  ClusterInfo map;
  for (int attempt = 1; !stop.load(); ++attempt) {
    if (attempt > 1) {
      // A fresh socket drops the unanswered request still queued for a learner not yet there.
      impl_->dealer = make_dealer(*impl_->ctx, c);
    }
    send_join_request();
    if (attempt == 1) {
      log::info("actor: joining the learner at {} as '{}'", c.join_endpoint, c.name);
    }
    const auto attempt_start = Clock::now();
    while (!stop.load() && ms_since(attempt_start) < c.join_retry_ms) {
      if (c.join_timeout_ms > 0 && ms_since(start) >= c.join_timeout_ms) {
        log::error("actor: no cluster map from the learner at {} within {} ms; giving up", c.join_endpoint,
                   c.join_timeout_ms);
        return std::nullopt;
      }
      uint64_t ignored = 0;
      switch (impl_->dealer.wait_readable(kStopCheckMs) ? receive(map, ignored) : Received::kNothing) {
        case Received::kClusterMap:
          log::info("actor: joined: actor index {}, map version {}, {} shard(s), weights at {}", map.actor_index,
                    map.version, map.shard_endpoints.size(), map.weights_endpoint);
          return map;
        case Received::kMalformed:
          if (++impl_->malformed_during_join == 1 || ms_since(last_malformed_log) >= 1000) {
            last_malformed_log = Clock::now();
            log::warn("actor: dropped a malformed message from the learner while joining; {} so far",
                      impl_->malformed_during_join);
          }
          break;
        case Received::kHeartbeat:  // an answer meant for an earlier socket's heartbeat
        case Received::kNothing: break;
      }
    }
    if (!stop.load()) {
      log::warn(
          "actor: no cluster map from {} after {} ms (attempt {}); asking again (is `pamdp learner` running there, "
          "and is the address reachable from this machine?)",
          c.join_endpoint, ms_since(attempt_start), attempt);
    }
  }
  return std::nullopt;
}

}  // namespace pamdp
