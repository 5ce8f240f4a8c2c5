// The hfo-server env against a real HFO server (1v0, --fullstate), started by
// tests/hfo_server_test.sh, which passes its port in PAMDP_HFO_PORT (skipped without it). Plays
// the scripted offense in the server's own encoding and checks, on every observation:
//  - 59 values in [-1, 1], the last the +1/-1 "command accepted" flag;
//  - the embedded view (e3_to_embedded) is geometrically consistent: the agent's x from the left
//    and from the right out-of-bounds proximity agree, likewise y from top and bottom, and the
//    goal-centre and corner proximities give the distances from that (x, y) — so the normalizers
//    of both encodings (R 85.908 / 62.548, OOB 57.75 / 71.4 vs 52.5 / 68) are right on real data;
//  - every episode starts with ball and agent at rest; the reward is the embedded env's shaped
//    reward of the embedded view, exactly 5 on a goal.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "envs/hfo/features.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/hfo_server/feature_encoding.hpp"
#include "envs/hfo_server/hfo_server_env.hpp"

namespace pamdp::hfo_server {
namespace {

constexpr double kMetreTol = 5e-3;

// Distance encoded by an embedded proximity with maximum `max`, or -1 where it saturated.
double distance(float p, double max) {
  return p > -0.99999F && p < 0.99999F ? (1.0 - p) * 0.5 * max : -1.0;
}

void check_geometry(const std::vector<float>& f, int step) {
  const double x_left = distance(f[hfo::feat::kOobLeft], hfo::kPitchHalfLength);
  const double x_right = distance(f[hfo::feat::kOobRight], hfo::kPitchHalfLength);
  const double y_top = distance(f[hfo::feat::kOobTop], 2.0 * hfo::kPitchHalfWidth);
  const double y_bottom = distance(f[hfo::feat::kOobBottom], 2.0 * hfo::kPitchHalfWidth);
  if (x_left < 0.0 || x_right < 0.0 || y_top < 0.0 || y_bottom < 0.0) {
    return;  // on or outside a line: one side saturates
  }
  const double x = x_left;
  const double y = y_top - hfo::kPitchHalfWidth;
  ASSERT_NEAR(x, hfo::kPitchHalfLength - x_right, kMetreTol) << "step " << step;
  ASSERT_NEAR(y, hfo::kPitchHalfWidth - y_bottom, kMetreTol) << "step " << step;
  struct Landmark {
    int index = 0;
    hfo::Vec2 at;
  };
  const Landmark landmarks[] = {{hfo::feat::kGoalCentre, {52.5, 0.0}},
                                {hfo::feat::kPenaltyTop, {36.0, -20.16}},
                                {hfo::feat::kCentreField, {0.0, 0.0}},
                                {hfo::feat::kCornerTopLeft, {0.0, -34.0}},
                                {hfo::feat::kCornerBottomRight, {52.5, 34.0}}};
  for (const auto& l : landmarks) {
    const double d = distance(f[static_cast<size_t>(l.index) + 2], hfo::kMaxDistance);
    if (d >= 0.0) {
      ASSERT_NEAR(d, (l.at - hfo::Vec2{x, y}).r(), kMetreTol) << "landmark at feature " << l.index << ", step " << step;
    }
  }
}

TEST(HfoServerLive, ScriptedOffenseOnTheRealServer) {
  const char* port = std::getenv("PAMDP_HFO_PORT");
  if (port == nullptr) {
    GTEST_SKIP() << "PAMDP_HFO_PORT not set (tests/hfo_server_test.sh starts a server)";
  }
  const char* episodes_env = std::getenv("PAMDP_HFO_EPISODES");
  const int episodes = episodes_env != nullptr ? std::atoi(episodes_env) : 5;
  HfoServerConfig c;
  c.port = std::atoi(port);
  c.encoding = Encoding::kNative;
  const std::unique_ptr<Env> env = make_hfo_server_env(c);
  ASSERT_EQ(env->observation_size(), 59);

  std::vector<float> obs(59);
  std::vector<float> embedded(58);
  hfo::ScriptedOffense policy;
  hfo::ShapedReward reward;
  int goals = 0;
  int steps = 0;
  for (int ep = 0; ep < episodes; ++ep) {
    env->reset(obs);
    e3_to_embedded(obs, 0, 0, embedded);
    EXPECT_FLOAT_EQ(embedded[hfo::feat::kBallSpeed], -1.0F) << "episode " << ep << " starts with the ball moving";
    EXPECT_FLOAT_EQ(embedded[hfo::feat::kSelfSpeed], -1.0F) << "episode " << ep << " starts with the agent moving";
    reward.reset();
    StepResult r;
    do {
      r = env->step(policy.act(embedded), obs);
      ++steps;
      for (float v : obs) {
        ASSERT_LE(std::abs(v), 1.0F);
      }
      ASSERT_TRUE(obs[58] == 1.0F || obs[58] == -1.0F) << obs[58];
      e3_to_embedded(obs, 0, 0, embedded);
      check_geometry(embedded, steps);
      ASSERT_FLOAT_EQ(r.reward, reward(embedded, r.status)) << "step " << steps;
    } while (!r.terminal());
    if (r.status == env->success_status()) {
      ++goals;
      EXPECT_FLOAT_EQ(r.reward, 5.0F);
    }
  }
  // The scripted offense scores every one of 300 episodes on the real server (docs/hfo-server.md).
  EXPECT_GE(goals, episodes - 1) << goals << " goals in " << episodes << " episodes";
}

}  // namespace
}  // namespace pamdp::hfo_server
