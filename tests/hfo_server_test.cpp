// The real HFO server's features (E3, shared/hfo-reference.md §3.4) converted to the embedded
// encoding (E1/E2, §3.2), the hfo-server config keys, and env creation in builds with and without
// HFO. Needs no server: tests/hfo_server_live_test.cpp plays against a real one.
//
// E3 normalizers: R3 = sqrt(52.5^2 + 68^2) = sqrt(7380.25) = 85.9083814; OOB 1.1 * 52.5 = 57.75
// (left, right) and 1.05 * 68 = 71.4 (top, bottom). E1/E2: R1 = sqrt(52.5^2 + 34^2) = 62.5479816,
// OOB 52.5 and 68. A proximity is 1 - 2 clamp(d / M, 0, 1).
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "core/rng.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/soccer_sim.hpp"
#include "envs/hfo_server/feature_encoding.hpp"
#include "envs/hfo_server/hfo_server_env.hpp"
#include "envs/hfo_server/server_action.hpp"
#include "envs/hfo_server/server_probe.hpp"
#include "envs/registry.hpp"
#include "learner/evaluation.hpp"

namespace pamdp::hfo_server {
namespace {

constexpr double kTol = 2e-6;
const double kR3 = std::sqrt(52.5 * 52.5 + 68.0 * 68.0);

double e3_prox(double d, double max) {
  return 1.0 - 2.0 * std::clamp(d / max, 0.0, 1.0);
}

// The 11 landmarks of features 13-45, in feature order (reference §3.2).
const std::array<hfo::Vec2, 11> kLandmarks{{{52.5, 0.0},
                                            {52.5, -7.01},
                                            {52.5, 7.01},
                                            {36.0, 0.0},
                                            {36.0, -20.16},
                                            {36.0, 20.16},
                                            {0.0, 0.0},
                                            {0.0, -34.0},
                                            {52.5, -34.0},
                                            {52.5, 34.0},
                                            {0.0, 34.0}}};

hfo::SoccerState state_1v0(hfo::Vec2 agent, double body_deg, hfo::Vec2 ball, hfo::Vec2 ball_vel = {}) {
  hfo::SoccerState s;
  s.num_players = 1;
  s.players[0].pos = agent;
  s.players[0].body_deg = body_deg;
  s.ball.pos = ball;
  s.ball.vel = ball_vel;
  s.prev_ball = ball;
  return s;
}

// What the real server sends for `s` (1v0 or with a goalie): the values the two encodings share
// come from the embedded writer; every proximity is recomputed here from the geometry with the E3
// normalizers, independently of the code under test; then the uniform numbers and the
// last-action flag.
std::vector<float> e3_of(const hfo::SoccerState& s, float last_action = 1.0F) {
  const int others = s.num_players - 1;
  std::vector<float> e1(static_cast<size_t>(hfo::feature_count(s.num_players)));
  hfo::write_features(s, e1);
  std::vector<float> e3(static_cast<size_t>(e3_feature_count(0, others)));
  std::copy(e1.begin(), e1.end(), e3.begin());
  const hfo::Vec2 p = s.players[0].pos;
  for (size_t k = 0; k < kLandmarks.size(); ++k) {
    e3[hfo::feat::kGoalCentre + 3 * k + 2] = static_cast<float>(e3_prox((kLandmarks[k] - p).r(), kR3));
  }
  e3[hfo::feat::kOobLeft] = static_cast<float>(e3_prox(p.x, 57.75));
  e3[hfo::feat::kOobRight] = static_cast<float>(e3_prox(52.5 - p.x, 57.75));
  e3[hfo::feat::kOobTop] = static_cast<float>(e3_prox(34.0 + p.y, 71.4));
  e3[hfo::feat::kOobBottom] = static_cast<float>(e3_prox(34.0 - p.y, 71.4));
  e3[hfo::feat::kBallProximity] = static_cast<float>(e3_prox((s.ball.pos - p).r(), kR3));
  const size_t unum_base = e3.size() - 1 - static_cast<size_t>(others);  // then one uniform number each
  for (int k = 0; k < others; ++k) {
    const hfo::PlayerState& o = s.players[static_cast<size_t>(k) + 1];
    const bool present = o.pos.x > 0.0;
    const size_t b = hfo::kNumAgentFeatures + static_cast<size_t>(hfo::kFeaturesPerPlayer) * static_cast<size_t>(k);
    if (present) {
      e3[b + 2] = static_cast<float>(e3_prox((o.pos - p).r(), kR3));
    }
    e3[unum_base + static_cast<size_t>(k)] = present ? 0.01F : -1.0F;
  }
  e3.back() = last_action;
  return e3;
}

std::vector<float> converted(const std::vector<float>& e3, int opponents) {
  std::vector<float> out(static_cast<size_t>(hfo::feature_count(1 + opponents)), -7.0F);  // sentinel
  e3_to_embedded(e3, 0, opponents, out);
  return out;
}

TEST(HfoServerFeatures, CountsOfCurrentHfo) {
  EXPECT_EQ(e3_feature_count(0, 0), 59);  // reference §3.4, measured in §9
  EXPECT_EQ(e3_feature_count(0, 1), 68);
  EXPECT_EQ(e3_feature_count(1, 1), 77);
  EXPECT_EQ(e3_last_action_index(0, 0), 58);
  EXPECT_NEAR(e3_max_distance(), 85.9083814, 1e-4);
  EXPECT_FLOAT_EQ(kE3OobLength, 57.75F);
  EXPECT_FLOAT_EQ(kE3OobWidth, 71.4F);
}

// Reference §3.2's worked example, as the real server encodes it, converted back. Agent at (0, 0),
// body 0, at rest; ball at (10, 0).
//   ball: E3 1 - 20/85.9083814 = 0.7671938 -> E1 1 - 20/62.5479816 = 0.6802455.
//   goal centre: E3 1 - 105/85.9083814 = -0.2222323 -> E1 1 - 105/62.5479816 = -0.6787112.
//   corner top-right (52.5, -34): d = R1 = 62.5479816, E3 1 - 125.0959632/85.9083814 = -0.4561555
//     -> E1 exactly -1.
//   corner top-left (0, -34): E3 1 - 68/85.9083814 = 0.2084591 -> E1 1 - 68/62.5479816 = -0.0871654.
//   OOB left d = 0: +1 in both. OOB right d = 52.5: E3 1 - 105/57.75 = -0.8181818 -> E1 -1.
//   OOB top/bottom d = 34: E3 1 - 68/71.4 = 0.0476190 -> E1 1 - 68/68 = 0.
TEST(HfoServerFeatures, WorkedExampleReencodedInE3ConvertsBack) {
  std::vector<float> e3 = e3_of(state_1v0({0.0, 0.0}, 0.0, {10.0, 0.0}));
  ASSERT_EQ(e3.size(), 59U);
  EXPECT_NEAR(e3[53], 0.7671938, kTol);
  EXPECT_NEAR(e3[15], -0.2222323, kTol);
  EXPECT_NEAR(e3[39], -0.4561555, kTol);
  EXPECT_NEAR(e3[36], 0.2084591, kTol);
  EXPECT_NEAR(e3[47], -0.8181818, kTol);
  EXPECT_NEAR(e3[48], 0.0476190, kTol);

  const std::vector<float> f = converted(e3, 0);
  EXPECT_NEAR(f[53], 0.6802455, kTol);
  EXPECT_NEAR(f[51], 0.0, kTol);
  EXPECT_NEAR(f[52], 1.0, kTol);
  EXPECT_NEAR(f[15], -0.6787112, kTol);
  EXPECT_NEAR(f[39], -1.0, kTol);
  EXPECT_NEAR(f[36], -0.0871654, kTol);
  EXPECT_NEAR(f[46], 1.0, kTol);
  EXPECT_NEAR(f[47], -1.0, kTol);
  EXPECT_NEAR(f[48], 0.0, kTol);
  EXPECT_NEAR(f[49], 0.0, kTol);
  EXPECT_NEAR(f[5], 0.0, kTol);
  EXPECT_NEAR(f[6], 1.0, kTol);
}

// Over random 1v0 states the conversion gives exactly what the embedded simulator writes for the
// same state, in every one of the 58 values (positions as far as 8 m outside the field, so
// distances beyond R1 saturate).
TEST(HfoServerFeatures, RandomStatesMatchTheEmbeddedEncoding) {
  Rng rng(17);
  for (int i = 0; i < 2000; ++i) {
    const hfo::Vec2 agent{rng.uniform(-8.0, 60.0), rng.uniform(-40.0, 40.0)};
    const hfo::Vec2 ball{rng.uniform(-2.0, 55.0), rng.uniform(-35.0, 35.0)};
    const hfo::Vec2 ball_vel{rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)};
    const hfo::SoccerState s = state_1v0(agent, rng.uniform(-180.0, 180.0), ball, ball_vel);
    std::vector<float> want(58);
    hfo::write_features(s, want);
    const std::vector<float> got = converted(e3_of(s), 0);
    for (size_t k = 0; k < want.size(); ++k) {
      ASSERT_NEAR(got[k], want[k], kTol) << "feature " << k << ", agent (" << agent.x << ", " << agent.y << ")";
    }
  }
}

// With a goalie the opponent block keeps its layout and its proximity is re-encoded; the uniform
// numbers and the last-action flag are dropped (68 -> 66).
TEST(HfoServerFeatures, OpponentBlockIsReencodedAndTheTailDropped) {
  hfo::SoccerState s = state_1v0({20.0, 5.0}, 30.0, {22.0, 4.0});
  s.num_players = 2;
  s.players[1].pos = {50.0, -1.0};
  s.players[1].body_deg = 180.0;
  s.players[1].vel = {-0.2, 0.1};
  s.players[1].team = hfo::Team::kDefense;
  s.players[1].goalie = true;
  const std::vector<float> e3 = e3_of(s, -1.0F);
  ASSERT_EQ(e3.size(), 68U);
  std::vector<float> want(66);
  hfo::write_features(s, want);
  const std::vector<float> got = converted(e3, 1);
  ASSERT_EQ(got.size(), 66U);
  for (size_t k = 0; k < want.size(); ++k) {
    EXPECT_NEAR(got[k], want[k], kTol) << "feature " << k;
  }
  // d = sqrt(30^2 + 6^2) = 30.5941171: E1 1 - 61.1882343/62.5479816 = 0.0217393.
  EXPECT_NEAR(got[58 + 2], 0.0217393, kTol);
}

// An empty opponent slot is zeros in both encodings (its uniform number is -1), not a player at
// distance R3/2 whose proximity happens to be 0.
TEST(HfoServerFeatures, EmptyOpponentSlotStaysZero) {
  hfo::SoccerState s = state_1v0({20.0, 5.0}, 30.0, {22.0, 4.0});
  s.num_players = 2;
  s.players[1].pos = {-5.0, 0.0};  // x <= 0: not in the HFO area, not listed
  s.players[1].team = hfo::Team::kDefense;
  const std::vector<float> e3 = e3_of(s);
  ASSERT_EQ(e3[58 + 8], -1.0F);
  const std::vector<float> got = converted(e3, 1);
  for (int k = 58; k < 66; ++k) {
    EXPECT_EQ(got[static_cast<size_t>(k)], 0.0F) << "feature " << k;
  }
  // A listed opponent exactly R3/2 = 42.954 m away has E3 proximity 0 and is re-encoded:
  // E1 1 - 85.9083814/62.5479816 = -0.3734797.
  std::vector<float> e3_present = e3;
  e3_present[58 + 2] = 0.0F;
  e3_present[58 + 8] = 0.01F;
  EXPECT_NEAR(converted(e3_present, 1)[58 + 2], -0.3734797, kTol);
}

// Without a valid self position HFO zeroes every landmark and OOB value; they stay zero.
TEST(HfoServerFeatures, ValuesZeroedByAnInvalidFlagStayZero) {
  std::vector<float> e3(59, 0.0F);
  e3[0] = -1.0F;   // self position invalid
  e3[50] = -1.0F;  // ball position invalid
  e3[58] = 1.0F;
  const std::vector<float> got = converted(e3, 0);
  for (int k = 13; k < 58; ++k) {
    if (k != 50) {
      EXPECT_EQ(got[static_cast<size_t>(k)], 0.0F) << "feature " << k;
    }
  }
}

// The config keys of the real-server env: defaults, validation, round trip.
TEST(HfoServerConfig, KeysAreValidatedAndRoundTrip) {
  const app::ExperimentConfig def = app::parse_experiment_config("", "defaults", {});
  EXPECT_EQ(def.env.params.text("server_host"), "localhost");
  EXPECT_EQ(def.env.params.integer("server_port"), 6000);
  EXPECT_EQ(def.env.params.integer("server_eval_port"), 0);
  EXPECT_EQ(server_config(def.env.params).encoding, Encoding::kNative);
  EXPECT_EQ(def.env.params.text("server_team"), "base_left");
  EXPECT_EQ(def.env.params.text("server_config_dir"), "");

  const app::ExperimentConfig c = app::parse_experiment_config(
      "", "x",
      {"env.name=hfo-server", "env.server_host=10.0.0.7", "env.server_port=7000", "env.server_eval_port=7010",
       "env.server_encoding=embedded", "env.server_config_dir=/opt/HFO/bin/teams/base/config/formations-dt"});
  EXPECT_EQ(c.env.name, "hfo-server");
  EXPECT_EQ(c.env.params.integer("server_port"), 7000);
  EXPECT_EQ(server_config(c.env.params).encoding, Encoding::kEmbedded);
  const app::ExperimentConfig back = app::parse_experiment_config(app::to_toml(c), "round-trip", {});
  EXPECT_EQ(app::to_toml(back), app::to_toml(c));
  EXPECT_EQ(back.env.params.text("server_config_dir"), "/opt/HFO/bin/teams/base/config/formations-dt");

  const auto error_of = [](const std::string& set) {
    try {
      app::parse_experiment_config("", "cfg", {set});
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(error_of("env.server_port=0").find("'env.server_port' must be within [1, 65535]"), std::string::npos);
  EXPECT_NE(error_of("env.server_port=70000").find("env.server_port"), std::string::npos);
  EXPECT_NE(error_of("env.server_encoding=e3").find("native, embedded"), std::string::npos);
  EXPECT_NE(error_of("env.server_host=''").find("'env.server_host' must be a non-empty string"), std::string::npos);
  EXPECT_NE(error_of("env.name=hfo_server").find(env_registry().names_joined()), std::string::npos);
  EXPECT_NE(error_of("env.server_prot=7000").find("server_port"), std::string::npos);  // lists the valid keys
  EXPECT_EQ(def.env.params.integer("server_connect_timeout_s"), 30);
  EXPECT_EQ(server_config(app::parse_experiment_config("", "x", {"env.server_connect_timeout_s=5"}).env.params)
                .connect_timeout_s,
            5);
  EXPECT_NE(error_of("env.server_connect_timeout_s=0").find("'env.server_connect_timeout_s' must be within [1, 3600]"),
            std::string::npos);
  EXPECT_NE(error_of("env.server_connect_timeout_s=3601").find("env.server_connect_timeout_s"), std::string::npos);
}

// Parameters outside the server's ranges reach it clipped (powers) or wrapped (directions), as
// HFO's client (librcsc) and the embedded simulator treat them, and each one is counted.
TEST(HfoServerActions, OutOfRangeParametersAreClippedWrappedAndCounted) {
  ActionClampCounts counts;
  const auto args = [&](int id, std::array<float, 6> p) { return server_command_args({id, p}, counts); };
  ServerCommandArgs a = args(hfo::kKick, {0, 0, 0, 0, 100.2F, 30});  // the server log's "com=100.2"
  EXPECT_EQ(a.p1, 100.0);
  EXPECT_EQ(a.p2, 30.0);
  a = args(hfo::kKick, {0, 0, 0, 0, -3, 181});
  EXPECT_EQ(a.p1, 0.0);
  EXPECT_NEAR(a.p2, -179.0, 1e-9);
  EXPECT_EQ(counts.kick_power, 2);
  EXPECT_EQ(counts.direction, 1);
  a = args(hfo::kKick, {0, 0, 0, 0, 100, -180});  // both ends are in range
  EXPECT_EQ(a.p1, 100.0);
  EXPECT_EQ(a.p2, -180.0);
  a = args(hfo::kDash, {-100, 180, 0, 0, 500, 500});  // in range; the kick's parameters are not read
  EXPECT_EQ(a.p1, -100.0);
  EXPECT_EQ(a.p2, 180.0);
  EXPECT_EQ(counts.total(), 3);
  a = args(hfo::kDash, {-100.5F, -270, 0, 0, 0, 0});
  EXPECT_EQ(a.p1, -100.0);
  EXPECT_NEAR(a.p2, 90.0, 1e-9);
  a = args(hfo::kDash, {101, 0, 0, 0, 0, 0});
  EXPECT_EQ(a.p1, 100.0);
  EXPECT_EQ(counts.dash_power, 2);
  EXPECT_NEAR(args(hfo::kTurn, {0, 0, 190, 0, 0, 0}).p1, -170.0, 1e-9);
  EXPECT_NEAR(args(hfo::kTackle, {0, 0, 0, -540, 0, 0}).p1, 180.0, 1e-9);
  EXPECT_EQ(args(hfo::kTurn, {0, 0, 12.5F, 0, 0, 0}).p1, 12.5);
  EXPECT_EQ(counts.kick_power, 2);
  EXPECT_EQ(counts.dash_power, 2);
  EXPECT_EQ(counts.direction, 4);
}

// env.shoot_action's SHOOT is a kick with its own two parameters: the server gets KICK's
// arguments from them, clipped and counted as a kick's are, and KICK's slots are not read.
TEST(HfoServerActions, ShootSendsAKickFromItsOwnParameters) {
  ActionClampCounts counts;
  const auto args = [&](int id, std::array<float, 8> p) { return server_command_args({id, p}, counts); };
  ServerCommandArgs a = args(hfo::kShoot, {0, 0, 0, 0, 3, -40, 100, 12.5F});
  EXPECT_EQ(a.p1, 100.0);
  EXPECT_EQ(a.p2, 12.5);
  EXPECT_EQ(counts.total(), 0);
  a = args(hfo::kShoot, {0, 0, 0, 0, 50, 0, 104, 190});
  EXPECT_EQ(a.p1, 100.0);
  EXPECT_NEAR(a.p2, -170.0, 1e-9);
  EXPECT_EQ(counts.kick_power, 1);
  EXPECT_EQ(counts.direction, 1);
  a = args(hfo::kKick, {0, 0, 0, 0, 3, -40, 100, 12.5F});  // KICK still reads its own
  EXPECT_EQ(a.p1, 3.0);
  EXPECT_EQ(a.p2, -40.0);
}

// A UDP socket on 127.0.0.1 that answers every datagram from the `first_answered`-th on (1-based),
// as rcssserver answers an unknown command; a server that is still starting answers none at first.
class FakeServer {
 public:
  explicit FakeServer(int first_answered) : fd_(socket(AF_INET, SOCK_DGRAM, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof(a);
    if (fd_ < 0 || bind(fd_, reinterpret_cast<sockaddr*>(&a), len) != 0 ||
        getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
      throw std::runtime_error("FakeServer: cannot bind a UDP socket on 127.0.0.1");
    }
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this, first_answered] {
      for (int received = 0; !stop_.load();) {
        pollfd p{fd_, POLLIN, 0};
        if (poll(&p, 1, 50) <= 0) {
          continue;
        }
        sockaddr_in from{};
        socklen_t from_len = sizeof(from);
        std::array<char, 256> buf{};
        if (recvfrom(fd_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&from), &from_len) > 0 &&
            ++received >= first_answered) {
          static constexpr char kReply[] = "(error unknown_command)";
          (void)sendto(fd_, kReply, sizeof(kReply), 0, reinterpret_cast<sockaddr*>(&from), from_len);
        }
      }
    });
  }
  FakeServer(const FakeServer&) = delete;
  FakeServer& operator=(const FakeServer&) = delete;
  ~FakeServer() {
    stop_ = true;
    thread_.join();
    close(fd_);
  }
  [[nodiscard]] int port() const { return port_; }

 private:
  int fd_;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(HfoServerProbe, AServerUpAlreadyIsJoinedAtOnce) {
  const FakeServer server(1);
  const ServerProbe probe = probe_server("127.0.0.1", server.port(), 5.0);
  EXPECT_TRUE(probe.answered);
  EXPECT_TRUE(probe.answered_at_once);
  EXPECT_LT(probe.waited_s, 0.5);
}

// The retry: a server that does not answer the first two probes (one still starting) is waited
// for, and the env then knows it came up late (and gives its trainer time to fill the NPC slots).
TEST(HfoServerProbe, AServerThatComesUpWhileWaitingIsWaitedFor) {
  const FakeServer server(3);
  const ServerProbe probe = probe_server("127.0.0.1", server.port(), 5.0);
  EXPECT_TRUE(probe.answered);
  EXPECT_FALSE(probe.answered_at_once);
  EXPECT_GT(probe.waited_s, 0.9);  // two unanswered probes, 0.5 s apart
  EXPECT_LT(probe.waited_s, 3.0);
}

TEST(HfoServerProbe, NoServerTimesOutWithTheFixNamed) {
  int port = 0;
  {
    const FakeServer gone(1);  // a port that was free a moment ago and is closed again
    port = gone.port();
  }
  const ServerProbe probe = probe_server("127.0.0.1", port, 1.0);
  EXPECT_FALSE(probe.answered);
  EXPECT_GE(probe.waited_s, 1.0);
  EXPECT_LT(probe.waited_s, 2.0);

  HfoServerConfig c;
  c.port = port;
  c.opponents = 1;
  c.connect_timeout_s = 1;
  const std::string message = no_server_message(c, "/opt/HFO");
  const std::string where = "localhost:" + std::to_string(port);
  EXPECT_NE(message.find("no HFO server answers at " + where + " (waited 1 s, env.server_connect_timeout_s)"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("/usr/bin/python3 /opt/HFO/bin/HFO --offense-agents 1 --defense-npcs 1"), std::string::npos)
      << message;
  EXPECT_NE(message.find("--port " + std::to_string(port)), std::string::npos) << message;
  EXPECT_NE(message.find("Waiting for player-controlled agent"), std::string::npos) << message;
}

// An env's counters reach the evaluation result (and its JSON) as counts over the evaluated
// episodes; envs without counters add no key, so their JSON is unchanged.
TEST(HfoServerActions, EnvCountersReachTheEvaluationResult) {
  class CountingEnv final : public Env {
   public:
    [[nodiscard]] std::string_view name() const override { return "counting"; }
    [[nodiscard]] const ActionSpace& action_space() const override { return hfo::hfo_action_space(); }
    [[nodiscard]] int observation_size() const override { return 1; }
    [[nodiscard]] int max_episode_steps() const override { return 3; }
    [[nodiscard]] std::string_view status_name(int s) const override { return s == 0 ? "IN_GAME" : "GOAL"; }
    [[nodiscard]] std::span<const int> outcomes() const override {
      static constexpr std::array<int, 2> kOutcomes{0, 1};
      return kOutcomes;
    }
    [[nodiscard]] int success_status() const override { return 1; }
    [[nodiscard]] std::span<const EnvCounter> counters() const override {
      counters_[0] = {"kick_power_clamped", clamps_.kick_power};
      return counters_;
    }
    void reset(uint64_t /*seed*/, std::span<float> obs) override { reset(obs); }
    void reset(std::span<float> obs) override { obs[0] = 0.0F; }
    StepResult step(const ParamAction& action, std::span<float> obs) override {
      (void)server_command_args(action, clamps_);
      obs[0] = 0.0F;
      return {0.0F, 1};
    }

   private:
    ActionClampCounts clamps_;
    mutable std::array<EnvCounter, 1> counters_{};
  };
  class OverPowerKick final : public Policy {
   public:
    ParamAction act(std::span<const float> /*obs*/) override { return {hfo::kKick, params_}; }

   private:
    std::array<float, 6> params_{0, 0, 0, 0, 100.2F, 0};
  };
  CountingEnv env;
  OverPowerKick policy;
  (void)evaluate(env, policy, 2, 1);
  const EvalResult r = evaluate(env, policy, 3, 1);  // counts these 3 episodes, not the 2 before
  EXPECT_EQ(r.env_counters.at("kick_power_clamped"), 3);
  EXPECT_NE(to_json(r).find("\"env_counters\":{\"kick_power_clamped\":3}"), std::string::npos) << to_json(r);
  EvalResult none = r;
  none.env_counters.clear();
  EXPECT_EQ(to_json(none).find("env_counters"), std::string::npos);
}

// Widths come from the env: 59 native / 58 embedded in 1v0, 68 / 66 with a goalie.
TEST(HfoServerEnv, ObservationSizesComeFromTheConfig) {
  app::EnvConfig e;
  e.name = "hfo-server";
  EXPECT_EQ(app::observation_size(e), 59);
  e.params.set("server_encoding", std::string("embedded"));
  EXPECT_EQ(app::observation_size(e), 58);
  e.params.set("goalie", true);
  EXPECT_EQ(app::observation_size(e), 66);
  e.params.set("server_encoding", std::string("native"));
  EXPECT_EQ(app::observation_size(e), 68);
  // One of two offense agents (bin/HFO --offense-agents 2): a teammate block and its uniform
  // number more, 58 + 9 + 9 + 1 = 77 native, 58 + 8 + 8 = 74 embedded.
  e.params.set("offense_agents", int64_t{2});
  EXPECT_EQ(app::observation_size(e), 77);
  e.params.set("server_encoding", std::string("embedded"));
  EXPECT_EQ(app::observation_size(e), 74);
}

// Without HFO the env name is known but making one names the fix; with HFO, making one opens no
// connection (the learner and shards make one only for its sizes).
TEST(HfoServerEnv, CreationWithoutHfoNamesTheFixAndWithHfoDoesNotConnect) {
  app::EnvConfig e;
  e.name = "hfo-server";
  e.params.set("server_port", int64_t{1});  // nothing listens there
  if (!built_with_hfo()) {
    try {
      (void)app::make_env(e);
      FAIL() << "made an hfo-server env without HFO";
    } catch (const std::runtime_error& err) {
      EXPECT_NE(std::string(err.what()).find("rebuild with -DHFO_ROOT=/path/to/HFO"), std::string::npos) << err.what();
    }
    return;
  }
  const std::unique_ptr<Env> env = app::make_env(e);
  EXPECT_EQ(env->name(), "hfo-server");
  EXPECT_EQ(env->observation_size(), 59);
  EXPECT_EQ(env->action_space().num_actions(), 4);
  EXPECT_EQ(env->max_episode_steps(), 501);
  EXPECT_EQ(env->status_name(env->success_status()), "GOAL");
}

// Greedy evaluations of train / learner need a server of their own, asked for at start-up.
TEST(HfoServerEnv, EvaluationsNeedTheirOwnServer) {
  app::ExperimentConfig c = app::parse_experiment_config("", "x", {"env.name=hfo-server", "env.server_port=7000"});
  if (!built_with_hfo()) {
    GTEST_SKIP() << "no HFO in this build";
  }
  try {
    (void)app::make_eval_env(c);
    FAIL() << "evaluations on the acting server were accepted";
  } catch (const std::runtime_error& err) {
    EXPECT_NE(std::string(err.what()).find("env.server_eval_port"), std::string::npos) << err.what();
  }
  c.train.eval_episodes = 0;
  EXPECT_NO_THROW((void)app::make_eval_env(c));
  c.train.eval_episodes = 10;
  c.env.params.set("server_eval_port", int64_t{7010});
  EXPECT_NO_THROW((void)app::make_eval_env(c));
}

}  // namespace
}  // namespace pamdp::hfo_server
