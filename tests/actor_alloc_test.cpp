// Proves the acting loop allocates nothing in steady state: every global operator new in this
// binary is replaced by one that counts while the actor thread has counting switched on (from
// its on_tick callback, so only that thread is measured). Its own binary, so the replacement
// affects no other test. The window spans env steps with and without the network (ε = 0.5),
// episode ends, batch sends, episode reports, heartbeats and their answers.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "actor_harness.hpp"

namespace {

thread_local bool t_counting = false;
std::atomic<long> g_allocations{0};

void* counted_alloc(std::size_t size, std::size_t align) {
  if (t_counting) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
  if (size == 0) {
    size = 1;
  }
  void* p = align <= alignof(std::max_align_t) ? std::malloc(size)
                                               : std::aligned_alloc(align, (size + align - 1) / align * align);
  if (p == nullptr) {
    throw std::bad_alloc();
  }
  return p;
}

}  // namespace

void* operator new(std::size_t size) {
  return counted_alloc(size, alignof(std::max_align_t));
}
void* operator new[](std::size_t size) {
  return counted_alloc(size, alignof(std::max_align_t));
}
void* operator new(std::size_t size, std::align_val_t align) {
  return counted_alloc(size, static_cast<std::size_t>(align));
}
void* operator new[](std::size_t size, std::align_val_t align) {
  return counted_alloc(size, static_cast<std::size_t>(align));
}
// libzmq allocates with new (std::nothrow); these must match the deletes below too.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(size, alignof(std::max_align_t));
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(size, alignof(std::max_align_t));
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}

namespace pamdp::testing {
namespace {

TEST(ActorLoopAllocations, SteadyStateActingAllocatesNothing) {
  net::Context ctx;
  FakeLearner learner(ctx);
  FakeShard shard(ctx);
  learner.shard_endpoints = {shard.endpoint()};
  ActorLoopConfig config = test_loop_config();
  config.exploration.epsilon_start = 0.5;
  config.exploration.epsilon_end = 0.5;

  constexpr int kTicks = 10;
  std::atomic<int> phase{0};  // 0 warming up, 1 counting, 2 done
  std::atomic<int64_t> steps_counted{0};
  std::atomic<int64_t> batches_counted{0};
  std::atomic<int64_t> episodes_counted{0};
  int ticks = 0;
  int64_t steps0 = 0;
  int64_t batches0 = 0;
  int64_t episodes0 = 0;
  auto on_tick = [&](const ActorCounters& c, double /*eps*/) {
    if (phase.load() == 0 && c.weights_version.load() >= 1 && c.batches_sent.load() >= 10) {
      steps0 = c.env_steps.load();
      batches0 = c.batches_sent.load();
      episodes0 = c.episodes.load();
      g_allocations = 0;
      t_counting = true;
      phase = 1;
    } else if (phase.load() == 1 && ++ticks >= kTicks) {
      t_counting = false;
      steps_counted = c.env_steps.load() - steps0;
      batches_counted = c.batches_sent.load() - batches0;
      episodes_counted = c.episodes.load() - episodes0;
      phase = 2;
    }
  };
  ActorRunner actor(ctx, learner.join_endpoint(), config, 2, 2000, on_tick);
  const Bytes weights = [] {
    flatbuffers::FlatBufferBuilder fbb;
    wire::build_policy_weights(fbb, 1, 0, kTestWidths, 0, constant_output_params({0.5F, -0.5F, 0.25F}));
    return copy_bytes(wire::bytes_of(fbb));
  }();
  ASSERT_TRUE(serve_until(learner, {&shard}, [&] {
    if (actor.counters.weights_version.load() < 1) {
      learner.publish(weights);
    }
    return phase.load() == 2;
  }));
  EXPECT_GT(steps_counted.load(), 1000);
  EXPECT_GT(batches_counted.load(), 10);
  EXPECT_GT(episodes_counted.load(), 10);
  EXPECT_EQ(g_allocations.load(), 0) << "over " << steps_counted.load() << " env steps";
}

}  // namespace
}  // namespace pamdp::testing
