// LearnerServer on loopback: the join handshake hands out the cluster map, malformed and
// unexpected messages on every socket are dropped and counted while the server keeps working,
// sample replies drive DDPG updates, and weights are published. Nothing sleeps: peers wait on
// their sockets with bounded timeouts.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/rng.hpp"
#include "core/transport.hpp"
#include "core/wire.hpp"
#include "envs/toy/reach_stop.hpp"
#include "learner/ddpg_algorithm.hpp"
#include "learner/learner_server.hpp"

namespace pamdp {
namespace {

using Clock = std::chrono::steady_clock;
constexpr uint32_t kObs = 3;
constexpr uint32_t kAct = 3;
constexpr int kBatch = 4;

DdpgConfig small() {
  DdpgConfig c;
  c.hidden = {8};
  c.batch_size = kBatch;
  return c;
}

// A learner on loopback ports chosen by the OS, for the toy task, that never times peers out.
LearnerServerConfig loopback_config() {
  LearnerServerConfig c;
  c.join_bind = "tcp://127.0.0.1:*";
  c.weights_bind = "tcp://127.0.0.1:*";
  c.config_toml = "[env]\nname = \"reach_stop\"\n";
  c.peer_timeout_ms = 60000;
  return c;
}

DdpgConfig cloning() {
  DdpgConfig c = small();
  c.demo_bc_weight = 1.0;
  c.demo_q_filter = false;
  return c;
}

struct Running {
  net::Context ctx;
  toy::ReachStopEnv env;
  DdpgAlgorithm ddpg;
  std::unique_ptr<LearnerServer> server;
  std::thread thread;
  std::atomic<bool> done{false};
  explicit Running(bool clone_demos = false, std::function<void(const UpdateStats&)> on_update = {})
      : ddpg(kObs, env.action_space(), clone_demos ? cloning() : small(), 1, UpdateDevice::kCpu) {
    LearnerServerConfig c = loopback_config();
    c.publish_every_updates = 5;
    c.max_updates = 20;
    c.clone_demos = clone_demos;
    server = std::make_unique<LearnerServer>(ctx, ddpg, c);
    server->on_update = std::move(on_update);
    thread = std::thread([this] {
      server->run();  // returns by itself after max_updates
      done.store(true);
    });
  }
  ~Running() {
    server->stop();
    thread.join();
  }
};

// Receives one frame within timeout_ms or returns false.
bool receive(net::Socket& s, net::Message& m, int timeout_ms) {
  return s.recv(m, timeout_ms);
}

// A batch of constant rows for the toy task's widths.
struct ConstantRows {
  std::vector<float> states = std::vector<float>(kBatch * kObs, 0.1F);
  std::vector<float> actions = std::vector<float>(kBatch * kAct, 0.2F);
  std::vector<float> rewards = std::vector<float>(kBatch, 1.0F);
  std::vector<uint8_t> terminals = std::vector<uint8_t>(kBatch, 1);
  std::vector<float> returns = std::vector<float>(kBatch, 1.0F);
  [[nodiscard]] wire::TransitionRows rows() const {
    return {kBatch,           kObs,          kAct, states.data(), actions.data(), rewards.data(), states.data(),
            terminals.data(), returns.data()};
  }
};

// Plays a shard's sample socket until the learner has returned from run() (or 10 s pass):
// `answer` gets every SampleRequest and the routing id to reply to.
void serve_samples(Running& run, net::Socket& sample,
                   const std::function<void(const wire::SampleRequest&, const net::Message&)>& answer) {
  net::Message id;
  net::Message req;
  const auto until = Clock::now() + std::chrono::seconds(10);
  while (!run.done.load() && Clock::now() < until) {
    if (!sample.recv_from(id, req, 100)) {
      continue;
    }
    const wire::Envelope* env = wire::open_envelope(req.bytes());
    ASSERT_NE(env, nullptr);
    const wire::SampleRequest* r = env->payload_as_SampleRequest();
    ASSERT_NE(r, nullptr);
    answer(*r, id);
  }
}

TEST(LearnerServer, JoinsShardsDropsGarbageAndUpdatesFromReplies) {
  Running run;
  net::Context& ctx = run.ctx;
  // A fake shard: a sample ROUTER the learner connects to, and a join DEALER.
  net::Socket sample(ctx, net::SocketType::kRouter);
  const std::string sample_endpoint = sample.bind("tcp://127.0.0.1:*");
  net::Socket join(ctx, net::SocketType::kDealer);
  join.connect(run.server->join_endpoint());
  net::Socket weights(ctx, net::SocketType::kSub);
  weights.subscribe_all();
  weights.connect(run.server->weights_endpoint());

  // Garbage first: raw bytes, a truncated envelope, an unexpected payload type.
  const std::vector<uint8_t> junk{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  ASSERT_TRUE(join.send(junk, 1000));
  flatbuffers::FlatBufferBuilder fbb;
  wire::build_sample_request(fbb, 1, 4);  // not something a learner's join socket accepts
  ASSERT_TRUE(join.send(wire::bytes_of(fbb), 1000));
  wire::build_join_request(fbb, wire::Role::Shard, "shard", "tcp://127.0.0.1:1", sample_endpoint, 0);
  const std::vector<uint8_t> truncated(wire::bytes_of(fbb).begin(), wire::bytes_of(fbb).begin() + 20);
  ASSERT_TRUE(join.send(truncated, 1000));

  // Then a real join: the answer is the cluster map with this shard in it.
  ASSERT_TRUE(join.send(wire::bytes_of(fbb), 1000));
  net::Message m;
  const wire::ClusterMap* map = nullptr;
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (map == nullptr && Clock::now() < deadline) {
    ASSERT_TRUE(receive(join, m, 5000));
    const wire::Envelope* env = wire::open_envelope(m.bytes());
    ASSERT_NE(env, nullptr);
    map = env->payload_as_ClusterMap();
  }
  ASSERT_NE(map, nullptr);
  ASSERT_EQ(map->shard_sample_endpoints()->size(), 1U);
  EXPECT_EQ(map->shard_sample_endpoints()->Get(0)->str(), sample_endpoint);
  EXPECT_NE(map->config_toml()->str().find("reach_stop"), std::string::npos);

  // The learner publishes weights only as it updates, which starts with the first reply served
  // below; a PUB drops what it sends before the SUB's subscription has reached it, and on a fast
  // machine all 20 updates can be over within milliseconds of the join. Give the subscription
  // time to arrive first (the SUB connected before the join, so this is ample).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));

  // Serve sample requests: first one malformed reply (wrong widths), then good ones.
  const ConstantRows constant;
  bool sent_bad = false;
  int served = 0;
  serve_samples(run, sample, [&](const wire::SampleRequest& r, const net::Message& id) {
    EXPECT_EQ(r.batch_size(), static_cast<uint32_t>(kBatch));
    wire::TransitionRows rows = constant.rows();
    std::vector<float> wide(kBatch * (kObs + 1), 0.0F);
    if (!sent_bad) {
      rows.obs_dim = kObs + 1;  // sizes that do not match the experiment
      rows.states = rows.next_states = wide.data();
    }
    wire::build_sample_reply(fbb, r.request_id(), rows);
    ASSERT_TRUE(sample.send_to(id.bytes(), wire::bytes_of(fbb), 1000));
    served += sent_bad ? 1 : 0;
    sent_bad = true;
  });
  ASSERT_TRUE(run.done.load()) << "the learner did not reach max_updates";
  EXPECT_EQ(run.ddpg.updates(), 20);  // exactly max_updates: next() ends the run before another batch
  EXPECT_GE(served, 20);

  // Weights were published (at start and every 5 updates) and carry the actor's layout.
  ASSERT_TRUE(receive(weights, m, 5000));
  const wire::Envelope* env = wire::open_envelope(m.bytes());
  ASSERT_NE(env, nullptr);
  const wire::PolicyWeights* w = env->payload_as_PolicyWeights();
  ASSERT_NE(w, nullptr);
  ASSERT_NE(w->algorithm(), nullptr);
  EXPECT_EQ(w->algorithm()->str(), "ddpg");
  ASSERT_NE(w->networks(), nullptr);
  ASSERT_EQ(w->networks()->size(), 1U);
  EXPECT_EQ(w->networks()->Get(0)->name()->str(), "actor");
  EXPECT_EQ(w->networks()->Get(0)->params()->size(), static_cast<uint32_t>(run.ddpg.ddpg().actor().num_params()));
  EXPECT_GE(run.server->counters().weights_version, 2);
  // junk, wrong type, truncated, wrong-width reply.
  EXPECT_EQ(run.server->counters().malformed_messages, 4);
}

// Cloning on the cluster: every request asks for demonstrations too, and an update clones the
// ones a reply carries (and runs plain without them).
TEST(LearnerServer, ClonesTheDemonstrationsARepliesCarries) {
  std::atomic<int> cloned{0};
  Running run(/*clone_demos=*/true, [&](const UpdateStats& s) {
    if (s.bc_accepted_fraction > 0.0F) {
      cloned.fetch_add(1);
    }
  });
  net::Context& ctx = run.ctx;
  net::Socket sample(ctx, net::SocketType::kRouter);
  const std::string sample_endpoint = sample.bind("tcp://127.0.0.1:*");
  net::Socket join(ctx, net::SocketType::kDealer);
  join.connect(run.server->join_endpoint());
  flatbuffers::FlatBufferBuilder fbb;
  wire::build_join_request(fbb, wire::Role::Shard, "shard", "tcp://127.0.0.1:1", sample_endpoint, 0);
  ASSERT_TRUE(join.send(wire::bytes_of(fbb), 1000));

  const ConstantRows constant;
  std::vector<float> demo_actions(kBatch * kAct, -0.5F);
  int served = 0;
  int with_demos = 0;
  serve_samples(run, sample, [&](const wire::SampleRequest& r, const net::Message& id) {
    EXPECT_EQ(r.demo_batch_size(), static_cast<uint32_t>(kBatch));
    const wire::TransitionRows rows = constant.rows();
    wire::TransitionRows demos = rows;
    demos.actions = demo_actions.data();
    // Every other reply without demonstrations (a shard that holds none yet).
    const bool give = served % 2 == 1;
    wire::build_sample_reply(fbb, r.request_id(), rows, give ? &demos : nullptr);
    ASSERT_TRUE(sample.send_to(id.bytes(), wire::bytes_of(fbb), 1000));
    ++served;
    with_demos += give ? 1 : 0;
  });
  ASSERT_TRUE(run.done.load()) << "the learner did not reach max_updates";  // run() has returned
  const int64_t updates = run.server->counters().updates;
  EXPECT_GE(updates, 20);
  // Replies are served in order; the learner updates once per reply it reads.
  EXPECT_EQ(run.server->counters().demo_samples_received, int64_t{kBatch} * cloned.load());
  EXPECT_GE(cloned.load(), 9);
  EXPECT_LE(cloned.load(), with_demos);
  EXPECT_EQ(run.server->counters().malformed_messages, 0);
}

// Waits for an envelope of the given payload type on `s` (skipping others); nullptr on timeout.
const wire::Envelope* await_payload(net::Socket& s, net::Message& m, wire::Payload type) {
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < deadline) {
    if (!s.recv(m, 100)) {
      continue;
    }
    const wire::Envelope* env = wire::open_envelope(m.bytes());
    if (env != nullptr && env->payload_type() == type) {
      return env;
    }
  }
  return nullptr;
}

// The probe of issue 33 at the learner's join socket, bounded and on loopback: 2,000 random
// frames (empty, 1-7 bytes, short ones with the schema's identifier, up to 4 KB) from one DEALER,
// then a MetricsUrlsRequest; the join socket reads one peer's frames in order, so once its answer
// comes every frame before it has been handled, and each must have been counted.
TEST(LearnerServer, EveryRandomFrameAtTheJoinSocketIsCounted) {
  net::Context ctx;
  toy::ReachStopEnv env;
  DdpgAlgorithm ddpg{kObs, env.action_space(), small(), 1, UpdateDevice::kCpu};
  LearnerServer server(ctx, ddpg, loopback_config());
  std::thread thread([&] { server.run(); });
  net::Socket probe(ctx, net::SocketType::kDealer);
  probe.connect(server.join_endpoint());
  Rng rng(33);
  constexpr int kFrames = 2000;
  std::vector<uint8_t> frame;
  for (int i = 0; i < kFrames; ++i) {
    const int kind = i % 10;
    const size_t size = kind == 0   ? 0
                        : kind == 1 ? 1 + rng.next_u64() % 7
                        : kind <= 4 ? 8 + rng.next_u64() % 57
                                    : rng.next_u64() % 4097;
    frame.resize(size);
    for (uint8_t& b : frame) {
      b = static_cast<uint8_t>(rng.next_u64());
    }
    if (kind >= 2 && kind <= 4) {
      std::memcpy(frame.data() + 4, "PMSG", 4);  // the envelope's file identifier
    }
    ASSERT_TRUE(probe.send(frame, 2000)) << "frame " << i;
  }
  flatbuffers::FlatBufferBuilder fbb;
  wire::build_metrics_urls_request(fbb);
  ASSERT_TRUE(probe.send(wire::bytes_of(fbb), 2000));
  net::Message m;
  EXPECT_NE(await_payload(probe, m, wire::Payload::MetricsUrls), nullptr);
  server.stop();
  thread.join();
  EXPECT_EQ(server.counters().malformed_messages, kFrames);
}

// Episode reports count only from an actor that joined this learner: a peer that never joined
// (or an actor of a learner that restarted, until it joins again) is counted as refused and its
// reports reach neither the episode count nor on_episode.
TEST(LearnerServer, EpisodeReportsOnlyFromJoinedActors) {
  net::Context ctx;
  toy::ReachStopEnv env;
  DdpgAlgorithm ddpg{kObs, env.action_space(), small(), 1, UpdateDevice::kCpu};
  LearnerServer server(ctx, ddpg, loopback_config());
  std::atomic<int> reported{0};
  server.on_episode = [&](const EpisodeSummary&) { reported.fetch_add(1); };
  std::thread thread([&] { server.run(); });
  flatbuffers::FlatBufferBuilder fbb;
  net::Message m;
  // Every frame a socket sent before its MetricsUrlsRequest was handled before the answer.
  const auto settle = [&](net::Socket& s) {
    wire::build_metrics_urls_request(fbb);
    ASSERT_TRUE(s.send(wire::bytes_of(fbb), 1000));
    ASSERT_NE(await_payload(s, m, wire::Payload::MetricsUrls), nullptr);
  };
  net::Socket stranger(ctx, net::SocketType::kDealer);
  stranger.connect(server.join_endpoint());
  for (uint64_t e = 1; e <= 3; ++e) {
    wire::build_episode_report(fbb, 0, e, 1.0F, 5, 1, 1);
    ASSERT_TRUE(stranger.send(wire::bytes_of(fbb), 1000));
  }
  settle(stranger);
  net::Socket actor(ctx, net::SocketType::kDealer);
  actor.connect(server.join_endpoint());
  wire::build_join_request(fbb, wire::Role::Actor, "actor", "", "", 1, "");
  ASSERT_TRUE(actor.send(wire::bytes_of(fbb), 1000));
  ASSERT_NE(await_payload(actor, m, wire::Payload::ClusterMap), nullptr);
  for (uint64_t e = 1; e <= 2; ++e) {
    wire::build_episode_report(fbb, 0, e, 1.0F, 5, 1, 1);
    ASSERT_TRUE(actor.send(wire::bytes_of(fbb), 1000));
  }
  settle(actor);
  server.stop();
  thread.join();
  EXPECT_EQ(server.counters().episodes, 2);
  EXPECT_EQ(server.counters().episode_reports_refused, 3);
  EXPECT_EQ(server.counters().malformed_messages, 0);
  EXPECT_EQ(reported.load(), 2);
}

TEST(LearnerServer, ListsTheMetricsUrlsOfItsPeersForMonitors) {
  net::Context ctx;
  toy::ReachStopEnv env;
  DdpgAlgorithm ddpg{kObs, env.action_space(), small(), 1, UpdateDevice::kCpu};
  LearnerServerConfig c = loopback_config();
  c.metrics_url = "http://learner:1/metrics";
  LearnerServer server(ctx, ddpg, c);
  std::mutex mutex;
  std::vector<std::string> written;
  int writes = 0;
  server.on_metrics_urls = [&](const std::vector<std::string>& urls) {
    const std::lock_guard lock(mutex);
    written = urls;
    ++writes;
  };
  std::thread thread([&] { server.run(); });

  flatbuffers::FlatBufferBuilder fbb;
  net::Message m;
  net::Socket sample(ctx, net::SocketType::kRouter);
  const std::string sample_endpoint = sample.bind("tcp://127.0.0.1:*");
  net::Socket shard(ctx, net::SocketType::kDealer);
  shard.connect(server.join_endpoint());
  wire::build_join_request(fbb, wire::Role::Shard, "shard", "tcp://127.0.0.1:1", sample_endpoint, 0,
                           "http://shard:2/metrics");
  ASSERT_TRUE(shard.send(wire::bytes_of(fbb), 1000));
  ASSERT_NE(await_payload(shard, m, wire::Payload::ClusterMap), nullptr);
  net::Socket actor(ctx, net::SocketType::kDealer);
  actor.connect(server.join_endpoint());
  wire::build_join_request(fbb, wire::Role::Actor, "actor", "", "", 1, "http://actor:3/metrics");
  ASSERT_TRUE(actor.send(wire::bytes_of(fbb), 1000));
  ASSERT_NE(await_payload(actor, m, wire::Payload::ClusterMap), nullptr);

  // A monitor asks on its own DEALER: the learner first, then shards, then actors.
  net::Socket monitor(ctx, net::SocketType::kDealer);
  monitor.connect(server.join_endpoint());
  wire::build_metrics_urls_request(fbb);
  ASSERT_TRUE(monitor.send(wire::bytes_of(fbb), 1000));
  const wire::Envelope* answer = await_payload(monitor, m, wire::Payload::MetricsUrls);
  ASSERT_NE(answer, nullptr);
  std::vector<std::string> urls;
  for (const flatbuffers::String* u : *answer->payload_as_MetricsUrls()->urls()) {
    urls.push_back(u->str());
  }
  const std::vector<std::string> expected{"http://learner:1/metrics", "http://shard:2/metrics",
                                          "http://actor:3/metrics"};
  EXPECT_EQ(urls, expected);
  server.stop();
  thread.join();
  const std::lock_guard lock(mutex);
  EXPECT_EQ(written, expected);
  EXPECT_EQ(writes, 3);  // at the start, and once per peer that joined with a URL
  EXPECT_EQ(server.counters().actors_alive, 1);
}

// An actor silent past the peer timeout (a partition) is dropped from the live peers; when its
// heartbeats come back, the learner answers with map version 0, so it joins again, is counted
// alive again and keeps its index.
TEST(LearnerServer, AnActorBackFromSilenceIsToldToJoinAgain) {
  net::Context ctx;
  toy::ReachStopEnv env;
  DdpgAlgorithm ddpg{kObs, env.action_space(), small(), 1, UpdateDevice::kCpu};
  LearnerServerConfig c = loopback_config();
  c.peer_timeout_ms = 300;
  LearnerServer server(ctx, ddpg, c);
  std::atomic<int64_t> alive{-1};
  server.on_tick = [&](const LearnerCounters& counters) { alive.store(counters.actors_alive); };
  std::thread thread([&] { server.run(); });

  flatbuffers::FlatBufferBuilder fbb;
  net::Message m;
  net::Socket actor(ctx, net::SocketType::kDealer);
  actor.connect(server.join_endpoint());
  wire::build_join_request(fbb, wire::Role::Actor, "actor", "", "", 1, "");
  ASSERT_TRUE(actor.send(wire::bytes_of(fbb), 1000));
  const wire::Envelope* map = await_payload(actor, m, wire::Payload::ClusterMap);
  ASSERT_NE(map, nullptr);
  const uint64_t version = map->payload_as_ClusterMap()->version();
  const uint32_t index = map->payload_as_ClusterMap()->actor_index();
  const int64_t counters[] = {0};
  // While it is alive, its heartbeat is answered with the current map version.
  wire::build_heartbeat(fbb, wire::Role::Actor, "actor", version, counters);
  ASSERT_TRUE(actor.send(wire::bytes_of(fbb), 1000));
  const wire::Envelope* hb = await_payload(actor, m, wire::Payload::Heartbeat);
  ASSERT_NE(hb, nullptr);
  EXPECT_EQ(hb->payload_as_Heartbeat()->map_version(), version);
  // Silent for longer than the peer timeout: no longer alive (the learner ticks once a second).
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (alive.load() != 0 && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_EQ(alive.load(), 0);
  wire::build_heartbeat(fbb, wire::Role::Actor, "actor", version, counters);
  ASSERT_TRUE(actor.send(wire::bytes_of(fbb), 1000));
  hb = await_payload(actor, m, wire::Payload::Heartbeat);
  ASSERT_NE(hb, nullptr);
  EXPECT_EQ(hb->payload_as_Heartbeat()->map_version(), 0U) << "a dropped actor must be told to join again";
  wire::build_join_request(fbb, wire::Role::Actor, "actor", "", "", 1, "");
  ASSERT_TRUE(actor.send(wire::bytes_of(fbb), 1000));
  map = await_payload(actor, m, wire::Payload::ClusterMap);
  ASSERT_NE(map, nullptr);
  EXPECT_EQ(map->payload_as_ClusterMap()->actor_index(), index);
  server.stop();
  thread.join();
  EXPECT_EQ(server.counters().actors_alive, 1);
  EXPECT_EQ(server.counters().actors_joined, 1);
}

// With CURVE, a peer whose key the cluster did not issue (even one that knows the learner's
// public key) is refused in the handshake at both of the learner's bound sockets: its JoinRequest
// is never answered and its SUB never receives weights, while a subscriber with the cluster's key
// gets every publication of the same run.
TEST(LearnerServer, CurveRefusesForeignKeysAtJoinAndWeights) {
  const net::CurveServerKeys server_keys = net::generate_curve_keypair();
  const net::CurveServerKeys cluster_client = net::generate_curve_keypair();
  const net::CurveServerKeys intruder = net::generate_curve_keypair();
  const net::CurveClientKeys good{cluster_client.public_key, cluster_client.secret_key, server_keys.public_key};
  const net::CurveClientKeys bad{intruder.public_key, intruder.secret_key, server_keys.public_key};

  net::Context ctx;
  net::CurveAuthenticator auth(ctx, {cluster_client.public_key});  // before the sockets
  toy::ReachStopEnv env;
  DdpgAlgorithm ddpg{kObs, env.action_space(), small(), 1, UpdateDevice::kCpu};
  LearnerServerConfig c = loopback_config();
  c.publish_every_updates = 2;
  c.max_updates = 400;
  c.curve = server_keys;
  c.curve_client = good;
  LearnerServer server(ctx, ddpg, c);
  std::atomic<bool> done{false};
  std::thread thread([&] {
    server.run();
    done.store(true);
  });

  // Subscribers and an intruding joiner first (CURVE applies to connections made after the keys).
  net::Socket good_sub(ctx, net::SocketType::kSub);
  good_sub.make_curve_client(good);
  good_sub.subscribe_all();
  good_sub.connect(server.weights_endpoint());
  net::Socket bad_sub(ctx, net::SocketType::kSub);
  bad_sub.make_curve_client(bad);
  bad_sub.subscribe_all();
  bad_sub.connect(server.weights_endpoint());
  flatbuffers::FlatBufferBuilder fbb;
  net::Socket bad_join(ctx, net::SocketType::kDealer);
  bad_join.make_curve_client(bad);
  bad_join.connect(server.join_endpoint());
  wire::build_join_request(fbb, wire::Role::Actor, "intruder", "", "", 1);
  (void)bad_join.send(wire::bytes_of(fbb), 200);  // queued until a handshake that never succeeds

  // The refusal table (docs/reliability.md), one intruder at a time so that each is seen counted:
  // no key at all (a plain SUB, a plain actor, a plain shard), a key the cluster did not issue, and
  // the cluster's own client key with another server public key.
  auto refused_more_than = [&](int64_t before) {
    const auto until = Clock::now() + std::chrono::seconds(5);
    while (server.connections_refused() <= before && Clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return server.connections_refused() > before;
  };
  ASSERT_TRUE(refused_more_than(1)) << "the two foreign-key intruders: " << server.connections_refused();
  net::Socket plain_sub(ctx, net::SocketType::kSub);
  int64_t before = server.connections_refused();
  plain_sub.subscribe_all();
  plain_sub.connect(server.weights_endpoint());
  EXPECT_TRUE(refused_more_than(before)) << "a plain SUB on the weights socket was not counted";
  std::vector<net::Socket> intruders;
  const std::string nowhere = "tcp://127.0.0.1:1";
  const net::CurveServerKeys other_server = net::generate_curve_keypair();
  const net::CurveClientKeys wrong_server{cluster_client.public_key, cluster_client.secret_key,
                                          other_server.public_key};
  for (int kind = 0; kind < 4; ++kind) {
    before = server.connections_refused();
    intruders.emplace_back(ctx, net::SocketType::kDealer);
    net::Socket& s = intruders.back();
    if (kind == 2) {
      s.make_curve_client(bad);
    } else if (kind == 3) {
      s.make_curve_client(wrong_server);
    }
    s.connect(server.join_endpoint());
    if (kind == 0) {
      wire::build_join_request(fbb, wire::Role::Actor, "plain-actor", "", "", 1);
    } else {
      wire::build_join_request(fbb, wire::Role::Shard, "intruding-shard", nowhere, nowhere, 0);
    }
    (void)s.send(wire::bytes_of(fbb), 200);
    EXPECT_TRUE(refused_more_than(before)) << "intruder " << kind << " (0 plain actor, 1 plain shard, 2 foreign "
                                           << "key shard, 3 wrong server key shard) was not counted";
  }

  // A shard with the cluster's key: its sample socket is a CURVE server with the cluster's keys.
  net::Socket sample(ctx, net::SocketType::kRouter);
  sample.make_curve_server(server_keys);
  const std::string sample_endpoint = sample.bind("tcp://127.0.0.1:*");
  net::Socket join(ctx, net::SocketType::kDealer);
  join.make_curve_client(good);
  join.connect(server.join_endpoint());
  wire::build_join_request(fbb, wire::Role::Shard, "shard", "tcp://127.0.0.1:1", sample_endpoint, 0);
  ASSERT_TRUE(join.send(wire::bytes_of(fbb), 1000));
  net::Message m;
  const wire::Envelope* map_env = await_payload(join, m, wire::Payload::ClusterMap);
  ASSERT_NE(map_env, nullptr);
  EXPECT_EQ(map_env->payload_as_ClusterMap()->shard_sample_endpoints()->size(), 1U)
      << "an intruding shard is in the map";

  // Serve samples until the run ends; the good subscriber counts what it receives meanwhile.
  std::vector<float> states(kBatch * kObs, 0.1F);
  std::vector<float> actions(kBatch * kAct, 0.2F);
  std::vector<float> rewards(kBatch, 1.0F);
  std::vector<uint8_t> terminals(kBatch, 0);
  const wire::TransitionRows rows{kBatch,         kObs,           kAct,          states.data(),
                                  actions.data(), rewards.data(), states.data(), terminals.data(),
                                  rewards.data()};
  int received = 0;
  net::Message id;
  net::Message req;
  const auto until = Clock::now() + std::chrono::seconds(20);
  while (!done.load() && Clock::now() < until) {
    while (good_sub.recv(m, 0)) {
      const wire::Envelope* e = wire::open_envelope(m.bytes());
      received += e != nullptr && e->payload_as_PolicyWeights() != nullptr ? 1 : 0;
    }
    if (!sample.recv_from(id, req, 20)) {
      continue;
    }
    const wire::Envelope* e = wire::open_envelope(req.bytes());
    ASSERT_NE(e, nullptr);
    wire::build_sample_reply(fbb, e->payload_as_SampleRequest()->request_id(), rows);
    ASSERT_TRUE(sample.send_to(id.bytes(), wire::bytes_of(fbb), 1000));
  }
  ASSERT_TRUE(done.load()) << "the learner did not reach max_updates";
  thread.join();
  EXPECT_GT(received, 10) << "the subscriber with the cluster's key got " << received << " publications";
  EXPECT_FALSE(bad_sub.recv(m, 300)) << "a subscriber with a foreign key received weights";
  EXPECT_FALSE(bad_join.recv(m, 300)) << "a joiner with a foreign key was answered";
  EXPECT_FALSE(plain_sub.recv(m, 100)) << "a plain subscriber received weights";
  for (net::Socket& s : intruders) {
    EXPECT_FALSE(s.recv(m, 100)) << "an intruding joiner was answered";
  }
  EXPECT_GE(auth.refused(), 3);  // the ZAP handler sees only the foreign client keys
  EXPECT_GE(server.connections_refused(), 7);
  EXPECT_GE(server.counters().connections_refused, 7);  // as the metrics see it
  EXPECT_EQ(server.counters().shards, 1);
  EXPECT_EQ(server.counters().actors_alive, 0);
  EXPECT_EQ(server.counters().malformed_messages, 0);
}

}  // namespace
}  // namespace pamdp
