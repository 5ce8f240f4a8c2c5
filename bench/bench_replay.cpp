// One replay shard (replay/shard_server.hpp) on its own thread behind real loopback TCP
// sockets, with the HFO widths (obs 58, action 10) and a fake learner that answers the join.
// BM_ReplayInsertTcp/64: an actor's DEALER sends TransitionBatches of 64 transitions as fast as
//   the shard stores them (verify, validate, copy into the ring, InsertAck); items = transitions
//   stored. Up to 32 batches in flight: the data path's own rate, the reference.
// BM_ReplayInsertTcpAcked/64/W: the same, paced as an actor paces its sends to one shard: at most
//   W batches unacknowledged (cluster.actor_batches_in_flight), the next sent as soon as an
//   InsertAck frees one. Its ratio to BM_ReplayInsertTcp/64 is what the window costs one actor.
// BM_ReplaySampleTcp/N: the learner's DEALER keeps N SampleRequests of 32 in flight and
//   verifies every reply (open_envelope) before sending the next; items = transitions received.
// The rate limiter is configured out of the way (huge slack): these measure the data path.
#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/log.hpp"
#include "core/rng.hpp"
#include "core/transport.hpp"
#include "core/wire.hpp"
#include "replay/shard_server.hpp"

namespace {

using pamdp::ShardConfig;
using pamdp::ShardServer;
namespace net = pamdp::net;
namespace wire = pamdp::wire;

constexpr int kObs = 58;
constexpr int kAct = 10;

// A joined shard serving on its own thread.
class BenchShard {
 public:
  BenchShard() : learner_(peer_ctx_, net::SocketType::kRouter) {
    pamdp::log::set_level("warn");
    ShardConfig config;
    config.capacity = 250000;  // replay.capacity 500,000 over 2 shards
    config.obs_dim = kObs;
    config.action_dim = kAct;
    config.limiter = {.samples_per_insert = 1.0, .min_size = 1, .slack = int64_t{1} << 50};
    config.heartbeat_ms = 1000;
    config.peer_timeout_ms = 1 << 30;
    pamdp::ShardServerOptions options;
    options.join_endpoint = learner_.bind("tcp://127.0.0.1:*");
    options.insert_bind = options.sample_bind = "tcp://127.0.0.1:*";
    server_ = std::make_unique<ShardServer>(ctx_, options, [config](const std::string&) { return config; });
    loop_ = std::thread([this] { server_->run(); });
    net::Message id;
    net::Message frame;
    if (!learner_.recv_from(id, frame, 5000)) {
      throw std::runtime_error("bench: the shard did not join");
    }
    flatbuffers::FlatBufferBuilder fbb;
    wire::build_cluster_map(fbb, 1, "bench", {}, {}, "", 0, 0, 0);
    learner_.send_to(id.bytes(), wire::bytes_of(fbb), 1000);
    while (server_->counters().joins == 0) {
      std::this_thread::yield();
    }
  }
  ~BenchShard() {
    server_->stop();
    loop_.join();
  }
  BenchShard(const BenchShard&) = delete;
  BenchShard& operator=(const BenchShard&) = delete;
  // The peers' context: in a cluster they are other processes with their own I/O threads.
  net::Context& peer_ctx() { return peer_ctx_; }
  ShardServer& server() { return *server_; }
  void wait_inserted(int64_t n) {
    while (server_->counters().inserted < n) {
      std::this_thread::yield();
    }
  }

 private:
  net::Context ctx_;
  net::Context peer_ctx_;
  net::Socket learner_;
  std::unique_ptr<ShardServer> server_;
  std::thread loop_;
};

// One TransitionBatch of `count` HFO transitions with plausible values.
std::vector<uint8_t> hfo_batch(uint32_t count) {
  pamdp::Rng rng(5);
  std::vector<float> states(size_t{count} * kObs), next(size_t{count} * kObs), actions(size_t{count} * kAct);
  std::vector<float> rewards(count), returns(count);
  std::vector<uint8_t> terminals(count, 0);
  for (auto* v : {&states, &next, &actions, &rewards, &returns}) {
    for (float& x : *v) {
      x = static_cast<float>(rng.uniform(-1.0, 1.0));
    }
  }
  flatbuffers::FlatBufferBuilder fbb;
  wire::build_transition_batch(fbb, 0, 0,
                               {count, kObs, kAct, states.data(), actions.data(), rewards.data(), next.data(),
                                terminals.data(), returns.data()});
  const auto bytes = wire::bytes_of(fbb);
  return {bytes.begin(), bytes.end()};
}

void BM_ReplayInsertTcp(benchmark::State& state) {
  const auto batch = static_cast<uint32_t>(state.range(0));
  BenchShard shard;
  net::Socket actor(shard.peer_ctx(), net::SocketType::kDealer);
  actor.connect(shard.server().insert_endpoint());
  const std::vector<uint8_t> message = hfo_batch(batch);
  constexpr int kRound = 16;  // batches per iteration
  int64_t sent = 0;
  net::Message ack;
  for (auto _ : state) {
    for (int i = 0; i < kRound; ++i) {
      actor.send(message, -1);
    }
    sent += int64_t{kRound} * batch;
    // At most two rounds in flight, so the untimed tail below is small.
    shard.wait_inserted(sent - 2 * int64_t{kRound} * batch);
    while (actor.recv(ack, 0)) {
    }
  }
  shard.wait_inserted(sent);
  state.SetItemsProcessed(sent);
  state.SetBytesProcessed(sent / batch * static_cast<int64_t>(message.size()));
  state.counters["malformed"] = static_cast<double>(shard.server().counters().malformed);
}
BENCHMARK(BM_ReplayInsertTcp)->Arg(64)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_ReplayInsertTcpAcked(benchmark::State& state) {
  const auto batch = static_cast<uint32_t>(state.range(0));
  const auto window = static_cast<int>(state.range(1));
  BenchShard shard;
  net::Socket actor(shard.peer_ctx(), net::SocketType::kDealer);
  actor.connect(shard.server().insert_endpoint());
  const std::vector<uint8_t> message = hfo_batch(batch);
  net::Message ack;
  int unacked = 0;
  int64_t sent = 0;
  for (auto _ : state) {
    if (unacked == window) {
      if (!actor.recv(ack, 5000)) {
        state.SkipWithError("no InsertAck within 5 s");
        break;
      }
      --unacked;  // one ack per batch read: each frees one batch
    }
    actor.send(message, -1);
    ++unacked;
    sent += batch;
  }
  shard.wait_inserted(sent);
  state.SetItemsProcessed(sent);
  state.counters["malformed"] = static_cast<double>(shard.server().counters().malformed);
}
BENCHMARK(BM_ReplayInsertTcpAcked)
    ->Args({64, 1})
    ->Args({64, 2})
    ->Args({64, 4})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

void BM_ReplaySampleTcp(benchmark::State& state) {
  const int in_flight = static_cast<int>(state.range(0));
  constexpr uint32_t kBatch = 32;
  BenchShard shard;
  {
    net::Socket actor(shard.peer_ctx(), net::SocketType::kDealer);
    actor.connect(shard.server().insert_endpoint());
    const std::vector<uint8_t> message = hfo_batch(64);
    for (int i = 0; i < 160; ++i) {  // 10,240 transitions to sample from
      actor.send(message, -1);
    }
    shard.wait_inserted(int64_t{160} * 64);
  }
  net::Socket learner(shard.peer_ctx(), net::SocketType::kDealer);
  learner.connect(shard.server().sample_endpoint());
  flatbuffers::FlatBufferBuilder fbb;
  net::Message reply;
  uint64_t next_id = 0;
  auto request = [&] {
    wire::build_sample_request(fbb, next_id++, kBatch);
    learner.send(wire::bytes_of(fbb), -1);
  };
  for (int i = 0; i < in_flight; ++i) {
    request();
  }
  int64_t received = 0;
  for (auto _ : state) {
    if (!learner.recv(reply, 5000)) {
      state.SkipWithError("no SampleReply within 5 s");
      break;
    }
    const wire::Envelope* env = wire::open_envelope(reply.bytes());
    if (env == nullptr || env->payload_type() != wire::Payload::SampleReply) {
      state.SkipWithError("bad SampleReply");
      break;
    }
    received += env->payload_as_SampleReply()->batch()->count();
    request();
  }
  for (int i = 0; i < in_flight; ++i) {
    learner.recv(reply, 5000);
  }
  state.SetItemsProcessed(received);
}
BENCHMARK(BM_ReplaySampleTcp)->Arg(1)->Arg(4)->Arg(8)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace
