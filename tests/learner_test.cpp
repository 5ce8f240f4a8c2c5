// Learning code: gradient bounds computed by hand, exploration, DDPG target updates, config
// parsing, checkpoints (atomic, verified, bit-for-bit resume) and an end-to-end test that
// `pamdp train` solves the toy ReachStop PAMDP.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "actor/exploration.hpp"
#include "app/experiment_config.hpp"
#include "app/trainer.hpp"
#include "core/actor_output.hpp"
#include "core/files.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/toy/reach_stop.hpp"
#include "learner/checkpoint.hpp"
#include "learner/ddpg.hpp"
#include "learner/ddpg_algorithm.hpp"
#include "learner/gradient_bounds.hpp"
#include "learner/sampler.hpp"
#include "learner/update_backend.hpp"
#include "replay/episode_buffer.hpp"
#include "replay/replay_buffer.hpp"
#include "replay/replay_snapshot.hpp"

namespace pamdp {
namespace {

namespace fs = std::filesystem;

OutputBounds one_bound(float lo, float hi) {
  OutputBounds b;
  b.lo = {lo};
  b.hi = {hi};
  return b;
}

float bounded(BoundMethod m, float lo, float hi, float p, float grad, float raw = 0.0F) {
  Eigen::MatrixXf P(1, 1);
  Eigen::MatrixXf R(1, 1);
  Eigen::MatrixXf G(1, 1);
  P(0, 0) = p;
  R(0, 0) = raw;
  G(0, 0) = grad;
  apply_gradient_bounds(m, one_bound(lo, hi), P, R, G);
  return G(0, 0);
}

// Paper §5 / reference §7.4 step 5, with dash power bounds [0, 100]. g < 0 means "increase".
TEST(GradientBounds, InvertingByHand) {
  // p = 25, g = -2 (increase): scale (100 - 25) / 100 = 0.75 -> -1.5.
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kInverting, 0, 100, 25, -2), -1.5F);
  // p = 25, g = +2 (decrease): scale (25 - 0) / 100 = 0.25 -> 0.5.
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kInverting, 0, 100, 25, 2), 0.5F);
  // At the upper bound an "increase" gradient vanishes: (100 - 100) / 100 = 0.
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kInverting, 0, 100, 100, -2), 0.0F);
  // Above the bound it is inverted: p = 120, g = -2: (100 - 120) / 100 = -0.2 -> +0.4 (decrease).
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kInverting, 0, 100, 120, -2), 0.4F);
  // Below the lower bound a "decrease" gradient is inverted: p = -10, g = 1: (-10 - 0) / 100 -> -0.1.
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kInverting, 0, 100, -10, 1), -0.1F);
  // Directions [-180, 180]: p = 90, g = -1: (180 - 90) / 360 = 0.25.
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kInverting, -180, 180, 90, -1), -0.25F);
}

TEST(GradientBounds, ZeroingByHand) {
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kZeroing, 0, 100, 50, -3), -3.0F);  // inside: untouched
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kZeroing, 0, 100, 100, -3), 0.0F);  // at max, pushing up
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kZeroing, 0, 100, 130, -3), 0.0F);  // above max, pushing up
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kZeroing, 0, 100, 130, 3), 3.0F);   // above max, pulling back
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kZeroing, 0, 100, -5, 3), 0.0F);    // below min, pushing down
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kZeroing, 0, 100, -5, -3), -3.0F);  // below min, pulling back
}

TEST(GradientBounds, SquashingChainRule) {
  // p = lo + (hi - lo)(tanh(u) + 1)/2; dp/du = (hi - lo)/2 (1 - tanh(u)^2).
  // u = 0: dp/du = 50 -> g 0.1 becomes 5. u = 1: 50 (1 - tanh(1)^2) = 50 * 0.41997434 = 20.998717.
  EXPECT_FLOAT_EQ(bounded(BoundMethod::kSquashing, 0, 100, 50, 0.1F, 0.0F), 5.0F);
  EXPECT_NEAR(bounded(BoundMethod::kSquashing, 0, 100, 88.0797F, 1.0F, 1.0F), 20.998717, 1e-4);
  // Saturated: u = 10 -> 1 - tanh(10)^2 ~ 8.2e-9, the gradient all but vanishes.
  EXPECT_LT(std::fabs(bounded(BoundMethod::kSquashing, 0, 100, 100, 1.0F, 10.0F)), 1e-5);
  std::vector<float> out(1);
  squash(std::vector<float>{0.0F}, one_bound(-180, 180), out);
  EXPECT_FLOAT_EQ(out[0], 0.0F);
}

TEST(GradientBounds, ParsesNames) {
  BoundMethod m{};
  EXPECT_TRUE(parse_bound_method("zeroing", &m));
  EXPECT_EQ(m, BoundMethod::kZeroing);
  EXPECT_FALSE(parse_bound_method("clip", &m));
}

TEST(Exploration, EpsilonSchedules) {
  EXPECT_DOUBLE_EQ(linear_epsilon(0, 1.0, 0.1, 10000), 1.0);
  EXPECT_DOUBLE_EQ(linear_epsilon(5000, 1.0, 0.1, 10000), 0.55);
  EXPECT_DOUBLE_EQ(linear_epsilon(10000, 1.0, 0.1, 10000), 0.1);
  EXPECT_DOUBLE_EQ(linear_epsilon(50000, 1.0, 0.1, 10000), 0.1);
  // Ape-X: 0.4^(1 + 7 i / (N - 1)); i = 0 -> 0.4, i = N - 1 -> 0.4^8 = 0.00065536.
  EXPECT_DOUBLE_EQ(apex_epsilon(0, 8), 0.4);
  EXPECT_NEAR(apex_epsilon(7, 8), 0.00065536, 1e-12);
  EXPECT_DOUBLE_EQ(apex_epsilon(0, 1), 0.4);
  // Demonstrations: constant without an anneal, else linear down to 0.
  EXPECT_DOUBLE_EQ(demo_share(123456, 0.3, 0, 0.0), 0.3);
  EXPECT_DOUBLE_EQ(demo_share(0, 0.5, 100, 0.0), 0.5);
  EXPECT_DOUBLE_EQ(demo_share(50, 0.5, 100, 0.0), 0.25);
  EXPECT_DOUBLE_EQ(demo_share(100, 0.5, 100, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(demo_share(5000, 0.5, 100, 0.0), 0.0);
  // With a floor (exploration.demo_fraction_end): linear down to it, then kept.
  EXPECT_DOUBLE_EQ(demo_share(50, 0.5, 100, 0.1), 0.3);
  EXPECT_DOUBLE_EQ(demo_share(100, 0.5, 100, 0.1), 0.1);
  EXPECT_DOUBLE_EQ(demo_share(5000, 0.5, 100, 0.1), 0.1);
  EXPECT_DOUBLE_EQ(demo_share(5000, 0.3, 0, 0.1), 0.3);
}

TEST(Exploration, RandomActionsFollowThePaper) {
  const ActionSpace& space = hfo::hfo_action_space();
  ExplorationConfig cfg;
  cfg.masked_actions = {hfo::kTackle};
  cfg.random_param_lo = {-100, -180, -180, -180, 0, -180};
  cfg.random_param_hi = {100, 180, 180, 180, 100, 180};
  EpsilonGreedy eg(space, cfg, 3);
  std::vector<float> net(10, 0.0F);
  net[hfo::kTackle] = 5.0F;  // the network prefers tackle; it is masked
  net[hfo::kKick] = 1.0F;
  std::vector<float> stored(10);
  std::vector<int> counts(4, 0);
  bool saw_back_dash = false;
  for (int i = 0; i < 6000; ++i) {
    const int id = eg.select(net, 1.0, stored);
    ++counts[static_cast<size_t>(id)];
    for (int a = 0; a < 4; ++a) {
      EXPECT_GE(stored[static_cast<size_t>(a)], -1.0F);
      EXPECT_LE(stored[static_cast<size_t>(a)], 1.0F);
    }
    EXPECT_GE(stored[4 + hfo::param::kKickPower], 0.0F);
    saw_back_dash = saw_back_dash || stored[4 + hfo::param::kDashPower] < 0.0F;
  }
  EXPECT_EQ(counts[hfo::kTackle], 0);
  for (int a : {hfo::kDash, hfo::kTurn, hfo::kKick}) {
    EXPECT_NEAR(counts[static_cast<size_t>(a)] / 6000.0, 1.0 / 3.0, 0.03);  // uniform over 3, ~5 sigma
  }
  EXPECT_TRUE(saw_back_dash);
  // Greedy: tackle masked, so kick wins, and the stored vector is the network's.
  EXPECT_EQ(eg.select(net, 0.0, stored), hfo::kKick);
  EXPECT_EQ(stored, net);
}

TEST(Exploration, ParameterNoiseIsGaussianAroundTheGreedyParametersAndStaysInBounds) {
  const ActionSpace& space = hfo::hfo_action_space();
  ExplorationConfig cfg;
  cfg.masked_actions = {hfo::kTackle};
  cfg.param_noise = 0.1;
  EpsilonGreedy eg(space, cfg, 5);
  std::vector<float> net(10, 0.0F);
  net[hfo::kKick] = 1.0F;
  net[4 + hfo::param::kDashPower] = 40.0F;  // bounds [0, 100]: std 0.1 * 50 = 5
  net[4 + hfo::param::kKickDir] = -30.0F;   // bounds [-180, 180]: std 18
  net[4 + hfo::param::kKickPower] = 99.0F;  // bounds [0, 100]: std 5, clamped at 100
  std::vector<float> stored(10);
  const int n = 20000;
  double sum_dash = 0;
  double sq_dash = 0;
  double sum_dir = 0;
  double sq_dir = 0;
  int at_max_power = 0;
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(eg.select(net, 0.0, stored), hfo::kKick);  // the discrete choice stays greedy
    for (int a = 0; a < 4; ++a) {
      EXPECT_EQ(stored[static_cast<size_t>(a)], net[static_cast<size_t>(a)]);  // scores untouched
    }
    const double dash = stored[4 + hfo::param::kDashPower] - 40.0;
    const double dir = stored[4 + hfo::param::kKickDir] + 30.0;
    sum_dash += dash;
    sq_dash += dash * dash;
    sum_dir += dir;
    sq_dir += dir * dir;
    const float power = stored[4 + hfo::param::kKickPower];
    ASSERT_GE(power, 0.0F);
    ASSERT_LE(power, 100.0F);
    at_max_power += power == 100.0F ? 1 : 0;
  }
  // Means within ~5 standard errors of 0, standard deviations within 3 % of 5 and 18.
  EXPECT_NEAR(sum_dash / n, 0.0, 5 * 5 / std::sqrt(n));
  EXPECT_NEAR(sum_dir / n, 0.0, 5 * 18 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sq_dash / n), 5.0, 0.15);
  EXPECT_NEAR(std::sqrt(sq_dir / n), 18.0, 0.54);
  // P(99 + 5 z > 100) = P(z > 0.2) = 0.42: those draws are clamped to the bound.
  EXPECT_NEAR(at_max_power / static_cast<double>(n), 0.42, 0.02);

  // Without parameter noise a greedy step stores the network's vector unchanged.
  cfg.param_noise = 0.0;
  EpsilonGreedy plain(space, cfg, 5);
  plain.select(net, 0.0, stored);
  EXPECT_EQ(stored, net);
  cfg.param_noise = 1.5;
  EXPECT_THROW(EpsilonGreedy(space, cfg, 5), std::invalid_argument);
}

// exploration.uniform_random_params = false (MP-DQN's runs): a random step draws the scores only
// and keeps the network's parameters.
TEST(Exploration, RandomActionsCanKeepThePolicysParameters) {
  const ActionSpace& space = hfo::hfo_action_space();
  ExplorationConfig cfg;
  cfg.masked_actions = {hfo::kTackle};
  cfg.uniform_random_params = false;
  EpsilonGreedy eg(space, cfg, 3);
  std::vector<float> net(10, 0.0F);
  for (int i = 0; i < 6; ++i) {
    net[static_cast<size_t>(4 + i)] = 10.0F + static_cast<float>(i);
  }
  std::vector<float> stored(10);
  std::vector<int> counts(4, 0);
  for (int i = 0; i < 3000; ++i) {
    ++counts[static_cast<size_t>(eg.select(net, 1.0, stored))];
    EXPECT_TRUE(std::equal(net.begin() + 4, net.end(), stored.begin() + 4));
  }
  EXPECT_EQ(counts[hfo::kTackle], 0);
  for (int a : {hfo::kDash, hfo::kTurn, hfo::kKick}) {
    EXPECT_NEAR(counts[static_cast<size_t>(a)] / 3000.0, 1.0 / 3.0, 0.045);
  }
}

// exploration.gated_actions: a gated action (HFO's KICK, on the kickable feature) is neither the
// greedy nor a random choice where its feature is off, and is both where it is on; without the
// observation a gated selector refuses to choose.
TEST(Exploration, AGatedActionIsTakenOnlyWhereItsFeatureIsOn) {
  const ActionSpace& space = hfo::hfo_action_space();
  ExplorationConfig cfg;
  cfg.masked_actions = {hfo::kTackle};
  cfg.gates = {{hfo::kKick, 12}};
  EpsilonGreedy eg(space, cfg, 3);
  std::vector<float> net(10, 0.0F);
  net[hfo::kKick] = 2.0F;  // the network prefers kick, then turn
  net[hfo::kTurn] = 1.0F;
  std::vector<float> shut(58, 0.0F);
  shut[12] = -1.0F;
  std::vector<float> open = shut;
  open[12] = 1.0F;
  std::vector<float> stored(10);
  EXPECT_EQ(eg.greedy(shut, net), hfo::kTurn);
  EXPECT_EQ(eg.greedy(open, net), hfo::kKick);
  EXPECT_EQ(eg.select(shut, net, 0.0, stored), hfo::kTurn);
  EXPECT_EQ(stored, net);  // the stored scores are the network's: the learner applies the gate itself
  std::vector<int> counts_shut(4, 0);
  std::vector<int> counts_open(4, 0);
  for (int i = 0; i < 3000; ++i) {
    ++counts_shut[static_cast<size_t>(eg.select(shut, net, 1.0, stored))];
    ++counts_open[static_cast<size_t>(eg.select(open, net, 1.0, stored))];
  }
  EXPECT_EQ(counts_shut[hfo::kKick], 0);
  EXPECT_NEAR(counts_shut[hfo::kDash] / 3000.0, 0.5, 0.045);
  EXPECT_NEAR(counts_open[hfo::kKick] / 3000.0, 1.0 / 3.0, 0.045);
  EXPECT_THROW((void)eg.greedy(net), std::logic_error);
  EXPECT_THROW(eg.select(net, 0.0, stored), std::logic_error);
  cfg.gates = {{hfo::kDash, 12}, {hfo::kTurn, 12}, {hfo::kKick, 12}};  // no action left in some states
  EXPECT_THROW(EpsilonGreedy(space, cfg, 3), std::invalid_argument);
}

TEST(ReplayBuffer, FifoAndSampling) {
  ReplayBuffer rb(3, 1, 1);
  Rng rng(1);
  for (int i = 0; i < 5; ++i) {
    const float s = static_cast<float>(i);
    rb.insert({{&s, 1}, {&s, 1}, s, {&s, 1}, i == 4, s});
  }
  EXPECT_EQ(rb.size(), 3);
  EXPECT_EQ(rb.inserted(), 5);
  BatchBuffers out(1, 1, 64);
  rb.sample(rng, 64, out);
  std::set<float> seen(out.rewards.begin(), out.rewards.end());
  EXPECT_EQ(seen, (std::set<float>{2.0F, 3.0F, 4.0F}));  // 0 and 1 were evicted
  for (size_t j = 0; j < 64; ++j) {
    EXPECT_EQ(out.terminal[j], out.rewards[j] == 4.0F ? 1.0F : 0.0F);
  }
}

// The one episode buffer of `pamdp train` and the actors: returns by hand for gamma = 0.5,
// the last step terminal (time-outs too), and flush_episode into replay and a second buffer.
TEST(EpisodeBuffer, ReturnsTerminalAndFlush) {
  EpisodeBuffer ep(4, 2, 1);
  EXPECT_EQ(ep.capacity(), 4U);
  const float rewards[3] = {1.0F, 0.0F, 4.0F};
  for (int i = 0; i < 3; ++i) {
    const float s[2] = {static_cast<float>(i), -1.0F};
    const float a[1] = {10.0F + static_cast<float>(i)};
    const float s2[2] = {static_cast<float>(i + 1), -1.0F};
    ep.push(s, a, rewards[i], s2);
  }
  ASSERT_EQ(ep.size(), 3U);
  ep.compute_returns(0.5);
  // G2 = 4, G1 = 0 + 0.5 * 4 = 2, G0 = 1 + 0.5 * 2 = 2.
  const float want[3] = {2.0F, 2.0F, 4.0F};
  for (size_t i = 0; i < 3; ++i) {
    const TransitionView t = ep.transition(i);
    EXPECT_FLOAT_EQ(t.mc_return, want[i]) << i;
    EXPECT_EQ(t.terminal, i == 2) << i;
    EXPECT_EQ(t.state[0], static_cast<float>(i));
    EXPECT_EQ(t.next_state[0], static_cast<float>(i + 1));
    EXPECT_EQ(t.action[0], 10.0F + static_cast<float>(i));
    EXPECT_EQ(t.reward, rewards[i]);
  }
  ReplayBuffer replay(8, 2, 1);
  ReplayBuffer also(8, 2, 1);
  flush_episode(ep, 0.5, replay, &also);
  EXPECT_EQ(ep.size(), 0U);
  EXPECT_EQ(replay.inserted(), 3);
  EXPECT_EQ(also.inserted(), 3);
  Rng rng(3);
  BatchBuffers out(2, 1, 64);
  replay.sample(rng, 64, out);
  for (size_t j = 0; j < 64; ++j) {
    const int i = static_cast<int>(out.states[2 * j]);
    ASSERT_GE(i, 0);
    ASSERT_LT(i, 3);
    EXPECT_FLOAT_EQ(out.mc_returns[j], want[i]);
    EXPECT_EQ(out.terminal[j], i == 2 ? 1.0F : 0.0F);
  }
}

// The one "act with this policy" function: raw output without squashing, the tanh map into
// the bounds with it, for the same network and observation.
TEST(ActorOutput, RawOrSquashed) {
  Mlp<float> net({3, 4, 2}, 1);
  Rng rng(7);
  net.init_gaussian(rng, 0.5F);
  Eigen::MatrixXf input(3, 1);
  const float obs[3] = {0.3F, -0.2F, 0.9F};
  float raw[2];
  actor_output(net, input, obs, nullptr, raw);
  Eigen::MatrixXf x(3, 1);
  x << 0.3F, -0.2F, 0.9F;
  const Eigen::MatrixXf ref = net.forward(x);
  EXPECT_EQ(raw[0], ref(0, 0));
  EXPECT_EQ(raw[1], ref(1, 0));
  OutputBounds b;
  b.lo = {-1.0F, 0.0F};
  b.hi = {1.0F, 100.0F};
  float sq[2];
  actor_output(net, input, obs, &b, sq);
  EXPECT_FLOAT_EQ(sq[0], std::tanh(raw[0]));
  EXPECT_FLOAT_EQ(sq[1], 50.0F * (std::tanh(raw[1]) + 1.0F));
}

TEST(ReplayBuffer, SnapshotRoundTripAndCorruption) {
  const fs::path dir = fs::temp_directory_path() / "pamdp_replay_snapshot_test";
  fs::create_directories(dir);
  const std::string path = (dir / "replay.bin").string();
  ReplayBuffer rb(10, 2, 3);
  const std::vector<float> s{1, 2};
  const std::vector<float> a{3, 4, 5};
  for (int i = 0; i < 4; ++i) {
    rb.insert({s, a, static_cast<float>(i), s, false, 0.5F});
  }
  save_replay_snapshot(path, rb);
  ReplayBuffer back(10, 2, 3);
  load_replay_snapshot(path, back);
  EXPECT_EQ(back.size(), 4);
  EXPECT_EQ(back.inserted(), 4);
  EXPECT_TRUE(std::equal(rb.raw().begin(), rb.raw().end(), back.raw().begin()));
  ReplayBuffer other(11, 2, 3);
  EXPECT_THROW(load_replay_snapshot(path, other), std::runtime_error);
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(60);
    f.put('\x7f');
  }
  try {
    load_replay_snapshot(path, back);
    FAIL() << "corrupt snapshot accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

DdpgConfig tiny_config() {
  DdpgConfig c;
  c.hidden = {8};
  c.batch_size = 4;
  c.tau = 0.25;
  return c;
}

// Four ReachStop-shaped transitions (3 observations, 3 outputs) with states and actions drawn
// in [-1, 1], rewards 1, 0, -1, 0.5, the second one terminal.
BatchBuffers four_transitions() {
  BatchBuffers b(3, 3, 4);
  Rng rng(2);
  for (auto* v : {&b.states, &b.actions, &b.next_states}) {
    for (float& x : *v) {
      x = static_cast<float>(rng.uniform(-1, 1));
    }
  }
  b.rewards = {1, 0, -1, 0.5F};
  b.terminal = {0, 1, 0, 0};
  return b;
}

TEST(Ddpg, TargetsStartEqualAndMoveByTau) {
  toy::ReachStopEnv env;
  Ddpg d(3, env.action_space(), tiny_config(), 5);
  const std::vector<float> actor_before(d.actor().params().begin(), d.actor().params().end());
  ASSERT_TRUE(std::equal(actor_before.begin(), actor_before.end(), d.target_actor().params().begin()));
  const BatchBuffers b = four_transitions();
  d.update(view_of(b, 4));
  // theta' = tau theta_new + (1 - tau) theta_old, with theta_old the initial copy.
  for (size_t i = 0; i < actor_before.size(); ++i) {
    const float expect = 0.25F * d.actor().params()[i] + 0.75F * actor_before[i];
    ASSERT_NEAR(d.target_actor().params()[i], expect, 1e-6F) << i;
  }
  EXPECT_EQ(d.updates(), 1);
}

// ddpg.bootstrap_clip: a critic whose output layer is all bias (its weights zeroed) rates every
// (s, a) at that bias, so Q'(s', mu'(s')) is known exactly and each target can be computed by
// hand.
TEST(Ddpg, BootstrapClipBoundsTheTargetNetworksValue) {
  toy::ReachStopEnv env;
  const BatchBuffers b = four_transitions();
  const auto target_mean = [&](float bias, double clip) {
    DdpgConfig c = tiny_config();
    c.gamma = 0.9;
    c.critic_output_init_bias = bias;
    c.bootstrap_clip = clip;
    Ddpg d(3, env.action_space(), c, 5);
    for (Mlp<float>* net : {&d.critic(), &d.target_critic()}) {
      net->weight(net->num_layers() - 1).setZero();
    }
    return d.update(view_of(b, 4)).target_mean;
  };
  // y = r + 0.9 * clamp(Q', -c, c) after the three non-terminal samples, r after the terminal.
  EXPECT_NEAR(target_mean(100.0F, 2.0), (2.8 + 0.0 + 0.8 + 2.3) / 4.0, 1e-6);
  EXPECT_NEAR(target_mean(-100.0F, 2.0), (-0.8 + 0.0 - 2.8 - 1.3) / 4.0, 1e-6);
  EXPECT_NEAR(target_mean(100.0F, 0.0), (91.0 + 0.0 + 89.0 + 90.5) / 4.0, 1e-5);     // off
  EXPECT_NEAR(target_mean(100.0F, 1000.0), (91.0 + 0.0 + 89.0 + 90.5) / 4.0, 1e-5);  // inside the bound
}

// The evaluation average: it starts as the actor, moves by 1 - (1 - tau)^k toward it over k
// updates (one call or k calls alike while the actor holds still), stands still without new
// updates or with tau = 0, and act(kAverage) plays it.
TEST(Ddpg, ActorAverageMovesByTheUpdatesSinceItsLastCall) {
  toy::ReachStopEnv env;
  DdpgConfig c = tiny_config();
  c.actor_average_tau = 0.1;
  Ddpg d(3, env.action_space(), c, 5);
  const std::vector<float> p0(d.actor().params().begin(), d.actor().params().end());
  ASSERT_TRUE(std::equal(p0.begin(), p0.end(), d.actor_average().params().begin()));
  Rng rng(3);
  d.actor().init_gaussian(rng, 0.5F);  // the trained actor, far from where the average began
  const std::vector<float> p1(d.actor().params().begin(), d.actor().params().end());
  d.track_actor_average();  // no update since the start: nothing to absorb
  ASSERT_TRUE(std::equal(p0.begin(), p0.end(), d.actor_average().params().begin()));

  d.set_updates(3);
  d.track_actor_average();
  for (size_t i = 0; i < p0.size(); ++i) {
    ASSERT_NEAR(d.actor_average().params()[i], p0[i] + 0.271F * (p1[i] - p0[i]), 1e-6F) << i;  // 1 - 0.9^3
  }
  EXPECT_EQ(d.actor_average_updates(), 3);
  Ddpg stepwise(3, env.action_space(), c, 5);
  std::copy(p1.begin(), p1.end(), stepwise.actor().params().begin());
  for (int k = 1; k <= 3; ++k) {
    stepwise.set_updates(k);
    stepwise.track_actor_average();
  }
  for (size_t i = 0; i < p0.size(); ++i) {
    ASSERT_NEAR(stepwise.actor_average().params()[i], d.actor_average().params()[i], 1e-6F) << i;
  }

  const std::array<float, 3> obs{0.3F, -0.2F, 0.7F};
  std::vector<float> avg_out(static_cast<size_t>(d.output_width()));
  std::vector<float> online_out(avg_out.size());
  d.act(obs, avg_out, ActorCopy::kAverage);
  d.act(obs, online_out);
  Eigen::MatrixXf in(3, 1);
  in << obs[0], obs[1], obs[2];
  const Eigen::MatrixXf expect = d.actor_average().forward(in);
  for (int i = 0; i < d.output_width(); ++i) {
    EXPECT_FLOAT_EQ(avg_out[static_cast<size_t>(i)], expect(i, 0));
  }
  EXPECT_NE(avg_out, online_out);

  c.actor_average_tau = 0.0;
  Ddpg off(3, env.action_space(), c, 5);
  off.actor().init_gaussian(rng, 0.5F);
  off.set_updates(1000);
  off.track_actor_average();
  EXPECT_TRUE(std::equal(p0.begin(), p0.end(), off.actor_average().params().begin()));
  EXPECT_FALSE(off.averages_actor());
  c.actor_average_tau = 1.5;
  EXPECT_THROW(Ddpg(3, env.action_space(), c, 5), std::invalid_argument);
}

TEST(Ddpg, LearningRatesDecayLinearlyThenHold) {
  // lr 1e-3 (critic 2e-3) falls to 10 % over 4 updates: the update after k done uses
  // lr * (1 - 0.9 * min(k / 4, 1)).
  toy::ReachStopEnv env;
  DdpgConfig c = tiny_config();
  c.actor_learning_rate = 1e-3;
  c.critic_learning_rate = 2e-3;
  c.lr_decay_updates = 4;
  c.lr_final_fraction = 0.1;
  Ddpg d(3, env.action_space(), c, 5);
  BatchBuffers b(3, 3, 4);
  const double want[] = {1.0, 0.775, 0.55, 0.325, 0.1, 0.1};
  for (const double scale : want) {
    d.update(view_of(b, 4));
    EXPECT_DOUBLE_EQ(d.actor_optimizer().config().learning_rate, 1e-3 * scale) << "after " << d.updates();
    EXPECT_DOUBLE_EQ(d.critic_optimizer().config().learning_rate, 2e-3 * scale) << "after " << d.updates();
  }
  // Without a schedule the rates never move.
  c.lr_decay_updates = 0;
  Ddpg constant(3, env.action_space(), c, 5);
  for (int i = 0; i < 3; ++i) {
    constant.update(view_of(b, 4));
  }
  EXPECT_EQ(constant.actor_optimizer().config().learning_rate, 1e-3);
}

// The actor step with demonstrations descends L = -sum Q(s, pi(s)) over the batch + lambda *
// sum over the demonstrations the Q-filter lets through of 1/2 |pi(s_d) - a_d|^2 (the scores
// and the demonstrated action's parameters, in units of half their range). Its gradient is
// recovered exactly from the first Adam step and compared with finite differences of L.
TEST(Ddpg, CloningGradientMatchesFiniteDifferences) {
  toy::ReachStopEnv env;
  const ActionSpace& space = env.action_space();  // MOVE(velocity in [-1, 1]), STOP
  DdpgConfig c = tiny_config();
  c.bound = BoundMethod::kZeroing;  // the identity while no output is at a bound
  c.clip_grad_norm = 0.0;
  c.init_std = 0.3;
  c.actor_learning_rate = 100.0;  // first step: delta = -lr k g / (k |g| + eps), k = sqrt(1 - beta2)
  c.adam_epsilon = 100.0;
  c.demo_bc_weight = 3.0;
  for (const bool filter : {true, false}) {
    c.demo_q_filter = filter;
    Ddpg d(3, space, c, 2);
    BatchBuffers b(3, 3, 4);
    BatchBuffers demo(3, 3, 4);
    Rng rng(9);
    for (auto* v : {&b.states, &b.actions, &b.next_states, &demo.states}) {
      for (float& x : *v) {
        x = static_cast<float>(rng.uniform(-1, 1));
      }
    }
    b.rewards = {1, 0, -1, 0.5F};
    b.terminal = {0, 1, 0, 0};
    // MOVE at 0.8 and -0.6, then STOP twice (its velocity entry is not a demonstration).
    demo.actions = {1, -1, 0.8F, 1, -1, -0.6F, -1, 1, 0.5F, -1, 1, -0.9F};
    const BatchView batch = view_of(b, 4);
    const BatchView demos = view_of(demo, 4);
    const std::vector<float> before(d.actor().params().begin(), d.actor().params().end());
    const UpdateStats stats = d.update(batch, &demos);
    std::vector<float> after(d.actor().params().begin(), d.actor().params().end());

    // L at actor parameters theta, with the critic as the actor step saw it (updated once).
    auto critic_q = [&](const Eigen::MatrixXf& s, const Eigen::MatrixXf& a) {
      Eigen::MatrixXf in(6, 4);
      in.topRows(3) = s;
      in.bottomRows(3) = a;
      return Eigen::MatrixXf(d.critic().forward(in));
    };
    const Eigen::MatrixXf s_b = batch.states;
    const Eigen::MatrixXf s_d = demos.states;
    const Eigen::MatrixXf a_d = demos.actions;
    std::copy(before.begin(), before.end(), d.actor().params().begin());
    const Eigen::MatrixXf pi_d0 = d.actor().forward(s_d);
    const Eigen::MatrixXf q_demo = critic_q(s_d, a_d);
    const Eigen::MatrixXf q_pi = critic_q(s_d, pi_d0);
    const Eigen::MatrixXf pi_b0 = d.actor().forward(s_b);
    ASSERT_LT(std::max(pi_d0.cwiseAbs().maxCoeff(), pi_b0.cwiseAbs().maxCoeff()), 1.0F)
        << "an output at a bound: zeroing would drop its gradient";
    std::vector<bool> take(4);
    int taken = 0;
    for (int j = 0; j < 4; ++j) {
      take[static_cast<size_t>(j)] = !filter || q_demo(0, j) > q_pi(0, j);
      taken += take[static_cast<size_t>(j)] ? 1 : 0;
    }
    EXPECT_FLOAT_EQ(stats.bc_accepted_fraction, static_cast<float>(taken) / 4.0F);
    if (filter) {
      EXPECT_GT(taken, 0);
      EXPECT_LT(taken, 4) << "pick another seed: the filter should drop some demonstrations";
    }
    auto loss = [&]() {
      const Eigen::MatrixXf pi_b = d.actor().forward(s_b);
      double l = -static_cast<double>(critic_q(s_b, pi_b).sum());
      const Eigen::MatrixXf pi_d = d.actor().forward(s_d);
      for (int j = 0; j < 4; ++j) {
        if (!take[static_cast<size_t>(j)]) {
          continue;
        }
        const bool move = a_d(0, j) > a_d(1, j);
        for (int i = 0; i < (move ? 3 : 2); ++i) {  // scores, and velocity when MOVE
          const double diff = pi_d(i, j) - a_d(i, j);
          l += 0.5 * c.demo_bc_weight * diff * diff;  // every range here is 2: unit scale
        }
      }
      return l;
    };
    const double k = std::sqrt(1.0 - c.adam_beta2);
    int checked = 0;
    for (size_t i = 0; i < before.size(); ++i) {
      const double delta = static_cast<double>(after[i]) - before[i];
      const double g = -delta * c.adam_epsilon / (k * (c.actor_learning_rate - std::abs(delta)));
      const float h = 1e-3F;
      d.actor().params()[i] = before[i] + h;
      const double up = loss();
      d.actor().params()[i] = before[i] - h;
      const double down = loss();
      d.actor().params()[i] = before[i];
      const double fd = (up - down) / (2.0 * h);
      EXPECT_NEAR(g, fd, 2e-3 + 2e-2 * std::abs(fd)) << "actor parameter " << i << (filter ? " (filter)" : "");
      checked += std::abs(fd) > 1e-2 ? 1 : 0;
    }
    EXPECT_GT(checked, 10);
  }
}

TEST(Ddpg, CriticLearnsAFixedTarget) {
  // Terminal transitions with reward r: the critic must regress Q(s, a) onto r.
  toy::ReachStopEnv env;
  DdpgConfig c = tiny_config();
  c.hidden = {32, 32};
  c.actor_learning_rate = 0.0;
  c.init_std = 0.1;
  Ddpg d(3, env.action_space(), c, 7);
  BatchBuffers b(3, 3, 4);
  Rng rng(3);
  for (auto* v : {&b.states, &b.actions, &b.next_states}) {
    for (float& x : *v) {
      x = static_cast<float>(rng.uniform(-1, 1));
    }
  }
  b.rewards = {1.0F, -0.5F, 0.25F, 0.75F};
  b.terminal = {1, 1, 1, 1};
  const float first = d.update(view_of(b, 4)).critic_loss;
  float last = first;
  for (int i = 0; i < 400; ++i) {
    last = d.update(view_of(b, 4)).critic_loss;
  }
  EXPECT_GT(first, 0.05F);
  EXPECT_LT(last, 1e-3F);
}

app::ExperimentConfig toy_config(int64_t max_updates) {
  std::ifstream in(std::string(PAMDP_SOURCE_DIR) + "/deploy/configs/reach_stop.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  app::ExperimentConfig c = app::parse_experiment_config(ss.str(), "reach_stop.toml", {});
  c.train.max_updates = max_updates;
  c.train.log_every_seconds = 1e9;
  return c;
}

fs::path fresh_dir(const std::string& name) {
  // The pid keeps two builds' test runs on one machine out of each other's directories.
  const fs::path d = fs::temp_directory_path() / ("pamdp_learner_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

TEST(Train, SolvesReachStop) {
  const fs::path dir = fresh_dir("solve");
  const app::TrainSummary s = app::train(toy_config(12000), {dir.string(), false, true, nullptr});
  // Learned: the run's best greedy evaluation (best_eval.txt, the rate first) solves the task,
  // where the untrained policy scores 0. The final policy only has to hold most of it: DDPG's
  // last snapshot swings, and with -march=native the rounding differs between CPUs (seed 1
  // ends at 1.000 on AVX-512 machines, at .675 on an AVX2 one after 1.000 at 10,000 updates).
  std::ifstream best_file(dir / "best_eval.txt");
  double best_rate = -1.0;
  best_file >> best_rate;
  EXPECT_GE(best_rate, 0.9) << "DDPG with inverting gradients failed to learn ReachStop";
  EXPECT_GE(s.final_eval.goal_rate, 0.5) << "DDPG's final ReachStop policy lost what it learned";
  EXPECT_TRUE(fs::exists(dir / "config.toml"));
  EXPECT_TRUE(fs::exists(dir / "metrics.csv"));
  EXPECT_TRUE(fs::exists(dir / "episodes.csv"));
  fs::remove_all(dir);
}

std::vector<float> params_of(const std::string& ckpt, const app::ExperimentConfig& c) {
  toy::ReachStopEnv env;
  DdpgAlgorithm d_alg(3, env.action_space(), c.ddpg, 99, UpdateDevice::kCpu);
  Ddpg& d = d_alg.ddpg();
  load_checkpoint(ckpt, d_alg);
  std::vector<float> all(d.actor().params().begin(), d.actor().params().end());
  all.insert(all.end(), d.critic().params().begin(), d.critic().params().end());
  all.insert(all.end(), d.target_critic().params().begin(), d.target_critic().params().end());
  all.insert(all.end(), d.critic_optimizer().second_moment().begin(), d.critic_optimizer().second_moment().end());
  return all;
}

struct EpisodeCsvRow {
  int64_t updates = 0;
  int64_t steps = 0;
  std::string outcome;
  std::string weights_version;
  std::string policy;
};

// The fields of one CSV line of a run directory (no quoting there).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  for (std::string f; std::getline(ss, f, ',');) {
    fields.push_back(f);
  }
  return fields;
}

std::vector<EpisodeCsvRow> episode_rows(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  std::vector<EpisodeCsvRow> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cols = csv_fields(line);
    if (cols.size() == 9) {
      rows.push_back({std::stoll(cols[2]), std::stoll(cols[5]), cols[6], cols[7], cols[8]});
    }
  }
  return rows;
}

// Steps of the episodes in a run's episodes.csv: {played by the scripted offense, by the agent}.
std::pair<int64_t, int64_t> steps_by_policy(const fs::path& dir) {
  std::pair<int64_t, int64_t> steps{0, 0};
  for (const auto& r : episode_rows(dir / "episodes.csv")) {
    (r.policy == "scripted" ? steps.first : steps.second) += r.steps;
  }
  return steps;
}

app::ExperimentConfig hfo_demo_config(double demo_fraction, int64_t episodes) {
  app::ExperimentConfig c =
      app::load_experiment_config(std::string(PAMDP_SOURCE_DIR) + "/deploy/configs/fast.toml",
                                  {"train.max_updates=100000000", "train.eval_every_updates=0", "train.eval_episodes=0",
                                   "train.confirm_episodes=0", "train.log_every_seconds=1000000000"});
  c.train.max_episodes = episodes;
  c.exploration.demo_fraction = demo_fraction;
  return c;
}

TEST(Train, DemonstrationsArePlayedByTheScriptedOffense) {
  // All demonstrations: the scripted offense scores ~.998 on the empty goal; every episode is
  // marked policy "scripted" with weights_version 0, also after the updates began.
  const fs::path dir = fresh_dir("demo");
  app::train(hfo_demo_config(1.0, 30), {dir.string(), false, true, nullptr});
  const auto rows = episode_rows(dir / "episodes.csv");
  ASSERT_EQ(rows.size(), 30U);
  EXPECT_GT(rows.back().updates, 0) << "the demonstrations filled the warm-up and fed the updates";
  int goals = 0;
  for (const auto& r : rows) {
    EXPECT_EQ(r.weights_version, "0");
    EXPECT_EQ(r.policy, "scripted");
    goals += r.outcome == "GOAL" ? 1 : 0;
  }
  EXPECT_GE(goals, 27);
  // Every stored action is the scripted offense's, written as an actor output: score 1 for the
  // action it took and -1 for the others, its parameters within their bounds.
  const app::ExperimentConfig demo_config = hfo_demo_config(1.0, 30);
  const hfo::HfoEnv env;
  const ActionSpace& space = env.action_space();
  ReplayBuffer replay(demo_config.replay.capacity, env.observation_size(), space.output_width());
  load_replay_snapshot((dir / "replay.bin").string(), replay);
  ASSERT_GT(replay.size(), 1000);
  const auto raw = replay.raw();
  const int64_t row = 2LL * env.observation_size() + space.output_width() + 3;
  std::vector<int> taken(static_cast<size_t>(space.num_actions()), 0);
  for (int64_t i = 0; i < replay.size(); ++i) {
    const float* a = raw.data() + i * row + env.observation_size();
    int chosen = -1;
    for (int k = 0; k < space.num_actions(); ++k) {
      ASSERT_TRUE(a[k] == 1.0F || a[k] == -1.0F) << "row " << i << " score " << k << " = " << a[k];
      if (a[k] == 1.0F) {
        ASSERT_EQ(chosen, -1) << "row " << i << " has two chosen actions";
        chosen = k;
      }
    }
    ASSERT_NE(chosen, -1) << "row " << i;
    ++taken[static_cast<size_t>(chosen)];
    for (const int p : space.actions[static_cast<size_t>(chosen)].param_indices) {
      const ParamSpec& spec = space.params[static_cast<size_t>(p)];
      const float v = a[space.num_actions() + p];
      EXPECT_TRUE(v >= spec.lo && v <= spec.hi) << "row " << i << " " << spec.name << " = " << v;
    }
  }
  EXPECT_GT(taken[static_cast<size_t>(space.find_action("DASH"))], 0);
  EXPECT_GT(taken[static_cast<size_t>(space.find_action("KICK"))], 0);
  fs::remove_all(dir);

  // None: the fresh actor, random (ε = 1) until the warm-up ends, then ε-greedy, does not score;
  // once updates run, every episode carries the update count.
  const fs::path none = fresh_dir("nodemo");
  app::train(hfo_demo_config(0.0, 30), {none.string(), false, true, nullptr});
  goals = 0;
  int64_t acted = 0;
  const auto agent_rows = episode_rows(none / "episodes.csv");
  ASSERT_EQ(agent_rows.size(), 30U);
  for (const auto& r : agent_rows) {
    EXPECT_EQ(r.policy, "agent");
    goals += r.outcome == "GOAL" ? 1 : 0;
    if (r.updates > 0) {
      ++acted;
      EXPECT_EQ(r.weights_version, std::to_string(r.updates));
    }
  }
  EXPECT_GT(acted, 0);
  EXPECT_LE(goals, 3);
  fs::remove_all(none);
}

TEST(Train, CloningIsLoggedAndItsDemonstrationsSurviveAResume) {
  // ddpg.demo_bc_weight > 0: the demonstrated transitions are kept apart for cloning (and
  // saved with the checkpoint), and metrics.csv says how many the Q-filter let through.
  const fs::path dir = fresh_dir("clone");
  app::ExperimentConfig c = hfo_demo_config(0.5, 20);
  c.ddpg.demo_bc_weight = 1.0;
  app::train(c, {dir.string(), false, true, nullptr});
  ASSERT_TRUE(fs::exists(dir / "demo_replay.bin"));
  const hfo::HfoEnv env;
  const int width = env.action_space().output_width();
  // Every step of the episodes marked "scripted" is a demonstration kept, and nothing else.
  auto expect_every_demonstrated_step = [&](const char* when) {
    ReplayBuffer demos(c.replay.capacity, env.observation_size(), width);
    load_replay_snapshot((dir / "demo_replay.bin").string(), demos);
    const auto [demonstrated, agent] = steps_by_policy(dir);
    EXPECT_GT(demonstrated, 0);
    EXPECT_GT(agent, 0);
    EXPECT_EQ(demos.size(), demonstrated) << when;
  };
  expect_every_demonstrated_step("after the first run");

  std::ifstream metrics(dir / "metrics.csv");
  std::string header;
  std::string line;
  std::string last;
  std::getline(metrics, header);
  while (std::getline(metrics, line)) {
    last = line;
  }
  ASSERT_NE(header.find(",bc_accepted_fraction,bc_loss"), std::string::npos) << header;
  const std::string accepted = last.substr(0, last.rfind(','));
  const double fraction = std::stod(accepted.substr(accepted.rfind(',') + 1));
  EXPECT_GE(fraction, 0.0);
  EXPECT_LE(fraction, 1.0);

  c.train.max_episodes = 30;
  app::train(c, {dir.string(), true, true, nullptr});
  expect_every_demonstrated_step("after the resume: the demonstrations before it were kept");
  fs::remove_all(dir);
}

TEST(Train, RelabellingPutsTheAgentsStatesWithTheScriptedActionsIntoTheCloningMemory) {
  // exploration.demo_relabel: every step of every episode, the agent's too, is in the cloning
  // memory, and every stored action there is what the scripted offense does in that state (the
  // agent's own actions, random ones included, are in the main memory only).
  const fs::path dir = fresh_dir("relabel");
  app::ExperimentConfig c = hfo_demo_config(0.5, 20);
  c.ddpg.demo_bc_weight = 1.0;
  c.exploration.demo_relabel = true;
  app::train(c, {dir.string(), false, true, nullptr});
  const auto [demonstrated, agent] = steps_by_policy(dir);
  ASSERT_GT(demonstrated, 0);
  ASSERT_GT(agent, 0);
  const hfo::HfoEnv env;
  const ActionSpace& space = env.action_space();
  const int obs = env.observation_size();
  const int width = space.output_width();
  ReplayBuffer labels(c.replay.capacity, obs, width);
  load_replay_snapshot((dir / "demo_replay.bin").string(), labels);
  ASSERT_EQ(labels.size(), demonstrated + agent);
  ReplayBuffer replay(c.replay.capacity, obs, width);
  load_replay_snapshot((dir / "replay.bin").string(), replay);
  ASSERT_EQ(replay.size(), labels.size());

  hfo::ScriptedOffense teacher;
  const int64_t row = 2LL * obs + width + 3;
  int64_t differs = 0;  // rows where the agent's action is not its teacher's
  for (int64_t i = 0; i < labels.size(); ++i) {
    const float* l = labels.raw().data() + i * row;
    const float* r = replay.raw().data() + i * row;
    ASSERT_TRUE(std::equal(l, l + obs, r)) << "row " << i << ": the same states in the same order";
    const ParamAction a = teacher.act(std::span<const float>(l, static_cast<size_t>(obs)));
    for (int k = 0; k < space.num_actions(); ++k) {
      ASSERT_EQ(l[obs + k], k == a.id ? 1.0F : -1.0F) << "row " << i << " score " << k;
    }
    for (const int p : space.actions[static_cast<size_t>(a.id)].param_indices) {
      ASSERT_EQ(l[obs + space.num_actions() + p], a.params[static_cast<size_t>(p)]) << "row " << i << " param " << p;
    }
    differs += std::equal(l + obs, l + obs + width, r + obs) ? 0 : 1;
  }
  EXPECT_GT(differs, agent / 2) << "the agent's own actions stayed in the main memory";
  fs::remove_all(dir);
}

TEST(Train, WithTheShootActionTheTeachersShotsAreClonedAsShoot) {
  // env.shoot_action: the network has a second kick, SHOOT, and the scripted offense's full-power
  // shots are stored as SHOOT with their power and direction in SHOOT's own slots. On the empty
  // goal every kick of the offense is such a shot, so no demonstrated step is a KICK.
  const fs::path dir = fresh_dir("shoot");
  app::ExperimentConfig c = hfo_demo_config(1.0, 20);
  c.env.params.set("shoot_action", true);
  c.ddpg.demo_bc_weight = 1.0;
  app::train(c, {dir.string(), false, true, nullptr});
  const hfo::HfoEnv env({}, true);
  const ActionSpace& space = env.action_space();
  ASSERT_EQ(space.num_actions(), 5);
  const int obs = env.observation_size();
  const int width = space.output_width();
  ReplayBuffer demos(c.replay.capacity, obs, width);
  load_replay_snapshot((dir / "demo_replay.bin").string(), demos);
  ASSERT_GT(demos.size(), 0);
  const int64_t row = 2LL * obs + width + 3;
  int64_t shots = 0;
  for (int64_t i = 0; i < demos.size(); ++i) {
    const float* a = demos.raw().data() + i * row + obs;
    ASSERT_EQ(a[hfo::kKick], -1.0F) << "row " << i << ": a shot stored as KICK";
    if (a[hfo::kShoot] == 1.0F) {
      ++shots;
      EXPECT_EQ(a[space.num_actions() + hfo::param::kShootPower], 100.0F) << "row " << i;
    }
  }
  EXPECT_GE(shots, 20);  // one shot or more in each of the 20 episodes
  fs::remove_all(dir);
}

// The episodes a run finished before its updates reached `updates` (from its episodes.csv): a
// train.max_episodes that stops a run at an episode end just before that point.
int64_t episodes_before(const fs::path& dir, int64_t updates) {
  int64_t n = 0;
  for (const EpisodeCsvRow& r : episode_rows(dir / "episodes.csv")) {
    n += r.updates < updates ? 1 : 0;
  }
  return n;
}

// Stopped by train.max_episodes (as a long run is extended: --set train.max_episodes=N) and
// resumed, a run ends where one that never stopped does. train.max_updates is exact: both stop
// at 3,000 updates, not at the end of the episode past it.
TEST(Train, ResumeIsBitForBit) {
  const fs::path a = fresh_dir("straight");
  const fs::path b = fresh_dir("halves");
  const app::ExperimentConfig full = toy_config(3000);
  const app::TrainSummary straight_summary = app::train(full, {a.string(), false, true, nullptr});
  EXPECT_EQ(straight_summary.updates, 3000);
  app::ExperimentConfig half = full;
  half.train.max_episodes = episodes_before(a, 1950);
  const app::TrainSummary first = app::train(half, {b.string(), false, true, nullptr});
  ASSERT_LT(first.updates, 2000) << "the first half must stop before the evaluation at 2,000 updates";
  const app::TrainSummary second = app::train(full, {b.string(), true, true, nullptr});
  EXPECT_EQ(second.updates, 3000);
  EXPECT_EQ(read_file_bytes((a / "replay.bin").string()), read_file_bytes((b / "replay.bin").string()));
  EXPECT_EQ(params_of((a / "checkpoint.ckpt").string(), full), params_of((b / "checkpoint.ckpt").string(), full));
  // The last-100 training rates go on across the resume: the rows both runs wrote at the same
  // update (the evaluation after the resume, the end) average the same episodes. Returns read
  // back from episodes.csv carry its 6 digits.
  const auto rows_by_updates = [](const fs::path& dir) {
    std::ifstream in(dir / "metrics.csv");
    std::map<std::string, std::vector<std::string>> rows;
    for (std::string line; std::getline(in, line);) {
      std::vector<std::string> fields = csv_fields(line);
      if (fields.size() > 7) {
        rows[fields[1]] = std::move(fields);
      }
    }
    return rows;
  };
  const auto straight = rows_by_updates(a);
  const auto halves = rows_by_updates(b);
  int compared = 0;
  for (const auto& [updates, row] : halves) {
    const auto it = straight.find(updates);
    if (updates == "updates" || it == straight.end() || std::stoll(updates) <= first.updates) {
      continue;
    }
    ++compared;
    EXPECT_EQ(row[5], it->second[5]) << "success_rate_100 at " << updates;
    EXPECT_EQ(row[7], it->second[7]) << "mean_steps_100 at " << updates;
    EXPECT_NEAR(std::stod(row[6]), std::stod(it->second[6]), 1e-4) << "mean_return_100 at " << updates;
  }
  EXPECT_GE(compared, 2);  // the evaluation at 2,000 updates and the end
  fs::remove_all(a);
  fs::remove_all(b);
}

// A team game (HFO 2v0, env.offense_agents = 2, with demonstrations by the scripted team) stopped
// between episodes and resumed ends where a run that never stopped does: both players' transitions
// in replay, the teachers' draws and the weights alike. The bodies start each episode at 0
// (env.body_at_reset = "zero"): with the presets' "carry" an episode starts from the bodies the
// last one left, which a checkpoint does not keep, so a resumed HFO run, one player or several,
// takes another path from its first episode on.
TEST(Train, ATeamResumesBitForBit) {
  const fs::path a = fresh_dir("team_straight");
  const fs::path b = fresh_dir("team_halves");
  std::ifstream in(std::string(PAMDP_SOURCE_DIR) + "/deploy/configs/hfo-2v0-mpdqn.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  app::ExperimentConfig full =
      app::parse_experiment_config(ss.str(), "hfo-2v0-mpdqn.toml",
                                   {"ddpg.hidden=[16, 16]", "replay.warmup=200", "replay.capacity=20000",
                                    "train.max_updates=1500", "train.eval_every_updates=1000", "train.eval_episodes=5",
                                    "train.confirm_episodes=0", "exploration.demo_fraction=0.3", "env.max_steps=120",
                                    "train.log_every_seconds=1e9", "env.body_at_reset=\"zero\""});
  const app::TrainSummary straight = app::train(full, {a.string(), false, true, nullptr});
  EXPECT_EQ(straight.updates, 1500);
  EXPECT_EQ(straight.env_steps % 2, 0) << "a cycle of the game is a decision of each player";
  app::ExperimentConfig half = full;
  half.train.max_episodes = episodes_before(a, 700);
  ASSERT_GT(half.train.max_episodes, 0);
  const app::TrainSummary first = app::train(half, {b.string(), false, true, nullptr});
  ASSERT_LT(first.updates, 1000);
  const app::TrainSummary second = app::train(full, {b.string(), true, true, nullptr});
  EXPECT_EQ(second.updates, 1500);
  EXPECT_EQ(second.env_steps, straight.env_steps);
  // The replay memory holds every action the acting network chose, so it matches only if the
  // weights did all along; the final evaluation plays the last weights.
  EXPECT_EQ(read_file_bytes((a / "replay.bin").string()), read_file_bytes((b / "replay.bin").string()));
  EXPECT_EQ(second.final_eval.avg_return, straight.final_eval.avg_return);
  EXPECT_EQ(second.final_eval.avg_steps, straight.final_eval.avg_steps);
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST(Checkpoint, CorruptOrMismatchedIsRefused) {
  const fs::path dir = fresh_dir("corrupt");
  fs::create_directories(dir);
  const std::string path = (dir / "c.ckpt").string();
  toy::ReachStopEnv env;
  DdpgAlgorithm d_alg(3, env.action_space(), tiny_config(), 1, UpdateDevice::kCpu);
  save_checkpoint(path, d_alg, {});
  EXPECT_NO_THROW(load_checkpoint(path, d_alg));
  EXPECT_FALSE(fs::exists(path + ".tmp"));

  std::vector<uint8_t> bytes = read_file_bytes(path);
  const std::vector<uint8_t> good = bytes;
  bytes.resize(bytes.size() / 2);
  write_file_atomically(path, bytes.data(), bytes.size());
  EXPECT_THROW(load_checkpoint(path, d_alg), std::runtime_error);

  bytes = good;
  bytes[4] = 'X';  // file identifier
  write_file_atomically(path, bytes.data(), bytes.size());
  EXPECT_THROW(load_checkpoint(path, d_alg), std::runtime_error);

  write_file_atomically(path, good.data(), good.size());
  DdpgConfig wider = tiny_config();
  wider.hidden = {9};
  DdpgAlgorithm other_alg(3, env.action_space(), wider, 1, UpdateDevice::kCpu);
  try {
    load_checkpoint(path, other_alg);
    FAIL() << "mismatched checkpoint accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("widths"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_checkpoint((dir / "missing.ckpt").string(), d_alg), std::runtime_error);
  fs::remove_all(dir);
}

// A warm start into a run with more observations: the checkpoint's first features map one to one,
// the extra ones get zero weights, so every network computes what the checkpoint's did whatever
// the extra features hold (actor: state; critic: state, then the action after it). Equal up to
// float rounding: the GEMM sums a longer row in another order.
TEST(Checkpoint, WarmStartWidensTheInputsExactly) {
  const fs::path dir = fresh_dir("warm");
  fs::create_directories(dir);
  const std::string path = (dir / "w.ckpt").string();
  toy::ReachStopEnv env;
  const ActionSpace& space = env.action_space();
  DdpgAlgorithm from_alg(3, space, tiny_config(), 1, UpdateDevice::kCpu);
  Ddpg& from = from_alg.ddpg();
  Rng rng(5);
  for (Mlp<float>* net : {&from.actor(), &from.critic(), &from.target_actor(), &from.target_critic()}) {
    net->init_gaussian(rng, 0.5F);  // targets differ from the online networks
  }
  save_checkpoint(path, from_alg, {});
  DdpgAlgorithm to_alg(5, space, tiny_config(), 2, UpdateDevice::kCpu);
  Ddpg& to = to_alg.ddpg();
  warm_start_from_checkpoint(path, to_alg);

  const int act = from.output_width();
  Eigen::MatrixXf wide = Eigen::MatrixXf::Random(5 + act, 4);
  Eigen::MatrixXf narrow(3 + act, 4);
  narrow << wide.topRows(3), wide.bottomRows(act);
  const std::pair<Mlp<float>*, Mlp<float>*> pairs[] = {{&from.actor(), &to.actor()},
                                                       {&from.target_actor(), &to.target_actor()}};
  for (const auto& [a, b] : pairs) {
    const Eigen::MatrixXf expected = a->forward(narrow.topRows(3));
    EXPECT_TRUE(Eigen::MatrixXf(b->forward(wide.topRows(5))).isApprox(expected, 1e-6F));
  }
  const std::pair<Mlp<float>*, Mlp<float>*> critics[] = {{&from.critic(), &to.critic()},
                                                         {&from.target_critic(), &to.target_critic()}};
  for (const auto& [a, b] : critics) {
    const Eigen::MatrixXf expected = a->forward(narrow);
    EXPECT_TRUE(Eigen::MatrixXf(b->forward(wide)).isApprox(expected, 1e-6F));
  }
  EXPECT_NE(Eigen::MatrixXf(to.actor().forward(wide.topRows(5))),
            Eigen::MatrixXf(to.target_actor().forward(wide.topRows(5))));
  EXPECT_EQ(to.updates(), 0);

  // Other hidden widths, or fewer observations than the checkpoint's, are refused with the reason.
  DdpgConfig wider = tiny_config();
  wider.hidden = {9};
  DdpgAlgorithm other_alg(5, space, wider, 1, UpdateDevice::kCpu);
  DdpgAlgorithm fewer_alg(2, space, tiny_config(), 1, UpdateDevice::kCpu);
  for (DdpgAlgorithm* d : {&other_alg, &fewer_alg}) {
    try {
      warm_start_from_checkpoint(path, *d);
      FAIL() << "a warm start into other shapes was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("train.init_from"), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

// The actor average is in the checkpoint with the update it last absorbed; a file without one
// (tau was 0, or an older build) and a warm start begin it at the loaded actor.
TEST(Checkpoint, ActorAverageRoundTrips) {
  const fs::path dir = fresh_dir("average");
  fs::create_directories(dir);
  const std::string path = (dir / "a.ckpt").string();
  toy::ReachStopEnv env;
  DdpgConfig c = tiny_config();
  c.actor_average_tau = 0.01;
  DdpgAlgorithm from_alg(3, env.action_space(), c, 1, UpdateDevice::kCpu);
  Ddpg& from = from_alg.ddpg();
  Rng rng(7);
  from.actor_average().init_gaussian(rng, 0.5F);
  from.set_updates(9);
  from.set_actor_average_updates(7);
  save_checkpoint(path, from_alg, {});
  DdpgAlgorithm back_alg(3, env.action_space(), c, 2, UpdateDevice::kCpu);
  Ddpg& back = back_alg.ddpg();
  load_checkpoint(path, back_alg);
  EXPECT_TRUE(std::equal(from.actor_average().params().begin(), from.actor_average().params().end(),
                         back.actor_average().params().begin()));
  EXPECT_EQ(back.actor_average_updates(), 7);
  EXPECT_EQ(back.updates(), 9);

  DdpgConfig off = tiny_config();
  DdpgAlgorithm plain_alg(3, env.action_space(), off, 3, UpdateDevice::kCpu);
  Ddpg& plain = plain_alg.ddpg();
  plain.set_updates(5);
  save_checkpoint(path, plain_alg, {});
  load_checkpoint(path, back_alg);
  EXPECT_TRUE(
      std::equal(plain.actor().params().begin(), plain.actor().params().end(), back.actor_average().params().begin()));
  EXPECT_EQ(back.actor_average_updates(), 5);

  save_checkpoint(path, from_alg, {});
  DdpgAlgorithm warm_alg(3, env.action_space(), c, 4, UpdateDevice::kCpu);
  Ddpg& warm = warm_alg.ddpg();
  warm_start_from_checkpoint(path, warm_alg);
  EXPECT_TRUE(
      std::equal(from.actor().params().begin(), from.actor().params().end(), warm.actor_average().params().begin()));
  EXPECT_EQ(warm.actor_average_updates(), 0);
  fs::remove_all(dir);
}

// A run with an actor average: stopped and resumed, it keeps the same average as a run that never
// stopped, and that average has moved away from where it began (the evaluations played it).
TEST(Train, ActorAverageSurvivesAResume) {
  const fs::path a = fresh_dir("avg_straight");
  const fs::path b = fresh_dir("avg_halves");
  auto config = [](int64_t updates) {
    app::ExperimentConfig c = toy_config(updates);
    c.ddpg.actor_average_tau = 1e-3;
    return c;
  };
  app::train(config(3000), {a.string(), false, true, nullptr});
  app::ExperimentConfig half = config(3000);
  half.train.max_episodes = episodes_before(a, 1950);
  app::train(half, {b.string(), false, true, nullptr});
  app::train(config(3000), {b.string(), true, true, nullptr});
  const auto average_of = [](const fs::path& ckpt, const app::ExperimentConfig& c) {
    toy::ReachStopEnv env;
    DdpgAlgorithm d_alg(3, env.action_space(), c.ddpg, 99, UpdateDevice::kCpu);
    Ddpg& d = d_alg.ddpg();
    load_checkpoint(ckpt.string(), d_alg);
    EXPECT_EQ(d.actor_average_updates(), d.updates());
    return std::vector<float>(d.actor_average().params().begin(), d.actor_average().params().end());
  };
  const std::vector<float> straight = average_of(a / "checkpoint.ckpt", config(3000));
  EXPECT_EQ(straight, average_of(b / "checkpoint.ckpt", config(3000)));
  toy::ReachStopEnv env;
  Ddpg start(3, env.action_space(), config(3000).ddpg, mix_seeds(config(3000).seed, 1));  // the trainer's
  EXPECT_NE(straight, std::vector<float>(start.actor().params().begin(), start.actor().params().end()));
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST(Config, DefaultsRoundTripAndOverrides) {
  const app::ExperimentConfig def = app::parse_experiment_config("", "empty", {});
  EXPECT_EQ(def.ddpg.hidden, (std::vector<int>{1024, 512, 256, 128}));
  const app::ExperimentConfig back = app::parse_experiment_config(app::to_toml(def), "round-trip", {});
  EXPECT_EQ(app::to_toml(back), app::to_toml(def));
  const app::ExperimentConfig o =
      app::parse_experiment_config("", "x", {"ddpg.gamma=0.5", "ddpg.bound=squashing", "env.noise=false", "seed=9"});
  EXPECT_DOUBLE_EQ(o.ddpg.gamma, 0.5);
  EXPECT_EQ(o.ddpg.bound, BoundMethod::kSquashing);
  EXPECT_FALSE(o.env.params.boolean("noise"));
  EXPECT_EQ(o.seed, 9U);
}

// An algorithm's own keys ([pdqn]) come from its registration: read, range-checked, written back,
// and an unknown one in their section is refused naming the valid ones.
TEST(Config, AlgorithmKeysComeFromTheirRegistration) {
  const app::ExperimentConfig o =
      app::parse_experiment_config("[pdqn]\nq_tau = 0.1\n", "x", {"pdqn.passthrough=true", "pdqn.reward_scale=0.02"});
  EXPECT_DOUBLE_EQ(o.algorithm_params.real("pdqn.q_tau"), 0.1);
  EXPECT_TRUE(o.algorithm_params.boolean("pdqn.passthrough"));
  EXPECT_DOUBLE_EQ(o.algorithm_params.real("pdqn.reward_scale"), 0.02);
  const app::ExperimentConfig back = app::parse_experiment_config(app::to_toml(o), "round-trip", {});
  EXPECT_EQ(back.algorithm_params, o.algorithm_params);
  EXPECT_DOUBLE_EQ(app::ExperimentConfig{}.algorithm_params.real("pdqn.reward_scale"), 1.0);
  try {
    app::parse_experiment_config("[pdqn]\nq_taus = 0.1\n", "cfg.toml", {});
    FAIL() << "an unknown [pdqn] key was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("q_tau"), std::string::npos) << e.what();
  }
  try {
    app::parse_experiment_config("", "cfg.toml", {"pdqn.q_tau=2"});
    FAIL() << "pdqn.q_tau = 2 was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pdqn.q_tau"), std::string::npos) << e.what();
  }
}

// The registry refuses a key declared two ways, or one outside a section of its own.
TEST(Config, AlgorithmKeysAreDeclaredOnce) {
  const auto make = [](const AlgorithmArgs&) -> std::unique_ptr<Algorithm> { return nullptr; };
  AlgorithmRegistry r;
  r.add({"a", "", make, {AlgorithmKey::real("s.rate", 0.5, 0.0, 1.0, "")}});
  EXPECT_NO_THROW(r.add({"b", "", make, {AlgorithmKey::real("s.rate", 0.5, 0.0, 1.0, "")}}));
  EXPECT_THROW(r.add({"c", "", make, {AlgorithmKey::real("s.rate", 0.25, 0.0, 1.0, "")}}), std::logic_error);
  EXPECT_THROW(r.add({"d", "", make, {AlgorithmKey::boolean("flag", true, "")}}), std::logic_error);
  EXPECT_THROW(r.add({"e", "", make, {AlgorithmKey::boolean("ddpg.flag", true, "")}}), std::logic_error);
  EXPECT_EQ(r.keys().size(), 1U);
  EXPECT_DOUBLE_EQ(r.defaults().real("s.rate"), 0.5);
  EXPECT_THROW((void)r.defaults().boolean("s.rate"), std::logic_error);
}

TEST(Config, PaperPresetIsTheDefault) {
  const app::ExperimentConfig paper =
      app::load_experiment_config(std::string(PAMDP_SOURCE_DIR) + "/deploy/configs/paper.toml", {});
  EXPECT_EQ(app::to_toml(paper), app::to_toml(app::ExperimentConfig{}));
  EXPECT_NO_THROW(app::load_experiment_config(std::string(PAMDP_SOURCE_DIR) + "/deploy/configs/fast.toml", {}));
}

// Every preset loads, and one named <task>-<learner>.toml (issue 29's convention) trains that
// learner on that task.
TEST(Config, EveryPresetLoadsAndItsNameSaysItsTaskAndLearner) {
  const std::map<std::string, std::string> learners = {{"paddpg", "ddpg"}, {"pdqn", "pdqn"}, {"mpdqn", "mpdqn"}};
  const std::set<std::string> tasks = {"platform", "goal", "hfo"};  // each is its env's name
  int named = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(PAMDP_SOURCE_DIR) + "/deploy/configs")) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().string());
    std::optional<app::ExperimentConfig> loaded;
    try {
      loaded = app::load_experiment_config(entry.path().string(), {});
    } catch (const std::exception& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    const app::ExperimentConfig& c = *loaded;
    const std::string stem = entry.path().stem().string();
    const auto dash = stem.rfind('-');
    if (dash == std::string::npos) continue;
    const auto task = tasks.find(stem.substr(0, dash));
    const auto learner = learners.find(stem.substr(dash + 1));
    if (task == tasks.end() || learner == learners.end()) continue;
    EXPECT_EQ(c.env.name, *task);
    EXPECT_EQ(c.train.algorithm, learner->second);
    ++named;
  }
  EXPECT_EQ(named, 9);  // three tasks by three learners (hfo-paddpg.toml is fast.toml)
}

void expect_error(const std::string& text, const std::vector<std::string>& sets, const std::string& needle) {
  try {
    app::parse_experiment_config(text, "cfg.toml", sets);
    FAIL() << "accepted: " << text;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Config, ErrorsNameTheKeyAndTheChoices) {
  expect_error("[ddpg]\ngama = 0.9\n", {}, "unknown key 'ddpg.gama'");
  expect_error("[ddpg]\ngama = 0.9\n", {}, "gamma");  // lists the valid keys
  expect_error("[dpg]\n", {}, "valid: ");
  expect_error("[ddpg]\ngamma = 1.5\n", {}, "'ddpg.gamma' must be within [0, 1]");
  expect_error("[ddpg]\nbound = 'clip'\n", {}, "inverting, zeroing, squashing");
  expect_error("[ddpg]\nbatch_size = 'big'\n", {}, "'ddpg.batch_size' must be an integer");
  expect_error("[ddpg\n", {}, "not valid TOML");
  expect_error("", {"ddpg.gamma"}, "expected key=value");
  expect_error("[replay]\nwarmup = 10\n", {}, "replay.warmup must be at least ddpg.batch_size");
  expect_error("[env]\nname = 'reach_stop'\n[exploration]\ndemo_fraction = 0.5\n", {},
               "exploration.demo_fraction > 0 needs the scripted offense");
  expect_error("[ddpg]\ndemo_bc_weight = 1.0\n", {},
               "ddpg.demo_bc_weight > 0 clones demonstrations, and there are none");
  expect_error("[ddpg]\ndemo_bc_weight = -1.0\n", {}, "'ddpg.demo_bc_weight' must be within");
  expect_error("[exploration]\ndemo_fraction = 0.5\ndemo_relabel = true\n", {},
               "exploration.demo_relabel = true labels the agent's steps for cloning, and nothing clones");
  expect_error("[exploration]\ndemo_shot = 'corner'\n", {}, "best-course, bottom-post");
  expect_error("[exploration]\ndemo_shot = 'bottom-post'\n", {},
               "exploration.demo_shot aims the scripted offense's shots, and it plays no episodes");
  expect_error("[exploration]\ndemo_fraction = 0.1\ndemo_anneal_updates = 100\ndemo_fraction_end = 0.2\n", {},
               "exploration.demo_fraction_end is the share the teacher's episodes fall to, and it is above");
  expect_error("[exploration]\ndemo_fraction = 0.5\ndemo_fraction_end = 0.1\n", {},
               "exploration.demo_anneal_updates = 0 keeps demo_fraction throughout");
}

TEST(Config, UpdateDevice) {
  EXPECT_EQ(app::parse_experiment_config("", "empty", {}).ddpg.device, UpdateDevice::kAuto);
  EXPECT_EQ(app::parse_experiment_config("[ddpg]\ndevice = 'cpu'\n", "x", {}).ddpg.device, UpdateDevice::kCpu);
  EXPECT_EQ(app::parse_experiment_config("[ddpg]\ndevice = 'cuda'\n", "x", {}).ddpg.device, UpdateDevice::kCuda);
  const app::ExperimentConfig o = app::parse_experiment_config("", "x", {"ddpg.device=cuda"});
  EXPECT_EQ(o.ddpg.device, UpdateDevice::kCuda);
  EXPECT_NE(app::to_toml(o).find("device = 'cuda'"), std::string::npos) << app::to_toml(o);
  EXPECT_EQ(app::parse_experiment_config(app::to_toml(o), "round-trip", {}).ddpg.device, UpdateDevice::kCuda);
  expect_error("[ddpg]\ndevice = 'gpu'\n", {}, "'ddpg.device' must be one of: auto, cpu, cuda");
  expect_error("", {"ddpg.device=tpu"}, "auto, cpu, cuda");
}

TEST(UpdateBackend, CpuIsDdpgUpdate) {
  toy::ReachStopEnv env;
  Ddpg a(3, env.action_space(), tiny_config(), 5);
  Ddpg b(3, env.action_space(), tiny_config(), 5);
  const auto backend = make_update_backend(b, UpdateDevice::kCpu);
  EXPECT_STREQ(backend->name(), "cpu");
  BatchBuffers batch(3, 3, 4);
  Rng rng(2);
  for (auto* v : {&batch.states, &batch.actions, &batch.next_states}) {
    for (float& x : *v) {
      x = static_cast<float>(rng.uniform(-1, 1));
    }
  }
  batch.rewards = {1, 0, -1, 0.5F};
  batch.terminal = {0, 1, 0, 0};
  for (int i = 0; i < 3; ++i) {
    const UpdateStats sa = a.update(view_of(batch, 4));
    const UpdateStats sb = backend->update(view_of(batch, 4));
    EXPECT_EQ(sa.critic_loss, sb.critic_loss);
  }
  backend->sync_to_host();
  EXPECT_EQ(b.updates(), 3);
  EXPECT_TRUE(std::equal(a.actor().params().begin(), a.actor().params().end(), b.actor().params().begin()));
  EXPECT_TRUE(std::equal(a.critic().params().begin(), a.critic().params().end(), b.critic().params().begin()));
}

// Without a GPU (this machine, CI): "cuda" is refused in one line that names the fix, and "auto"
// falls back to the CPU. With a GPU these are covered by tests/cuda_learner_test.cpp instead.
TEST(UpdateBackend, CloningRunsOnTheCpu) {
  toy::ReachStopEnv env;
  DdpgConfig c = tiny_config();
  c.demo_bc_weight = 1.0;
  Ddpg d(3, env.action_space(), c, 5);
  EXPECT_STREQ(make_update_backend(d, UpdateDevice::kAuto)->name(), "cpu");
  try {
    make_update_backend(d, UpdateDevice::kCuda);
    FAIL() << "ddpg.device = cuda accepted with ddpg.demo_bc_weight > 0";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("ddpg.demo_bc_weight > 0 runs on the CPU only"), std::string::npos)
        << e.what();
  }
}

TEST(UpdateBackend, CudaWithoutADeviceIsAClearError) {
  std::string why;
  if (cuda_device_count(&why) > 0) {
    GTEST_SKIP() << "a CUDA device is present: the no-device error cannot be provoked here";
  }
  EXPECT_FALSE(why.empty());
  toy::ReachStopEnv env;
  DdpgAlgorithm d_alg(3, env.action_space(), tiny_config(), 5, UpdateDevice::kCpu);
  Ddpg& d = d_alg.ddpg();
  try {
    make_update_backend(d, UpdateDevice::kCuda);
    FAIL() << "ddpg.device = cuda accepted without a device";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("ddpg.device = \"cuda\" but no CUDA device is usable"), std::string::npos) << msg;
    EXPECT_NE(msg.find("use ddpg.device = \"cpu\" or \"auto\""), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
  EXPECT_STREQ(make_update_backend(d, UpdateDevice::kAuto)->name(), "cpu");
}

}  // namespace
}  // namespace pamdp
