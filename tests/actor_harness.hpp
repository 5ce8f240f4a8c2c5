// Test doubles for the actor role: a fake learner (join ROUTER + weights PUB) and a fake replay
// shard (insert ROUTER, acknowledging every batch it reads), both bound on tcp://127.0.0.1:* with the ports read back,
// and a runner that joins and runs an ActorLoop on its own thread over ReachStop envs. Nothing sleeps: the fakes wait
// on their sockets for a few milliseconds at a time until a condition holds or a deadline passes.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "actor/actor_loop.hpp"
#include "actor/learner_link.hpp"
#include "core/transport.hpp"
#include "core/wire.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp::testing {

inline constexpr uint32_t kObs = toy::ReachStopEnv::kObservationSize;  // 3
inline constexpr uint32_t kWidth = 3;                                  // MOVE, STOP scores + velocity
inline constexpr const char* kConfigToml = "[env]\nname = \"reach_stop\"\n";

using Bytes = std::vector<uint8_t>;

// Deadlines in these tests are multiplied by PAMDP_TEST_TIME_SCALE (default 1): sanitizer builds
// run many times slower (tests/sanitize.sh --thread sets 10).
inline int scaled_ms(int ms) {
  static const int scale = [] {
    const char* s = std::getenv("PAMDP_TEST_TIME_SCALE");
    const int v = s != nullptr ? std::atoi(s) : 1;
    return v >= 1 ? v : 1;
  }();
  return ms * scale;
}

inline Bytes copy_bytes(std::span<const uint8_t> b) {
  return {b.begin(), b.end()};
}

struct BatchCopy {
  uint32_t actor_id = 0;
  uint64_t sequence = 0;
  uint32_t count = 0;
  uint8_t table = 0;  // wire::kReplayTable or wire::kDemoTable
  std::vector<float> states, actions, rewards, next_states, returns;
  std::vector<uint8_t> terminals;
};

struct ReportCopy {
  uint32_t actor_id = 0;
  uint64_t episode = 0;
  float ret = 0.0F;
  uint32_t steps = 0;
  int32_t status = 0;
  uint64_t policy_version = 0;
  bool scripted = false;
};

struct JoinCopy {
  Bytes identity;
  wire::Role role = wire::Role::Monitor;
  std::string name;
  uint32_t actor_envs = 0;
};

class FakeShard {
 public:
  // Binds `endpoint` (a restarted shard takes its predecessor's) or any free loopback port.
  explicit FakeShard(net::Context& ctx, int recv_hwm = 1000, const std::string& endpoint = "tcp://127.0.0.1:*")
      : router_(ctx, net::SocketType::kRouter) {
    router_.set_recv_hwm(recv_hwm);
    router_.set_kernel_buffers(1 << 16, 1 << 16);
    endpoint_ = router_.bind(endpoint);
  }
  [[nodiscard]] const std::string& endpoint() const { return endpoint_; }

  // Receives what arrives within timeout_ms (then whatever else is queued).
  void serve(int timeout_ms) {
    if (!reading || !router_.wait_readable(timeout_ms)) {
      return;
    }
    while (router_.recv_from(identity_msg_, payload_, 0)) {
      identity = copy_bytes(identity_msg_.bytes());
      const wire::Envelope* env = wire::open_envelope(payload_.bytes());
      const wire::TransitionBatch* b = env != nullptr && env->payload_type() == wire::Payload::TransitionBatch
                                           ? env->payload_as_TransitionBatch()
                                           : nullptr;
      if (b != nullptr && acking) {
        wire::build_insert_ack(ack_fbb_, b->sequence(), wire::valid_batch(b, kObs, kWidth, 64) ? b->count() : 0);
        router_.send_to(identity, wire::bytes_of(ack_fbb_), 0);
      }
      if (b == nullptr || !wire::valid_batch(b, kObs, kWidth, 64)) {
        ++invalid;
        continue;
      }
      const wire::TransitionRows r = wire::rows_of(b);
      BatchCopy c;
      c.actor_id = b->actor_id();
      c.sequence = b->sequence();
      c.table = b->table();
      c.count = r.count;
      c.states.assign(r.states, r.states + r.count * kObs);
      c.next_states.assign(r.next_states, r.next_states + r.count * kObs);
      c.actions.assign(r.actions, r.actions + r.count * kWidth);
      c.rewards.assign(r.rewards, r.rewards + r.count);
      c.returns.assign(r.mc_returns, r.mc_returns + r.count);
      c.terminals.assign(r.terminals, r.terminals + r.count);
      batches.push_back(std::move(c));
    }
  }

  void send_to_actor(std::span<const uint8_t> bytes) { router_.send_to(identity, bytes, 100); }
  // Acknowledges the batch `sequence` (and so every earlier one) by hand.
  void ack(uint64_t sequence) {
    wire::build_insert_ack(ack_fbb_, sequence, 0);
    router_.send_to(identity, wire::bytes_of(ack_fbb_), 100);
  }

  bool reading = true;
  bool acking = true;  // answers every batch read with an InsertAck, as the real shard does
  std::vector<BatchCopy> batches;
  int invalid = 0;
  Bytes identity;  // the actor's DEALER, once it has sent something

 private:
  net::Socket router_;
  std::string endpoint_;
  net::Message identity_msg_, payload_;
  flatbuffers::FlatBufferBuilder ack_fbb_{64};
};

class FakeLearner {
 public:
  explicit FakeLearner(net::Context& ctx) : join_(ctx, net::SocketType::kRouter), pub_(ctx, net::SocketType::kPub) {
    join_endpoint_ = join_.bind("tcp://127.0.0.1:*");
    weights_endpoint_ = pub_.bind("tcp://127.0.0.1:*");
  }
  [[nodiscard]] const std::string& join_endpoint() const { return join_endpoint_; }
  [[nodiscard]] const std::string& weights_endpoint() const { return weights_endpoint_; }

  void serve(int timeout_ms) {
    if (!join_.wait_readable(timeout_ms)) {
      return;
    }
    while (join_.recv_from(identity_msg_, payload_, 0)) {
      const Bytes id = copy_bytes(identity_msg_.bytes());
      const wire::Envelope* env = wire::open_envelope(payload_.bytes());
      ASSERT_NE(env, nullptr) << "the actor sent a frame that does not verify";
      switch (env->payload_type()) {
        case wire::Payload::JoinRequest: {
          const auto* j = env->payload_as_JoinRequest();
          joins.push_back({id, j->role(), j->name() != nullptr ? j->name()->str() : "", j->actor_envs()});
          if (ignore_joins > 0) {
            --ignore_joins;
            break;
          }
          actor_identity = id;
          wire::build_cluster_map(fbb_, map_version, kConfigToml, shard_endpoints, {}, weights_endpoint_, actor_index,
                                  actor_index + 1, 0);
          join_.send_to(id, wire::bytes_of(fbb_), 100);
          break;
        }
        case wire::Payload::Heartbeat: {
          const auto* h = env->payload_as_Heartbeat();
          ++heartbeats;
          if (h->counters() != nullptr) {
            last_heartbeat_counters.assign(h->counters()->begin(), h->counters()->end());
          }
          wire::build_heartbeat(fbb_, wire::Role::Learner, "learner", map_version, {});
          join_.send_to(id, wire::bytes_of(fbb_), 100);
          break;
        }
        case wire::Payload::EpisodeReport: {
          const auto* r = env->payload_as_EpisodeReport();
          reports.push_back(
              {r->actor_id(), r->episode(), r->return_(), r->steps(), r->status(), r->policy_version(), r->scripted()});
          break;
        }
        default: ADD_FAILURE() << "unexpected message type from the actor";
      }
    }
  }

  void publish(std::span<const uint8_t> bytes) { pub_.send(bytes, 100); }
  void send_to_actor(std::span<const uint8_t> bytes) { join_.send_to(actor_identity, bytes, 100); }

  // Answers to the next joins.
  uint64_t map_version = 1;
  uint32_t actor_index = 0;
  std::vector<std::string> shard_endpoints;
  int ignore_joins = 0;  // leave this many JoinRequests unanswered

  std::vector<JoinCopy> joins;
  std::vector<ReportCopy> reports;
  std::vector<int64_t> last_heartbeat_counters;
  int heartbeats = 0;
  Bytes actor_identity;

 private:
  net::Socket join_;
  net::Socket pub_;
  std::string join_endpoint_, weights_endpoint_;
  net::Message identity_msg_, payload_;
  flatbuffers::FlatBufferBuilder fbb_;
};

// Settings that make the control plane fast enough for tests.
inline ActorLoopConfig test_loop_config() {
  ActorLoopConfig c;
  c.gamma = 0.9;
  c.batch_transitions = 64;
  c.heartbeat_ms = 20;
  c.peer_timeout_ms = scaled_ms(1000);
  c.tick_ms = 20;
  c.seed = 7;
  return c;
}

// Joins and runs an ActorLoop over `envs` ReachStop envs on its own thread; stops and joins the
// thread on destruction. Declare it after the fakes and the Context it uses.
class ActorRunner {
 public:
  // make_env: the envs it steps (ReachStop by default).
  ActorRunner(net::Context& ctx, const std::string& join_endpoint, ActorLoopConfig config, int envs = 2,
              int join_retry_ms = 2000, std::function<void(const ActorCounters&, double)> on_tick = nullptr,
              std::function<std::unique_ptr<Env>()> make_env = nullptr) {
    thread_ = std::thread([this, &ctx, join_endpoint, config, envs, join_retry_ms, on_tick, make_env] {
      LearnerLinkConfig lc;
      lc.join_endpoint = join_endpoint;
      lc.name = "test-actor";
      lc.actor_envs = static_cast<uint32_t>(envs);
      lc.join_retry_ms = join_retry_ms;
      LearnerLink link(ctx, lc);
      const std::optional<ClusterInfo> map = link.join(stop);
      if (!map) {
        return;
      }
      config_toml = map->config_toml;
      std::vector<std::unique_ptr<Env>> list;
      for (int k = 0; k < envs; ++k) {
        list.push_back(make_env ? make_env() : std::make_unique<toy::ReachStopEnv>());
      }
      ActorLoop loop(ctx, std::move(link), *map, std::move(list), config, counters);
      loop.on_tick = on_tick;
      loop.on_episode = [this](int /*status*/, double /*ret*/, int /*steps*/) { agent_episodes.fetch_add(1); };
      running = true;
      loop.run(stop);
    });
  }
  ~ActorRunner() {
    stop = true;
    thread_.join();
  }
  ActorRunner(const ActorRunner&) = delete;
  ActorRunner& operator=(const ActorRunner&) = delete;

  ActorCounters counters;
  std::atomic<bool> stop{false};
  std::atomic<bool> running{false};
  std::atomic<int64_t> agent_episodes{0};  // on_episode calls: the episodes the agent played
  std::string config_toml;                 // written by the actor thread before `running`

 private:
  std::thread thread_;
};

// Serves the fakes until `done()` holds or timeout_ms passes; returns done().
template <typename Done>
bool serve_until(FakeLearner& learner, std::vector<FakeShard*> shards, Done done, int timeout_ms = 2500) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(scaled_ms(timeout_ms));
  while (!done()) {
    if (std::chrono::steady_clock::now() >= deadline) {
      return false;
    }
    learner.serve(1);
    for (FakeShard* s : shards) {
      s->serve(1);
    }
  }
  return true;
}

// The actor network of the tests: widths {3, 4, 3}, every weight zero, so the output is the
// output layer's biases whatever the observation.
inline std::vector<float> constant_output_params(const std::vector<float>& output) {
  std::vector<float> p(3 * 4 + 4 + 4 * 3 + 3, 0.0F);
  std::copy(output.begin(), output.end(), p.end() - 3);
  return p;
}
inline constexpr std::array<int, 3> kTestWidths{3, 4, 3};

}  // namespace pamdp::testing
