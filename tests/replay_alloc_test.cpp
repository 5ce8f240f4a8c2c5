// Proves the replay shard's insert and sample paths allocate nothing in steady state
// (replay/shard_server.hpp): every global operator new in this binary is replaced by one that
// counts while counting is on. Its own binary, so the replacement affects no other test.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <new>
#include <thread>
#include <vector>

#include "core/transport.hpp"
#include "core/wire.hpp"
#include "counting_new.hpp"
#include "replay/shard_server.hpp"

namespace pamdp {
namespace alloc = testing::alloc;
namespace {

constexpr int kObs = 58;  // HFO widths
constexpr int kAct = 10;

struct Rows {
  std::vector<float> states, actions, rewards, next_states, mc_returns;
  std::vector<uint8_t> terminals;
  uint32_t count;
  explicit Rows(uint32_t n)
      : states(size_t{n} * kObs, 0.5F),
        actions(size_t{n} * kAct, -0.25F),
        rewards(n, 1.0F),
        next_states(size_t{n} * kObs, 0.75F),
        mc_returns(n, 2.0F),
        terminals(n, 0),
        count(n) {}
  [[nodiscard]] wire::TransitionRows view() const {
    return {count,
            kObs,
            kAct,
            states.data(),
            actions.data(),
            rewards.data(),
            next_states.data(),
            terminals.data(),
            mc_returns.data()};
  }
};

ShardConfig hfo_config() {
  ShardConfig c;
  c.capacity = 10000;
  c.obs_dim = kObs;
  c.action_dim = kAct;
  c.limiter = {.samples_per_insert = 1.0, .min_size = 1, .slack = 1000000};
  return c;
}

TEST(ReplayAlloc, ShardInsertAndSampleThroughTheWireAllocateNothing) {
  alloc::count_this_thread(true);
  ReplayShard shard(hfo_config(), 64);
  flatbuffers::FlatBufferBuilder in(1 << 16);
  flatbuffers::FlatBufferBuilder out(1 << 16);
  const Rows rows(64);
  wire::build_transition_batch(in, 1, 1, rows.view());
  auto round = [&] {
    const wire::Envelope* env = wire::open_envelope(wire::bytes_of(in));
    ASSERT_NE(env, nullptr);
    const wire::TransitionBatch* batch = env->payload_as_TransitionBatch();
    ASSERT_TRUE(wire::valid_batch(batch, kObs, kAct, 4096));
    shard.insert(wire::rows_of(batch));
    wire::build_sample_reply(out, 7, shard.sample(32));
    ASSERT_NE(wire::open_envelope(wire::bytes_of(out)), nullptr);
  };
  round();  // the builders reach their size
  alloc::CountAllocations counter(/*only_marked_threads=*/true);
  for (int i = 0; i < 200; ++i) {
    round();
  }
  EXPECT_EQ(counter.count(), 0);
}

// The whole loop: the shard's thread reading batches and requests from loopback TCP, storing,
// sampling, building and sending replies, and heartbeating.
TEST(ReplayAlloc, ServerLoopAllocatesNothingInSteadyState) {
  net::Context ctx;
  net::Socket learner(ctx, net::SocketType::kRouter);
  const std::string join_endpoint = learner.bind("tcp://127.0.0.1:*");
  ShardServerOptions o;
  o.join_endpoint = join_endpoint;
  o.insert_bind = o.sample_bind = "tcp://127.0.0.1:*";
  o.join_retry_ms = 20;
  o.poll_ms = 5;
  ShardConfig config = hfo_config();
  config.heartbeat_ms = 10;  // several heartbeats inside the counted window
  ShardServer server(ctx, o, [config](const std::string&) { return config; });
  std::thread loop([&] {
    alloc::count_this_thread(true);
    server.run();
  });

  flatbuffers::FlatBufferBuilder fbb;
  net::Message id, frame;
  ASSERT_TRUE(learner.recv_from(id, frame, 5000));
  wire::build_cluster_map(fbb, 1, "cfg", {}, {}, "", 0, 0, 0);
  ASSERT_TRUE(learner.send_to(id.bytes(), wire::bytes_of(fbb), 1000));

  net::Socket actor(ctx, net::SocketType::kDealer);
  actor.connect(server.insert_endpoint());
  net::Socket sampler(ctx, net::SocketType::kDealer);
  sampler.connect(server.sample_endpoint());
  const Rows rows(64);
  flatbuffers::FlatBufferBuilder batch;
  wire::build_transition_batch(batch, 1, 1, rows.view());
  flatbuffers::FlatBufferBuilder request;
  wire::build_sample_request(request, 1, 32);
  auto round = [&] {
    ASSERT_TRUE(actor.send(wire::bytes_of(batch), 1000));
    ASSERT_TRUE(sampler.send(wire::bytes_of(request), 1000));
    ASSERT_TRUE(sampler.recv(frame, 2000));
    while (learner.recv_from(id, frame, 0)) {  // heartbeats, unanswered
    }
  };
  for (int i = 0; i < 100; ++i) {
    round();
  }
  long allocations = 0;
  {
    alloc::CountAllocations counter(/*only_marked_threads=*/true);
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < 300; ++i) {
      round();
    }
    allocations = counter.count();
    EXPECT_GT(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(0));
  }
  // Replies can overtake the last batches (two sockets): wait for every insert.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (server.counters().inserted < int64_t{400} * 64 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::yield();
  }
  server.stop();
  loop.join();
  EXPECT_EQ(server.counters().inserted, int64_t{400} * 64);
  EXPECT_EQ(server.counters().sampled, int64_t{400} * 32);
  EXPECT_EQ(allocations, 0) << "operator new calls on the shard's thread during 300 insert + sample rounds";
}

}  // namespace
}  // namespace pamdp
