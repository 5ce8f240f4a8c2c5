// P-DQN and MP-DQN (learner/pdqn.hpp): finite-difference checks of both losses' gradients,
// hand-computed losses (the taken action, the masked max, MP-DQN's one-action passes, the indexed
// loss), the zeroed gradients of the actions not taken, each action's parameters on its own Q, the
// actors' acting policy against the learner's own act(), and the toy task learned end to end
// through `pamdp train`, resumed bit for bit.
#include "learner/pdqn.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "actor/acting_policy.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "app/trainer.hpp"
#include "envs/toy/reach_stop.hpp"
#include "learner/checkpoint.hpp"
#include "three_actions.hpp"

namespace pamdp {
namespace {

namespace fs = std::filesystem;

using testing::Batch;
using testing::kB;
using testing::kObs;
using testing::random_prior;
using testing::small;
using testing::test_space;

// Central differences of `loss` in every parameter of `net` against the gradient left in
// net.grads(). Float arithmetic and leaky-ReLU kinks: a coordinate agrees within 3e-3 + 3% of the
// gradient; all but at most one in twenty must.
void expect_gradients(Mlp<float>& net, const std::function<double()>& loss, const char* what) {
  const std::vector<float> grads(net.grads().begin(), net.grads().end());
  const float h = 1e-3F;
  int bad = 0;
  double largest = 0.0;
  for (size_t i = 0; i < grads.size(); ++i) {
    const float keep = net.params()[i];
    net.params()[i] = keep + h;
    const double up = loss();
    net.params()[i] = keep - h;
    const double down = loss();
    net.params()[i] = keep;
    const double fd = (up - down) / (2.0 * h);
    largest = std::max(largest, std::abs(fd));
    if (std::abs(fd - grads[i]) > 3e-3 + 0.03 * std::abs(fd)) {
      ++bad;
    }
  }
  EXPECT_LE(bad, static_cast<int>(grads.size()) / 20) << what << ": " << bad << " of " << grads.size() << " disagree";
  EXPECT_GT(largest, 1e-2) << what << ": the loss does not depend on these parameters";
}

// test_space() with every parameter over [-10, 10], so that zeroing leaves every gradient alone.
ActionSpace wide_space() {
  ActionSpace space = test_space();
  for (ParamSpec& p : space.params) {
    p.lo = -10.0F;
    p.hi = 10.0F;
  }
  return space;
}

class PdqnGradients : public ::testing::TestWithParam<std::tuple<bool, BoundMethod>> {};

TEST_P(PdqnGradients, MatchFiniteDifferences) {
  const auto [multipass, bound] = GetParam();
  const ActionSpace space = wide_space();
  Pdqn pdqn(kObs, space, small(bound), 3, multipass, /*masked_actions=*/{2});
  // Targets unlike the online networks, so the target term is not the online one.
  Rng rng(11);
  pdqn.target_q_net().init_gaussian(rng, 0.5F);
  pdqn.target_param_net().init_gaussian(rng, 0.5F);
  const Batch b;
  const BatchView v = b.view();
  pdqn.gradients(v);
  expect_gradients(
      pdqn.q_net(), [&] { return pdqn.losses(v).q_loss; }, "Q loss");
  // The parameter loss's gradient is only the loss's own where the bound leaves it alone: zeroing
  // inside the bounds, or squashing (the chain rule through tanh).
  pdqn.gradients(v);
  expect_gradients(
      pdqn.param_net(), [&] { return pdqn.losses(v).param_loss; }, "parameter loss");
}

INSTANTIATE_TEST_SUITE_P(Pdqn, PdqnGradients,
                         ::testing::Combine(::testing::Bool(),
                                            ::testing::Values(BoundMethod::kZeroing, BoundMethod::kSquashing)));

// The Q-network's input for transition j by hand: its state and stored parameters, where
// MP-DQN keeps only the taken action's parameters.
Eigen::MatrixXf q_input(const ActionSpace& space, const Batch& b, int j, int taken, bool multipass) {
  Eigen::MatrixXf in(kObs + 3, 1);
  in.col(0).head(kObs) = b.states.col(j);
  in.col(0).tail(3) = b.actions.col(j).tail(3);
  if (multipass) {
    const auto& owned = space.actions[static_cast<size_t>(taken)].param_indices;
    for (int p = 0; p < 3; ++p) {
      if (std::find(owned.begin(), owned.end(), p) == owned.end()) {
        in(kObs + p, 0) = 0.0F;
      }
    }
  }
  return in;
}

// Both losses by hand from the networks' own forward passes: the taken action is the arg-max of
// the stored scores over the unmasked actions (a masked action's high score is passed over), the
// target's max skips the masked action, MP-DQN's Q sees only the taken action's parameters, and
// the parameter loss sums Q over the unmasked actions.
TEST(Pdqn, LossesByHand) {
  for (const bool multipass : {false, true}) {
    const ActionSpace space = test_space();
    Pdqn pdqn(kObs, space, small(BoundMethod::kInverting), 5, multipass, /*masked_actions=*/{1});
    Batch b;
    b.actions.col(0) << 0.2F, 0.9F, 0.1F, 0.5F, -0.5F, 0.25F;  // "two" scores highest but is masked
    const BatchView v = b.view();
    double q_loss = 0.0;
    double param_loss = 0.0;
    std::vector<float> out(6);
    std::vector<float> next(6);
    for (int j = 0; j < kB; ++j) {
      int taken = -1;
      for (const int k : {0, 2}) {
        taken = taken < 0 || b.actions(k, j) > b.actions(taken, j) ? k : taken;
      }
      if (j == 0) {
        ASSERT_EQ(taken, 0);
      }
      const float q = pdqn.q_net().forward(q_input(space, b, j, taken, multipass))(taken, 0);
      pdqn.act({b.next_states.col(j).data(), kObs}, next, ActorCopy::kTarget);
      const float best = std::max(next[0], next[2]);
      const float y = b.rewards(j) + (b.terminal(j) > 0.5F ? 0.0F : 0.9F * best);
      q_loss += 0.5 * (q - y) * (q - y) / kB;
      pdqn.act({b.states.col(j).data(), kObs}, out, ActorCopy::kOnline);
      param_loss -= (out[0] + out[2]) / kB;
    }
    const Pdqn::Losses l = pdqn.losses(v);
    EXPECT_NEAR(l.q_loss, q_loss, 1e-5 * (1.0 + q_loss)) << (multipass ? "mpdqn" : "pdqn");
    EXPECT_NEAR(l.param_loss, param_loss, 1e-5 * (1.0 + std::abs(param_loss))) << (multipass ? "mpdqn" : "pdqn");
  }
}

// pdqn.indexed_loss: the parameter loss takes each sample's taken action alone (the arg-max of
// its stored scores over the unmasked actions), by hand from the learner's own act(), and its
// gradient against finite differences.
TEST(Pdqn, IndexedLossByHandAndFiniteDifferences) {
  for (const bool multipass : {false, true}) {
    const ActionSpace space = wide_space();
    PdqnSettings settings;
    settings.indexed_loss = true;
    Pdqn pdqn(kObs, space, small(BoundMethod::kZeroing), 5, multipass, /*masked_actions=*/{1}, settings);
    Batch b;
    b.actions.col(0) << 0.2F, 0.9F, 0.1F, 0.5F, -0.5F, 0.25F;  // "two" scores highest but is masked
    const BatchView v = b.view();
    double param_loss = 0.0;
    std::vector<float> out(6);
    int took_two = 0;
    for (int j = 0; j < kB; ++j) {
      const int taken = b.actions(0, j) >= b.actions(2, j) ? 0 : 2;
      took_two += taken == 2 ? 1 : 0;
      pdqn.act({b.states.col(j).data(), kObs}, out, ActorCopy::kOnline);
      param_loss -= out[static_cast<size_t>(taken)] / kB;
    }
    ASSERT_GT(took_two, 0);
    ASSERT_LT(took_two, kB);
    const Pdqn::Losses l = pdqn.losses(v);
    EXPECT_NEAR(l.param_loss, param_loss, 1e-5 * (1.0 + std::abs(param_loss))) << (multipass ? "mpdqn" : "pdqn");
    pdqn.gradients(v);
    expect_gradients(
        pdqn.param_net(), [&] { return pdqn.losses(v).param_loss; }, "indexed parameter loss");
  }
}

// The gradient left on the parameter network's output row p (its weights and bias).
std::vector<float> output_row_grads(Mlp<float>& net, int p) {
  const int last = static_cast<int>(net.widths().size()) - 2;
  auto w = net.weight(last);
  auto bias = net.bias(last);
  const auto at = [&](const float* x) { return net.grads()[static_cast<size_t>(x - net.params().data())]; };
  std::vector<float> g;
  for (int h = 0; h < w.cols(); ++h) {
    g.push_back(at(&w(p, h)));
  }
  g.push_back(at(&bias(p)));
  return g;
}

// Central differences of `loss` in the weights of the parameter network's output row p against
// the gradient left there (output_row_grads, its bias last), within expect_gradients' tolerance.
void expect_output_row_gradients(Mlp<float>& net, int p, const std::function<double()>& loss, const char* what) {
  const std::vector<float> g = output_row_grads(net, p);
  auto w = net.weight(static_cast<int>(net.widths().size()) - 2);
  for (int h = 0; h < w.cols(); ++h) {
    const float keep = w(p, h);
    w(p, h) = keep + 1e-3F;
    const double up = loss();
    w(p, h) = keep - 1e-3F;
    const double down = loss();
    w(p, h) = keep;
    const double fd = (up - down) / 2e-3;
    EXPECT_NEAR(g[static_cast<size_t>(h)], fd, 3e-3 + 0.03 * std::abs(fd))
        << what << ": parameter " << p << ", weight " << h;
  }
}

// pdqn.zero_index_gradients: on a batch whose samples all took one action, the parameter step
// leaves the gradient of that action's own parameters as it was (the loss's own, by finite
// differences) and zeroes every other parameter's; the loss itself is unchanged.
TEST(Pdqn, ZeroIndexGradientsKeepOnlyTheTakenActionsParameters) {
  for (const bool multipass : {false, true}) {
    const ActionSpace space = wide_space();
    PdqnSettings zeroed;
    zeroed.zero_index_gradients = true;
    for (const int taken : {0, 1, 2}) {  // "one" owns p0, "two" p1 and p2, "none" nothing
      Pdqn full(kObs, space, small(BoundMethod::kZeroing), 5, multipass);
      Pdqn zero(kObs, space, small(BoundMethod::kZeroing), 5, multipass, {}, zeroed);
      Batch b;
      b.actions.row(taken).setConstant(2.0F);
      const BatchView v = b.view();
      EXPECT_DOUBLE_EQ(full.losses(v).param_loss, zero.losses(v).param_loss);
      full.gradients(v);
      zero.gradients(v);
      const auto& owned = space.actions[static_cast<size_t>(taken)].param_indices;
      for (int p = 0; p < 3; ++p) {
        const bool own = std::find(owned.begin(), owned.end(), p) != owned.end();
        const std::vector<float> f = output_row_grads(full.param_net(), p);
        const std::vector<float> z = output_row_grads(zero.param_net(), p);
        float largest = 0.0F;
        for (size_t i = 0; i < f.size(); ++i) {
          largest = std::max(largest, std::abs(f[i]));
          EXPECT_FLOAT_EQ(z[i], own ? f[i] : 0.0F) << "action " << taken << ", parameter " << p << ", entry " << i;
        }
        EXPECT_GT(largest, 1e-4F) << "parameter " << p << " has no gradient to keep or zero";
      }
      if (owned.empty()) {
        for (const float g : zero.param_net().grads()) {
          ASSERT_EQ(g, 0.0F) << "a sample whose action has no parameters moves none";
        }
      }
    }
    // The rows kept are the loss's own gradient: finite differences of the full loss.
    Pdqn zero(kObs, space, small(BoundMethod::kZeroing), 5, multipass, {}, zeroed);
    Batch b;
    b.actions.row(1).setConstant(2.0F);
    const BatchView v = b.view();
    zero.gradients(v);
    for (const int p : {1, 2}) {
      expect_output_row_gradients(
          zero.param_net(), p, [&] { return zero.losses(v).param_loss; }, "zeroed index gradients");
    }
  }
}

// pdqn.own_action_gradients (P-DQN's single pass): the gradient on the parameter network's output
// row p is that of action owner(p)'s Q alone, -(1 / B) Σ_j Q(s_j, owner(p), x(s_j)), by finite
// differences through the learner's own act(); it is not the summed loss's (whose cross-terms
// it drops), and a parameter-free action's Q moves nothing. For MP-DQN it changes nothing.
TEST(Pdqn, OwnActionGradientsStepEachActionsParametersOnItsOwnQ) {
  const ActionSpace space = wide_space();
  PdqnSettings own;
  own.own_action_gradients = true;
  Pdqn pdqn(kObs, space, small(BoundMethod::kZeroing), 5, false, {}, own);
  Pdqn summed(kObs, space, small(BoundMethod::kZeroing), 5, false);
  const Batch b;
  const BatchView v = b.view();
  EXPECT_DOUBLE_EQ(pdqn.losses(v).param_loss, summed.losses(v).param_loss);
  pdqn.gradients(v);
  summed.gradients(v);
  std::vector<float> out(6);
  const auto own_q_loss = [&](int k) {
    double l = 0.0;
    for (int j = 0; j < kB; ++j) {
      pdqn.act({b.states.col(j).data(), kObs}, out, ActorCopy::kOnline);
      l -= out[static_cast<size_t>(k)] / kB;
    }
    return l;
  };
  float differs = 0.0F;
  for (int p = 0; p < 3; ++p) {
    const int owner = p == 0 ? 0 : 1;  // "one" owns p0, "two" p1 and p2
    expect_output_row_gradients(
        pdqn.param_net(), p, [&] { return own_q_loss(owner); }, "own-action gradients");
    const std::vector<float> g = output_row_grads(pdqn.param_net(), p);
    const std::vector<float> s = output_row_grads(summed.param_net(), p);
    for (size_t i = 0; i < g.size(); ++i) {
      differs = std::max(differs, std::abs(g[i] - s[i]));
    }
  }
  EXPECT_GT(differs, 1e-3F) << "the summed loss's cross-terms were not dropped";
  // MP-DQN: each pass sees only its own action's parameters, so the option changes nothing.
  Pdqn mp_own(kObs, space, small(BoundMethod::kZeroing), 5, true, {}, own);
  Pdqn mp(kObs, space, small(BoundMethod::kZeroing), 5, true);
  mp_own.gradients(v);
  mp.gradients(v);
  const std::vector<float> a(mp_own.param_net().grads().begin(), mp_own.param_net().grads().end());
  const std::vector<float> c(mp.param_net().grads().begin(), mp.param_net().grads().end());
  EXPECT_EQ(a, c);
}

// A gated action (exploration.gated_actions; here "one", open where state feature 0 > 0): where
// its gate is shut it is not the action a sample took though its stored score is highest, not in
// the target's max over the next state's actions, and not in the parameter loss; where open it is
// all three. Both losses by hand, and their gradients against finite differences.
TEST(Pdqn, GatesByHand) {
  for (const bool multipass : {false, true}) {
    const ActionSpace space = wide_space();
    Pdqn pdqn(kObs, space, small(BoundMethod::kZeroing), 5, multipass);
    pdqn.set_gates({{0, 0}});
    Rng rng(11);
    pdqn.target_q_net().init_gaussian(rng, 0.5F);
    pdqn.target_param_net().init_gaussian(rng, 0.5F);
    Batch b;
    b.actions.col(0) << 0.9F, 0.2F, 0.1F, 0.5F, -0.5F, 0.25F;  // "one" ranks first: shut at 0, open at 1
    b.actions.col(1) << 0.9F, 0.2F, 0.1F, 0.5F, -0.5F, 0.25F;
    b.states(0, 0) = -0.5F;
    b.states(0, 1) = 0.5F;
    b.next_states(0, 2) = -0.5F;
    b.next_states(0, 3) = 0.5F;
    const BatchView v = b.view();
    double q_loss = 0.0;
    double param_loss = 0.0;
    std::vector<float> out(6);
    std::vector<float> next(6);
    int shut_seen = 0;
    for (int j = 0; j < kB; ++j) {
      const bool open = b.states(0, j) > 0.0F;
      const bool next_open = b.next_states(0, j) > 0.0F;
      shut_seen += open ? 0 : 1;
      int taken = -1;
      for (const int k : {0, 1, 2}) {
        if (k == 0 && !open) {
          continue;
        }
        taken = taken < 0 || b.actions(k, j) > b.actions(taken, j) ? k : taken;
      }
      if (j < 2) {
        ASSERT_EQ(taken == 0, j == 1);
      }
      const float q = pdqn.q_net().forward(q_input(space, b, j, taken, multipass))(taken, 0);
      pdqn.act({b.next_states.col(j).data(), kObs}, next, ActorCopy::kTarget);
      const float best = next_open ? std::max({next[0], next[1], next[2]}) : std::max(next[1], next[2]);
      const float y = b.rewards(j) + (b.terminal(j) > 0.5F ? 0.0F : 0.9F * best);
      q_loss += 0.5 * (q - y) * (q - y) / kB;
      pdqn.act({b.states.col(j).data(), kObs}, out, ActorCopy::kOnline);
      param_loss -= ((open ? out[0] : 0.0F) + out[1] + out[2]) / kB;
    }
    ASSERT_GT(shut_seen, 0);
    const Pdqn::Losses l = pdqn.losses(v);
    EXPECT_NEAR(l.q_loss, q_loss, 1e-5 * (1.0 + q_loss)) << (multipass ? "mpdqn" : "pdqn");
    EXPECT_NEAR(l.param_loss, param_loss, 1e-5 * (1.0 + std::abs(param_loss))) << (multipass ? "mpdqn" : "pdqn");
    pdqn.gradients(v);
    expect_gradients(
        pdqn.q_net(), [&] { return pdqn.losses(v).q_loss; }, "Q loss");
    pdqn.gradients(v);
    expect_gradients(
        pdqn.param_net(), [&] { return pdqn.losses(v).param_loss; }, "parameter loss");
  }
  const ActionSpace space = test_space();
  Pdqn bad(kObs, space, small(BoundMethod::kZeroing), 5, true, /*masked_actions=*/{1});
  EXPECT_THROW(bad.set_gates({{1, 0}}), std::invalid_argument);          // masked and gated
  EXPECT_THROW(bad.set_gates({{0, kObs}}), std::invalid_argument);       // no such feature
  EXPECT_THROW(bad.set_gates({{0, 0}, {2, 1}}), std::invalid_argument);  // nothing left ungated
}

// MP-DQN's score k comes from a pass that sees only action k's parameters, all K passes of
// x(s): rebuilt by hand here from act()'s own parameters.
TEST(Pdqn, MultiPassScoresComeFromOnePassPerAction) {
  const ActionSpace space = test_space();
  Pdqn mp(kObs, space, small(BoundMethod::kInverting), 5, true);
  const Eigen::Vector3f s(0.1F, -0.3F, 0.7F);
  std::vector<float> a(6);
  mp.act({s.data(), kObs}, a);
  Eigen::MatrixXf passes(kObs + 3, 3);
  for (int k = 0; k < 3; ++k) {
    passes.col(k) << s, Eigen::Vector3f::Zero();
  }
  passes(kObs + 0, 0) = a[3];  // "one" owns p0
  passes(kObs + 1, 1) = a[4];  // "two" owns p1 and p2
  passes(kObs + 2, 1) = a[5];  // "none" owns nothing
  const Eigen::MatrixXf q = mp.q_net().forward(passes);
  for (int k = 0; k < 3; ++k) {
    EXPECT_FLOAT_EQ(a[static_cast<size_t>(k)], q(k, k)) << "action " << k;
  }
  // A pass that saw the other actions' parameters too would give other values.
  passes.col(0).tail(3) << a[3], a[4], a[5];
  EXPECT_NE(mp.q_net().forward(passes)(0, 0), a[0]);
}

// What an actor plays from the published networks is exactly what the learner's act() gives.
TEST(Pdqn, TheActorsPlayWhatTheLearnerActs) {
  for (const bool multipass : {false, true}) {
    for (const BoundMethod bound : {BoundMethod::kInverting, BoundMethod::kSquashing}) {
      const ActionSpace space = test_space();
      Pdqn pdqn(kObs, space, small(bound), 9, multipass);
      const ActingWeights w = pdqn.acting_weights();
      const ActingPolicyRegistration* r = acting_policy_registry().find(w.algorithm);
      ASSERT_NE(r, nullptr) << w.algorithm;
      const std::unique_ptr<ActingPolicy> policy = r->make(kObs, space);
      ASSERT_EQ(policy->check(w.networks, w.bound), nullptr);
      policy->load(w.networks, w.bound);
      std::vector<float> mine(6);
      std::vector<float> theirs(6);
      for (int i = 0; i < 20; ++i) {
        const Eigen::Vector3f s = Eigen::Vector3f::Random();
        pdqn.act({s.data(), kObs}, mine);
        policy->act({s.data(), kObs}, theirs);
        EXPECT_EQ(mine, theirs) << w.algorithm;
      }
      // The other algorithm's networks are refused.
      const ActingWeights ddpg_like{"ddpg", 0, {w.networks[0]}};
      EXPECT_NE(policy->check(ddpg_like.networks, 0), nullptr);
    }
  }
}

app::ExperimentConfig toy(const std::string& algorithm, int64_t updates) {
  std::ifstream in(std::string(PAMDP_SOURCE_DIR) + "/deploy/configs/reach_stop.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  app::ExperimentConfig c = app::parse_experiment_config(ss.str(), "reach_stop.toml", {});
  c.train.algorithm = algorithm;
  c.train.max_updates = updates;
  c.train.log_every_seconds = 1e9;
  return c;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("pamdp_pdqn_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

std::vector<float> state_of(const fs::path& ckpt, const app::ExperimentConfig& c) {
  const toy::ReachStopEnv env;
  const std::unique_ptr<Algorithm> a = app::make_learner(c, env.observation_size(), env.action_space(), 99);
  load_checkpoint(ckpt.string(), *a);
  std::vector<float> all;
  for (const StateTensor& t : a->state_tensors()) {
    all.insert(all.end(), t.values.begin(), t.values.end());
  }
  all.push_back(static_cast<float>(a->updates()));
  return all;
}

// The toy task, learned in about a second by each, through `pamdp train`'s own loop; a run
// stopped and resumed ends where one that never stopped does.
TEST(Pdqn, LearnsReachStopAndResumesExactly) {
  for (const std::string algorithm : {"pdqn", "mpdqn"}) {
    const fs::path dir = fresh_dir(algorithm);
    const app::TrainSummary s = app::train(toy(algorithm, 12000), {dir.string(), false, true, nullptr});
    EXPECT_GE(s.final_eval.goal_rate, 0.9) << algorithm << " failed to learn ReachStop";
    EXPECT_EQ(read_checkpoint_algorithm((dir / "checkpoint.ckpt").string()), algorithm);

    const fs::path straight = fresh_dir(algorithm + "_straight");
    const fs::path halves = fresh_dir(algorithm + "_halves");
    // Stopped half-way by train.max_episodes (train.max_updates is exact, so a run it stops ends
    // its last episode without updates, which one that never stopped makes).
    const app::TrainSummary whole = app::train(toy(algorithm, 3000), {straight.string(), false, true, nullptr});
    EXPECT_EQ(whole.updates, 3000) << algorithm;
    app::ExperimentConfig half = toy(algorithm, 3000);
    half.train.max_episodes = whole.episodes / 2;
    app::train(half, {halves.string(), false, true, nullptr});
    app::train(toy(algorithm, 3000), {halves.string(), true, true, nullptr});
    EXPECT_EQ(state_of(straight / "checkpoint.ckpt", toy(algorithm, 3000)),
              state_of(halves / "checkpoint.ckpt", toy(algorithm, 3000)))
        << algorithm;
    for (const fs::path& d : {dir, straight, halves}) {
      fs::remove_all(d);
    }
  }
}

// Settings P-DQN does not have are refused naming the key, not ignored.
TEST(Pdqn, RefusesSettingsItDoesNotHave) {
  const ActionSpace space = test_space();
  DdpgConfig cloning = small(BoundMethod::kInverting);
  cloning.demo_bc_weight = 1.0;
  DdpgConfig gpu = small(BoundMethod::kInverting);
  gpu.device = UpdateDevice::kCuda;
  for (const auto& [config, key] : {std::pair{cloning, "ddpg.demo_bc_weight"}, std::pair{gpu, "ddpg.device"}}) {
    try {
      Pdqn p(kObs, space, config, 1, false);
      ADD_FAILURE() << key << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

// exploration.gated_actions resolves against the env's own gates: KICK on HFO (its kickable
// feature) reaches P-DQN/MP-DQN; an env without that gate, or DDPG (whose critic reads the stored
// scores a gate overrides), is refused with the key named.
TEST(Pdqn, GatedActionsComeFromTheEnvAndOnlyValueLearnersTakeThem) {
  const auto learner = [](const std::string& toml) {
    const app::ExperimentConfig c = app::parse_experiment_config(toml, "test", {});
    const auto env = app::make_env(c.env);
    return app::make_learner(c, env->observation_size(), env->action_space(), 1, UpdateDevice::kCpu);
  };
  const std::string gated = "[exploration]\ngated_actions = [\"KICK\"]\n";
  EXPECT_NO_THROW(learner("[env]\nname = \"hfo\"\n[train]\nalgorithm = \"mpdqn\"\n" + gated));
  const auto refused = [&](const std::string& toml, const char* says) {
    try {
      learner(toml);
      ADD_FAILURE() << toml << " was accepted";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("exploration.gated_actions"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  refused("[env]\nname = \"hfo\"\n[train]\nalgorithm = \"ddpg\"\n" + gated, "DDPG");
  refused(
      "[env]\nname = \"platform\"\n[train]\nalgorithm = \"mpdqn\"\n"
      "[exploration]\nmasked_actions = []\ngated_actions = [\"JUMP\"]\n",
      "platform");
}

PdqnSettings with_passthrough(float output_std) {
  PdqnSettings s;
  s.passthrough = true;
  s.param_output_init_std = output_std;
  return s;
}

// With the pass-through layer the parameter network starts at the env's hand-made policy
// (W s + b, its own output near zero), the layer stays fixed through updates, its gradients
// match finite differences, and the actors play exactly what the learner acts.
TEST(Pdqn, PassthroughStartsAtThePriorAndStaysFixed) {
  const ActionSpace space = test_space();
  const ParameterPrior prior = random_prior(4);
  for (const bool multipass : {false, true}) {
    Pdqn pdqn(kObs, space, small(BoundMethod::kInverting), 5, multipass, {}, with_passthrough(1e-6F), &prior);
    std::vector<float> out(6);
    const Eigen::Vector3f s(0.3F, -0.6F, 0.9F);
    pdqn.act({s.data(), kObs}, out);
    for (int p = 0; p < 3; ++p) {
      float want = prior.bias[static_cast<size_t>(p)];
      for (int j = 0; j < kObs; ++j) {
        want += prior.weights[static_cast<size_t>(p * kObs + j)] * s(j);
      }
      EXPECT_NEAR(out[static_cast<size_t>(3 + p)], want, 1e-4) << "parameter " << p;
    }
    const std::vector<float> layer(pdqn.passthrough_net().params().begin(), pdqn.passthrough_net().params().end());
    const Batch b;
    for (int i = 0; i < 5; ++i) {
      pdqn.update(b.view());
    }
    EXPECT_EQ(layer,
              std::vector<float>(pdqn.passthrough_net().params().begin(), pdqn.passthrough_net().params().end()));

    const ActingWeights w = pdqn.acting_weights();
    ASSERT_EQ(w.networks.size(), 3U);
    const std::unique_ptr<ActingPolicy> policy = acting_policy_registry().find(w.algorithm)->make(kObs, space);
    ASSERT_EQ(policy->check(w.networks, w.bound), nullptr);
    policy->load(w.networks, w.bound);
    std::vector<float> theirs(6);
    policy->act({s.data(), kObs}, theirs);
    pdqn.act({s.data(), kObs}, out);
    EXPECT_EQ(out, theirs);
    // A layer of the wrong width is refused.
    std::vector<NetworkView> wrong = w.networks;
    const std::vector<int> widths{kObs + 1, 3};
    wrong[2].widths = widths;
    EXPECT_NE(policy->check(wrong, w.bound), nullptr);
  }
}

TEST(Pdqn, PassthroughGradientsMatchFiniteDifferences) {
  const ActionSpace space = wide_space();
  const ParameterPrior prior = random_prior(8);
  for (const BoundMethod bound : {BoundMethod::kZeroing, BoundMethod::kSquashing}) {
    Pdqn pdqn(kObs, space, small(bound), 3, true, {2}, with_passthrough(0.0F), &prior);
    const Batch b;
    const BatchView v = b.view();
    pdqn.gradients(v);
    expect_gradients(
        pdqn.param_net(), [&] { return pdqn.losses(v).param_loss; }, "parameter loss with the pass-through layer");
  }
}

// pdqn.reward_scale: the Q target is built from the scaled rewards and returns, exactly as if the
// batch had carried them.
TEST(Pdqn, RewardScaleScalesTheTarget) {
  const ActionSpace space = test_space();
  PdqnSettings scaled;
  scaled.reward_scale = 0.02;
  DdpgConfig config = small(BoundMethod::kInverting);
  config.mc_mix = 0.25;
  Pdqn a(kObs, space, config, 5, true, {}, scaled);
  Pdqn plain(kObs, space, config, 5, true);
  Batch b;
  b.rewards *= 50.0F;
  b.mc = Eigen::VectorXf::Random(kB) * 50.0F;
  Batch by_hand = b;
  by_hand.rewards *= 0.02F;
  by_hand.mc *= 0.02F;
  const double want = plain.losses(by_hand.view()).q_loss;
  EXPECT_NEAR(a.losses(b.view()).q_loss, want, 1e-6 * (1.0 + want));
  EXPECT_GT(std::abs(plain.losses(b.view()).q_loss - want), 1e-3);  // the scale matters here
}

// ddpg.bootstrap_clip bounds max_k Q'(s', k, x'(s')): with the Q-networks' output weights zeroed
// every output is the bias B, and the Q loss is (1 / 2B) sum (B - y)^2 with
// y = r + 0.9 * clamp(B, -c, c) (r after the terminal sample).
TEST(Pdqn, BootstrapClipBoundsTheTargetNetworksValue) {
  const ActionSpace space = test_space();
  const Batch b;
  for (const double clip : {0.0, 2.0, 1000.0}) {
    DdpgConfig config = small(BoundMethod::kInverting);
    config.critic_output_init_bias = 100.0;
    config.bootstrap_clip = clip;
    Pdqn pdqn(kObs, space, config, 5, true);
    for (Mlp<float>* net : {&pdqn.q_net(), &pdqn.target_q_net()}) {
      net->weight(net->num_layers() - 1).setZero();
    }
    const double next = clip > 0.0 && clip < 100.0 ? clip : 100.0;
    double want = 0.0;
    for (int j = 0; j < kB; ++j) {
      const double y = b.rewards(j) + (b.terminal(j) > 0.5F ? 0.0 : 0.9 * next);
      want += 0.5 * (100.0 - y) * (100.0 - y) / kB;
    }
    EXPECT_NEAR(pdqn.losses(b.view()).q_loss, want, 1e-4 * want) << clip;
  }
}

// pdqn.q_tau and pdqn.param_tau move each target network at its own rate.
TEST(Pdqn, EachNetworkHasItsOwnTargetRate) {
  const ActionSpace space = test_space();
  PdqnSettings rates;
  rates.q_tau = 0.5;
  rates.param_tau = 0.25;
  Pdqn pdqn(kObs, space, small(BoundMethod::kInverting), 5, false, {}, rates);
  Rng rng(2);
  pdqn.target_q_net().init_gaussian(rng, 0.5F);
  pdqn.target_param_net().init_gaussian(rng, 0.5F);
  const auto copy = [](std::span<const float> v) { return std::vector<float>(v.begin(), v.end()); };
  const std::vector<float> old_q = copy(pdqn.target_q_net().params());
  const std::vector<float> old_param = copy(pdqn.target_param_net().params());
  const Batch b;
  pdqn.update(b.view());
  for (size_t i = 0; i < old_q.size(); ++i) {
    EXPECT_NEAR(pdqn.target_q_net().params()[i], 0.5F * old_q[i] + 0.5F * pdqn.q_net().params()[i], 1e-6) << i;
  }
  for (size_t i = 0; i < old_param.size(); ++i) {
    EXPECT_NEAR(pdqn.target_param_net().params()[i], 0.75F * old_param[i] + 0.25F * pdqn.param_net().params()[i], 1e-6)
        << i;
  }
}

// The pass-through layer without a hand-made policy to start from is refused, naming the key.
TEST(Pdqn, PassthroughNeedsTheEnvsPolicy) {
  const ActionSpace space = test_space();
  try {
    Pdqn p(kObs, space, small(BoundMethod::kInverting), 1, false, {}, with_passthrough(0.0F), nullptr);
    ADD_FAILURE() << "pdqn.passthrough was accepted without a policy";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pdqn.passthrough"), std::string::npos) << e.what();
  }
}

// The pass-through layer is part of the checkpoint: a learner built from another policy reads
// the saved one back.
TEST(Pdqn, PassthroughIsCheckpointed) {
  const ActionSpace space = test_space();
  const ParameterPrior prior = random_prior(4);
  const ParameterPrior other = random_prior(5);
  Pdqn saved(kObs, space, small(BoundMethod::kInverting), 5, true, {}, with_passthrough(0.0F), &prior);
  const fs::path dir = fresh_dir("passthrough");
  fs::create_directories(dir);
  const std::string path = (dir / "p.ckpt").string();
  save_checkpoint(path, saved, {});
  Pdqn loaded(kObs, space, small(BoundMethod::kInverting), 6, true, {}, with_passthrough(0.0F), &other);
  load_checkpoint(path, loaded);
  EXPECT_TRUE(std::equal(saved.passthrough_net().params().begin(), saved.passthrough_net().params().end(),
                         loaded.passthrough_net().params().begin()));
  fs::remove_all(dir);
}

std::vector<float> flat(std::span<const float> a, std::span<const float> b) {
  std::vector<float> v(a.begin(), a.end());
  v.insert(v.end(), b.begin(), b.end());
  return v;
}

// The evaluation average (ddpg.actor_average_tau): it starts as both online networks, absorbs
// the updates since its last sync_acting() by 1 - (1 - tau)^k, stands still without new updates,
// and act(kAverage) plays it, the pass-through layer included. Without it there is none to play.
TEST(Pdqn, EvaluationAverageMovesByTheUpdatesSinceItsLastCall) {
  for (const bool multipass : {false, true}) {
    const ActionSpace space = test_space();
    const ParameterPrior prior = random_prior(4);
    DdpgConfig c = small(BoundMethod::kInverting);
    c.actor_average_tau = 0.1;
    Pdqn p(kObs, space, c, 3, multipass, {}, with_passthrough(0.5F), &prior);
    EXPECT_EQ(p.evaluated_copy(), ActorCopy::kAverage);
    EXPECT_NE(p.evaluated_copy_note().find("actor_average_tau"), std::string::npos);
    const std::vector<float> start = flat(p.param_net().params(), p.q_net().params());
    ASSERT_EQ(start, flat(p.param_average().params(), p.q_average().params()));
    const Batch batch;
    for (int i = 0; i < 3; ++i) {
      p.update(batch.view());
    }
    const std::vector<float> online = flat(p.param_net().params(), p.q_net().params());
    ASSERT_NE(online, start);
    ASSERT_EQ(start, flat(p.param_average().params(), p.q_average().params()));  // not synced yet
    p.sync_acting();
    EXPECT_EQ(p.average_updates(), 3);
    const std::vector<float> avg = flat(p.param_average().params(), p.q_average().params());
    for (size_t i = 0; i < avg.size(); ++i) {
      ASSERT_NEAR(avg[i], start[i] + 0.271F * (online[i] - start[i]), 1e-6F) << i;  // 1 - 0.9^3
    }
    p.sync_acting();  // nothing new to absorb
    EXPECT_EQ(avg, flat(p.param_average().params(), p.q_average().params()));

    // A learner whose online networks are that average acts as act(kAverage) does.
    Pdqn copy(kObs, space, c, 4, multipass, {}, with_passthrough(0.5F), &prior);
    std::copy(p.param_average().params().begin(), p.param_average().params().end(), copy.param_net().params().begin());
    std::copy(p.q_average().params().begin(), p.q_average().params().end(), copy.q_net().params().begin());
    std::vector<float> mine(6);
    std::vector<float> theirs(6);
    std::vector<float> online_out(6);
    bool differs = false;
    for (int i = 0; i < 10; ++i) {
      const Eigen::Vector3f s = Eigen::Vector3f::Random();
      p.act({s.data(), kObs}, mine, ActorCopy::kAverage);
      copy.act({s.data(), kObs}, theirs);
      p.act({s.data(), kObs}, online_out);
      EXPECT_EQ(mine, theirs) << multipass;
      differs = differs || mine != online_out;
    }
    EXPECT_TRUE(differs) << "act(kAverage) plays the online networks";

    Pdqn plain(kObs, space, small(BoundMethod::kInverting), 3, multipass);
    EXPECT_EQ(plain.evaluated_copy(), ActorCopy::kOnline);
    EXPECT_TRUE(plain.evaluated_copy_note().empty());
    EXPECT_THROW(plain.act({start.data(), kObs}, mine, ActorCopy::kAverage), std::logic_error);
  }
}

// The average is in the checkpoint with the update it last absorbed; a checkpoint written without
// one starts it at the loaded online networks, as a warm start does.
TEST(Pdqn, EvaluationAverageIsCheckpointed) {
  const ActionSpace space = test_space();
  DdpgConfig c = small(BoundMethod::kInverting);
  c.actor_average_tau = 0.1;
  Pdqn saved(kObs, space, c, 5, true);
  const Batch batch;
  for (int i = 0; i < 4; ++i) {
    saved.update(batch.view());
    if (i == 1) {
      saved.sync_acting();
    }
  }
  const fs::path dir = fresh_dir("average");
  fs::create_directories(dir);
  const std::string path = (dir / "a.ckpt").string();
  save_checkpoint(path, saved, {});
  Pdqn loaded(kObs, space, c, 6, true);
  load_checkpoint(path, loaded);
  EXPECT_EQ(flat(saved.param_average().params(), saved.q_average().params()),
            flat(loaded.param_average().params(), loaded.q_average().params()));
  EXPECT_EQ(loaded.average_updates(), 2);
  EXPECT_EQ(loaded.updates(), 4);

  Pdqn without(kObs, space, small(BoundMethod::kInverting), 7, true);
  without.update(batch.view());
  save_checkpoint(path, without, {});
  load_checkpoint(path, loaded);
  EXPECT_EQ(flat(without.param_net().params(), without.q_net().params()),
            flat(loaded.param_average().params(), loaded.q_average().params()));
  EXPECT_EQ(loaded.average_updates(), 1);

  save_checkpoint(path, saved, {});
  Pdqn warm(kObs, space, c, 8, true);
  warm_start_from_checkpoint(path, warm);
  EXPECT_EQ(flat(saved.param_net().params(), saved.q_net().params()),
            flat(warm.param_average().params(), warm.q_average().params()));
  fs::remove_all(dir);
}

// Through `pamdp train`: a run with the average, stopped and resumed, ends with the same state
// (the average included) as one that never stopped, and its average has moved off the start.
TEST(Pdqn, EvaluationAverageSurvivesAResume) {
  const auto config = [](int64_t updates) {
    app::ExperimentConfig c = toy("mpdqn", updates);
    c.ddpg.actor_average_tau = 1e-3;
    return c;
  };
  const fs::path straight = fresh_dir("avg_straight");
  const fs::path halves = fresh_dir("avg_halves");
  const app::TrainSummary whole = app::train(config(3000), {straight.string(), false, true, nullptr});
  app::ExperimentConfig half = config(3000);
  half.train.max_episodes = whole.episodes / 2;
  app::train(half, {halves.string(), false, true, nullptr});
  app::train(config(3000), {halves.string(), true, true, nullptr});
  EXPECT_EQ(state_of(straight / "checkpoint.ckpt", config(3000)), state_of(halves / "checkpoint.ckpt", config(3000)));
  const toy::ReachStopEnv env;
  const std::unique_ptr<Algorithm> a = app::make_learner(config(3000), env.observation_size(), env.action_space(), 99);
  load_checkpoint((straight / "checkpoint.ckpt").string(), *a);
  auto& p = dynamic_cast<Pdqn&>(*a);
  EXPECT_EQ(p.average_updates(), p.updates());
  EXPECT_NE(flat(p.param_average().params(), p.q_average().params()), flat(p.param_net().params(), p.q_net().params()));
  fs::remove_all(straight);
  fs::remove_all(halves);
}

}  // namespace
}  // namespace pamdp
