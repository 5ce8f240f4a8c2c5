// The metrics registry (core/metrics.hpp) and its HTTP endpoint (core/metrics_http.hpp): the text
// format, misuse, updates that allocate nothing, and a real scrape over loopback.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "app/experiment_config.hpp"
#include "app/role_metrics.hpp"
#include "core/metrics.hpp"
#include "core/metrics_http.hpp"
#include "counting_new.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp::metrics {
namespace {

TEST(Metrics, RendersTheTextFormat) {
  Registry r;
  Counter& c = r.counter("pamdp_things_total", "Things done");
  Counter& goal = r.counter("pamdp_outcomes_total", "By outcome", {{"outcome", "GOAL"}});
  Counter& out = r.counter("pamdp_outcomes_total", "By outcome", {{"outcome", "OUT\"OF\\BOUNDS\n"}});
  Gauge& g = r.gauge("pamdp_fill_ratio", "Fill\nratio");
  c.add(3);
  c.add();
  goal.add(2);
  out.set(7);
  g.set(0.25);
  const std::string text = r.render();
  EXPECT_EQ(text,
            "# HELP pamdp_things_total Things done\n"
            "# TYPE pamdp_things_total counter\n"
            "pamdp_things_total 4\n"
            "# HELP pamdp_outcomes_total By outcome\n"
            "# TYPE pamdp_outcomes_total counter\n"
            "pamdp_outcomes_total{outcome=\"GOAL\"} 2\n"
            "pamdp_outcomes_total{outcome=\"OUT\\\"OF\\\\BOUNDS\\n\"} 7\n"
            "# HELP pamdp_fill_ratio Fill\\nratio\n"
            "# TYPE pamdp_fill_ratio gauge\n"
            "pamdp_fill_ratio 0.25\n");
  int bad = -1;
  const std::vector<Sample> samples = parse_exposition(text, &bad);
  EXPECT_EQ(bad, 0);
  ASSERT_EQ(samples.size(), 4U);
  EXPECT_EQ(samples[0].name, "pamdp_things_total");
  EXPECT_EQ(samples[0].value, 4.0);
  ASSERT_NE(samples[2].label("outcome"), nullptr);
  EXPECT_EQ(*samples[2].label("outcome"), "OUT\"OF\\BOUNDS\n");
  EXPECT_EQ(samples[3].value, 0.25);
}

TEST(Metrics, SpecialValuesAndForeignText) {
  EXPECT_EQ(format_value(NAN), "NaN");
  EXPECT_EQ(format_value(INFINITY), "+Inf");
  EXPECT_EQ(format_value(-INFINITY), "-Inf");
  EXPECT_EQ(format_value(12.0), "12");
  EXPECT_EQ(format_value(1795267400.5), "1795267400.5");
  int bad = 0;
  const auto s = parse_exposition(
      "# a comment\n\nup 1 1700000000000\nx{a=\"1\",b=\"2\",} +Inf\nnot valid here\ny{a=\"unterminated} 1\n", &bad);
  ASSERT_EQ(s.size(), 2U);
  EXPECT_EQ(s[0].name, "up");
  EXPECT_EQ(s[0].value, 1.0);
  EXPECT_EQ(s[1].labels.size(), 2U);
  EXPECT_TRUE(std::isinf(s[1].value));
  EXPECT_EQ(bad, 2);
}

TEST(Metrics, MisuseIsRefused) {
  Registry r;
  r.counter("a_total", "x");
  EXPECT_THROW(r.counter("a_total", "x"), std::invalid_argument);  // same name and labels twice
  EXPECT_THROW(r.gauge("a_total", "x"), std::invalid_argument);    // a counter and a gauge
  EXPECT_THROW(r.counter("no_suffix", "x"), std::invalid_argument);
  EXPECT_THROW(r.gauge("1bad", "x"), std::invalid_argument);
  EXPECT_THROW(r.gauge("ok", "x", {{"bad-label", "v"}}), std::invalid_argument);
  EXPECT_NO_THROW(r.counter("a_total", "x", {{"k", "v"}}));
}

TEST(Metrics, CollectHooksRunBeforeRendering) {
  Registry r;
  Gauge& g = r.gauge("copied", "a value kept elsewhere");
  int source = 5;
  r.on_collect([&] { g.set(source); });
  source = 9;
  EXPECT_NE(r.render().find("copied 9\n"), std::string::npos);
}

TEST(Metrics, UpdatesAllocateNothing) {
  Registry r;
  Counter& c = r.counter("c_total", "c", {{"k", "v"}});
  Gauge& g = r.gauge("g", "g");
  testing::alloc::CountAllocations count;
  for (int i = 0; i < 1000; ++i) {
    c.add(1);
    g.set(i);
    g.add(0.5);
  }
  EXPECT_EQ(count.count(), 0);
  EXPECT_EQ(c.value(), 1000);
}

// The calls the env loops and update paths make (app/role_metrics.hpp).
TEST(Metrics, RoleUpdatesAllocateNothing) {
  toy::ReachStopEnv env;
  Registry train_registry;
  app::TrainMetrics train(train_registry, env, 1000);
  Registry actor_registry;
  ActorCounters counters;
  app::ActorMetrics actor(actor_registry, counters, env);
  UpdateStats stats;
  stats.critic_loss = 0.5F;
  stats.params_at_bound_fraction = 0.25F;
  {
    testing::alloc::CountAllocations count;
    for (int i = 1; i <= 300; ++i) {
      train.on_step(0.5);
      train.on_update(stats, i, 32);
      train.on_episode(i % 2 == 0 ? toy::ReachStopEnv::kSuccess : toy::ReachStopEnv::kWrongStop, 1.0, 4,
                       std::min(i * 4, 1000));
      actor.on_episode(i % 4, 2.0, 3);  // 0 is not an outcome: counted as OTHER
    }
    EXPECT_EQ(count.count(), 0);
  }
  const std::string t = train_registry.render();
  EXPECT_NE(t.find("pamdp_episodes_total 300\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_goals_total 150\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_episode_outcomes_total{outcome=\"SUCCESS\"} 150\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_goal_rate_100 0.5\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_updates_total 300\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_replay_transitions_sampled_total 9600\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_replay_fill_ratio 1\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_actor_params_at_bound_ratio 0.25\n"), std::string::npos) << t;
  counters.env_steps.store(77);
  const std::string a = actor_registry.render();
  EXPECT_NE(a.find("pamdp_env_steps_total 77\n"), std::string::npos) << a;
  EXPECT_NE(a.find("pamdp_episode_outcomes_total{outcome=\"OTHER\"} 75\n"), std::string::npos) << a;
  EXPECT_NE(a.find("pamdp_episode_return_mean_100 2\n"), std::string::npos) << a;
}

// Per-peer series (core/peer_stats.hpp, app::register_peer_metrics): peers known before the
// registration and added after it, counting that allocates nothing, silence, and the bound.
TEST(PeerMetrics, EveryPeerGetsItsSeries) {
  net::PeerTable table(3);
  net::PeerCounters& learner = table.peer("learner");  // before the metrics are registered
  Registry r;
  app::register_peer_metrics(r, table);
  net::PeerCounters& shard = table.peer("replay:tcp://10.0.0.2:7001");
  EXPECT_EQ(&table.peer("learner"), &learner);
  EXPECT_TRUE(table.knows("replay:tcp://10.0.0.2:7001"));
  EXPECT_FALSE(table.knows("actor:x"));
  {
    testing::alloc::CountAllocations count;
    for (int i = 0; i < 10; ++i) {
      learner.received(100);
      shard.sent(40);
    }
    shard.reconnected();
    shard.refused_oversized(3000);
    EXPECT_EQ(count.count(), 0);
  }
  const std::string t = r.render();
  EXPECT_NE(t.find("pamdp_peer_messages_received_total{peer=\"learner\"} 10\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_peer_bytes_received_total{peer=\"learner\"} 1000\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_peer_bytes_sent_total{peer=\"replay:tcp://10.0.0.2:7001\"} 400\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_peer_reconnects_total{peer=\"replay:tcp://10.0.0.2:7001\"} 1\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_peer_frames_refused_for_size_total{peer=\"replay:tcp://10.0.0.2:7001\"} 1\n"),
            std::string::npos)
      << t;
  EXPECT_NE(t.find("pamdp_peer_frames_refused_for_size_total{peer=\"learner\"} 0\n"), std::string::npos) << t;
  EXPECT_NE(t.find("pamdp_peer_bytes_received_total{peer=\"replay:tcp://10.0.0.2:7001\"} 3000\n"), std::string::npos)
      << t;  // a refused frame was still received
  for (const Sample& s : parse_exposition(t)) {
    if (s.name == "pamdp_peer_silence_seconds" && *s.label("peer") == "learner") {
      EXPECT_GE(s.value, 0.0);
      EXPECT_LT(s.value, 5.0);
    }
  }
  // Past the bound, new names share "other".
  net::PeerCounters& third = table.peer("actor:a");
  EXPECT_EQ(third.name, "actor:a");
  net::PeerCounters& other = table.peer("actor:b");
  EXPECT_EQ(other.name, "other");
  EXPECT_EQ(&table.peer("actor:c"), &other);
  EXPECT_NE(r.render().find("pamdp_peer_messages_sent_total{peer=\"other\"} 0\n"), std::string::npos);
}

TEST(MetricsHttp, ServesAndFetchesOverLoopback) {
  Registry r;
  Counter& c = r.counter("pamdp_scrapes_seen_total", "x");
  MetricsHttpServer server(r, "127.0.0.1", 0);
  ASSERT_GT(server.port(), 0);
  EXPECT_EQ(server.url(), "http://127.0.0.1:" + std::to_string(server.port()) + "/metrics");
  // Updates from another thread while scrapes render.
  std::thread writer([&] {
    for (int i = 0; i < 100000; ++i) {
      c.add(1);
    }
  });
  std::string error;
  for (int i = 0; i < 3; ++i) {
    const auto body = http_get(server.url(), 2000, &error);
    ASSERT_TRUE(body.has_value()) << error;
    const auto samples = parse_exposition(*body);
    ASSERT_EQ(samples.size(), 1U);
    EXPECT_EQ(samples[0].name, "pamdp_scrapes_seen_total");
  }
  writer.join();
  const auto body = http_get(server.url(), 2000, &error);
  ASSERT_TRUE(body.has_value()) << error;
  EXPECT_NE(body->find("pamdp_scrapes_seen_total 100000\n"), std::string::npos);
  EXPECT_FALSE(http_get("http://127.0.0.1:" + std::to_string(server.port()) + "/nothing", 2000, &error));
  EXPECT_NE(error.find("404"), std::string::npos) << error;
}

// A non-loopback IPv4 address of this machine, or "" when it has none.
std::string non_loopback_ipv4() {
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) {
    return "";
  }
  std::string found;
  for (ifaddrs* i = list; i != nullptr && found.empty(); i = i->ifa_next) {
    if (i->ifa_addr == nullptr || i->ifa_addr->sa_family != AF_INET || (i->ifa_flags & IFF_LOOPBACK) != 0 ||
        (i->ifa_flags & IFF_UP) == 0) {
      continue;
    }
    char text[INET_ADDRSTRLEN];
    const auto* in = reinterpret_cast<const sockaddr_in*>(i->ifa_addr);
    if (inet_ntop(AF_INET, &in->sin_addr, text, sizeof(text)) != nullptr) {
      found = text;
    }
  }
  freeifaddrs(list);
  return found;
}

// The promise of [metrics] bind's default: a process's /metrics is reachable from this machine
// only, not on its other interfaces, unless configured otherwise.
TEST(MetricsHttp, DefaultBindIsLoopbackOnly) {
  const app::ExperimentConfig defaults;
  EXPECT_EQ(defaults.metrics.bind, "127.0.0.1");
  const std::string other = non_loopback_ipv4();
  if (other.empty()) {
    GTEST_SKIP() << "this machine has no non-loopback IPv4 address to try";
  }
  Registry r;
  r.counter("pamdp_probe_total", "x");
  MetricsHttpServer server(r, defaults.metrics.bind, 0);
  std::string error;
  EXPECT_TRUE(http_get(server.url(), 2000, &error).has_value()) << error;
  EXPECT_FALSE(http_get("http://" + other + ":" + std::to_string(server.port()) + "/metrics", 2000, &error))
      << "/metrics answered on " << other;
  MetricsHttpServer everywhere(r, "0.0.0.0", 0);  // configured otherwise: reachable there too
  EXPECT_TRUE(http_get("http://" + other + ":" + std::to_string(everywhere.port()) + "/metrics", 2000, &error))
      << error;
}

TEST(MetricsHttp, PortInUseIsAnErrorNamingTheFix) {
  Registry r;
  MetricsHttpServer first(r, "127.0.0.1", 0);
  try {
    MetricsHttpServer second(r, "127.0.0.1", first.port());
    FAIL() << "bound a port in use";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("--metrics-port"), std::string::npos) << e.what();
  }
}

TEST(MetricsHttp, UrlHosts) {
  EXPECT_EQ(url_host("127.0.0.1", "ignored"), "127.0.0.1");
  EXPECT_EQ(url_host("0.0.0.0", "learner.example"), "learner.example");
  EXPECT_EQ(url_host("::", "::1"), "[::1]");
  EXPECT_FALSE(url_host("*", "").empty());
}

TEST(MetricsHttp, UnreachableIsReportedNotThrown) {
  std::string error;
  EXPECT_FALSE(http_get("http://127.0.0.1:1/metrics", 500, &error));
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(http_get("ftp://x/metrics", 500, &error));
}

}  // namespace
}  // namespace pamdp::metrics
