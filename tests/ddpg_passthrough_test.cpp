// PA-DDPG's pass-through layer and reward scale (ddpg.passthrough, ddpg.actor_output_init_std,
// ddpg.reward_scale; learner/ddpg.hpp): the actor starts at the env's hand-made parameter policy,
// the layer stays fixed, the actor step's gradient through it matches finite differences under
// each bound, the actors play exactly what the learner acts, the layer is checkpointed, the
// scale enters the critic's target, and each misuse is refused naming its key.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "actor/acting_policy.hpp"
#include "app/experiment_config.hpp"
#include "core/rng.hpp"
#include "learner/ddpg.hpp"
#include "learner/ddpg_algorithm.hpp"
#include "learner/pdqn.hpp"
#include "learner/update_backend.hpp"
#include "three_actions.hpp"

namespace pamdp {
namespace {

using testing::Batch;
using testing::kB;
using testing::kObs;
using testing::random_prior;
using testing::test_space;

constexpr int kWidth = 6;

// testing::small with the layer and no gradient clipping.
DdpgConfig small(BoundMethod bound) {
  DdpgConfig c = testing::small(bound);
  c.clip_grad_norm = 0.0;
  c.passthrough = true;
  return c;
}

std::vector<float> copy_of(std::span<const float> s) {
  return {s.begin(), s.end()};
}

TEST(DdpgPassthrough, StartsAtThePriorStaysFixedAndTheActorsPlayIt) {
  const ActionSpace space = test_space();
  const ParameterPrior prior = random_prior(4);
  for (const BoundMethod bound : {BoundMethod::kInverting, BoundMethod::kSquashing}) {
    DdpgConfig c = small(bound);
    c.actor_output_init_std = 1e-6;  // the actor's own output starts near zero
    DdpgAlgorithm algo(kObs, space, c, 5, UpdateDevice::kCpu, &prior);
    Ddpg& d = algo.ddpg();
    const Eigen::Vector3f s(0.3F, -0.6F, 0.9F);
    std::vector<float> out(kWidth);
    d.act({s.data(), kObs}, out);
    if (bound == BoundMethod::kInverting) {
      for (int p = 0; p < 3; ++p) {
        float want = prior.bias[static_cast<size_t>(p)];
        for (int j = 0; j < kObs; ++j) {
          want += prior.weights[static_cast<size_t>(p * kObs + j)] * s(j);
        }
        EXPECT_NEAR(out[static_cast<size_t>(3 + p)], want, 1e-4) << "parameter " << p;
      }
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(out[static_cast<size_t>(k)], 0.0F, 1e-4) << "score " << k << " takes no prior";
      }
    }
    const std::vector<float> layer = copy_of(d.passthrough().params());
    const Batch b;
    for (int i = 0; i < 5; ++i) {
      algo.update(b.view());
    }
    EXPECT_EQ(layer, copy_of(d.passthrough().params()));

    // The actors get the layer and play what the learner acts, bit for bit.
    const ActingWeights w = algo.acting_weights();
    ASSERT_EQ(w.networks.size(), 2U);
    EXPECT_EQ(w.networks[1].name, "actor_passthrough");
    const std::unique_ptr<ActingPolicy> policy = acting_policy_registry().find(w.algorithm)->make(kObs, space);
    ASSERT_EQ(policy->check(w.networks, w.bound), nullptr);
    policy->load(w.networks, w.bound);
    std::vector<float> theirs(kWidth);
    policy->act({s.data(), kObs}, theirs);
    d.act({s.data(), kObs}, out);
    EXPECT_EQ(out, theirs);
    // Without the layer they would play something else: it is not a no-op here.
    policy->load({w.networks.data(), 1}, w.bound);
    policy->act({s.data(), kObs}, theirs);
    EXPECT_NE(out, theirs);
    // A layer of the wrong width is refused.
    std::vector<NetworkView> wrong = w.networks;
    const std::vector<int> widths{kObs + 1, 3};
    wrong[1].widths = widths;
    EXPECT_NE(policy->check(wrong, w.bound), nullptr);

    // The layer is part of the checkpointed state.
    bool saved = false;
    for (const StateTensor& t : algo.state_tensors()) {
      saved = saved || (t.name == "actor_passthrough" && copy_of(t.values) == layer);
    }
    EXPECT_TRUE(saved);
  }
}

// The actor step's loss is -sum_j Q(s_j, mu(s_j)) with mu(s) = [bound](actor(s) + W s + b): its
// gradient in the actor's parameters (left in actor().grads() by the update) against central
// differences of that loss through act(), which adds the layer and squashes as the actors do.
TEST(DdpgPassthrough, ActorGradientMatchesFiniteDifferences) {
  ActionSpace space = test_space();  // zeroing: the identity while no output is at a bound
  for (ParamSpec& p : space.params) {
    p.lo = -10.0F;
    p.hi = 10.0F;
  }
  const ParameterPrior prior = random_prior(8);
  for (const BoundMethod bound : {BoundMethod::kZeroing, BoundMethod::kSquashing}) {
    DdpgConfig c = small(bound);
    c.actor_output_init_std = 0.1;  // scores well inside their [-1, 1], where zeroing is the identity
    Ddpg d(kObs, space, c, 3, &prior);
    const Batch b;
    const std::vector<float> before = copy_of(d.actor().params());
    d.update(b.view());
    const std::vector<float> grads = copy_of(d.actor().grads());
    // The gradient was taken before the actor's Adam step, through the critic as updated.
    std::copy(before.begin(), before.end(), d.actor().params().begin());
    for (int j = 0; j < kB; ++j) {
      std::vector<float> a(kWidth);
      d.act({b.states.col(j).data(), kObs}, a);
      for (int i = 0; i < kWidth; ++i) {
        ASSERT_GT(a[static_cast<size_t>(i)], d.bounds().lo[static_cast<size_t>(i)]) << "an output at a bound";
        ASSERT_LT(a[static_cast<size_t>(i)], d.bounds().hi[static_cast<size_t>(i)]) << "an output at a bound";
      }
    }
    auto loss = [&]() {
      double l = 0.0;
      std::vector<float> a(kWidth);
      Eigen::MatrixXf in(kObs + kWidth, 1);
      for (int j = 0; j < kB; ++j) {
        d.act({b.states.col(j).data(), kObs}, a);
        in.col(0).head(kObs) = b.states.col(j);
        in.col(0).tail(kWidth) = Eigen::Map<const Eigen::VectorXf>(a.data(), kWidth);
        l -= static_cast<double>(d.critic().forward(in)(0, 0));
      }
      return l;
    };
    const float h = 1e-3F;
    int bad = 0;
    int checked = 0;
    for (size_t i = 0; i < grads.size(); ++i) {
      const float keep = d.actor().params()[i];
      d.actor().params()[i] = keep + h;
      const double up = loss();
      d.actor().params()[i] = keep - h;
      const double down = loss();
      d.actor().params()[i] = keep;
      const double fd = (up - down) / (2.0 * h);
      bad += std::abs(grads[i] - fd) > 3e-3 + 3e-2 * std::abs(fd) ? 1 : 0;
      checked += std::abs(fd) > 1e-2 ? 1 : 0;
    }
    EXPECT_LE(bad * 20, static_cast<int>(grads.size())) << "bound " << static_cast<int>(bound);
    EXPECT_GT(checked, 10);
  }
}

TEST(DdpgPassthrough, RewardScaleEntersTheCriticsTarget) {
  const ActionSpace space = test_space();
  Batch b;
  b.terminal.setOnes();  // y = scale * r, by hand
  b.rewards << 1.0F, -2.0F, 0.5F, 50.0F, 0.0F;
  for (const double scale : {1.0, 0.02}) {
    DdpgConfig c = small(BoundMethod::kInverting);
    c.passthrough = false;
    c.reward_scale = scale;
    Ddpg d(kObs, space, c, 1);
    const UpdateStats stats = d.update(b.view());
    EXPECT_NEAR(stats.target_mean, scale * 49.5 / kB, 1e-5) << "scale " << scale;
  }
}

TEST(DdpgPassthrough, MisuseIsRefusedNamingTheKey) {
  const ActionSpace space = test_space();
  auto refused = [](const std::function<void()>& f, const std::string& needle) {
    try {
      f();
      ADD_FAILURE() << "accepted; wanted an error naming " << needle;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  // No hand-made policy, or one of the wrong width.
  refused([&] { Ddpg d(kObs, space, small(BoundMethod::kInverting), 1, nullptr); }, "ddpg.passthrough");
  ParameterPrior narrow = random_prior(1);
  narrow.bias.pop_back();
  refused([&] { Ddpg d(kObs, space, small(BoundMethod::kInverting), 1, &narrow); }, "does not fit");
  DdpgConfig zero = small(BoundMethod::kInverting);
  zero.passthrough = false;
  zero.reward_scale = 0.0;
  refused([&] { Ddpg d(kObs, space, zero, 1); }, "ddpg.reward_scale");
  // An env whose actions have no parameters still trains without the layer, and is refused with it.
  ActionSpace bare;
  bare.actions = {{"left", {}}, {"right", {}}};
  Ddpg plain(kObs, bare, testing::small(BoundMethod::kInverting), 1);
  EXPECT_EQ(plain.output_width(), 2);
  refused([&] { Ddpg d(kObs, bare, small(BoundMethod::kInverting), 1, &narrow); }, "no continuous parameters");
  // The CUDA update has neither setting.
  const ParameterPrior prior = random_prior(2);
  Ddpg d(kObs, space, small(BoundMethod::kInverting), 1, &prior);
  EXPECT_STREQ(make_update_backend(d, UpdateDevice::kAuto)->name(), "cpu");
  refused([&] { make_update_backend(d, UpdateDevice::kCuda); }, "ddpg.passthrough");
  // P-DQN and MP-DQN have their own keys for these, and say so.
  for (const bool multipass : {false, true}) {
    DdpgConfig c = small(BoundMethod::kInverting);
    refused([&] { Pdqn p(kObs, space, c, 1, multipass, {}, {}, &prior); }, "pdqn.passthrough");
    c.passthrough = false;
    c.reward_scale = 0.5;
    refused([&] { Pdqn p(kObs, space, c, 1, multipass, {}, {}, &prior); }, "pdqn.reward_scale");
    c.reward_scale = 1.0;
    c.actor_output_init_std = 0.1;
    refused([&] { Pdqn p(kObs, space, c, 1, multipass, {}, {}, &prior); }, "pdqn.param_output_init_std");
  }
  // The keys parse and round-trip through the config file.
  const app::ExperimentConfig parsed = app::parse_experiment_config(
      "[ddpg]\npassthrough = true\n", "x", {"ddpg.reward_scale=0.02", "ddpg.actor_output_init_std=0.01"});
  EXPECT_TRUE(parsed.ddpg.passthrough);
  EXPECT_DOUBLE_EQ(parsed.ddpg.reward_scale, 0.02);
  EXPECT_DOUBLE_EQ(parsed.ddpg.actor_output_init_std, 0.01);
  const app::ExperimentConfig again = app::parse_experiment_config(app::to_toml(parsed), "y", {});
  EXPECT_TRUE(again.ddpg.passthrough);
  EXPECT_DOUBLE_EQ(again.ddpg.reward_scale, 0.02);
}

}  // namespace
}  // namespace pamdp
