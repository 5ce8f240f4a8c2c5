// The one harness every Env must pass (envs/env.hpp states the contract). A new env joins by
// adding one EnvCase to kEnvCases below: a factory, its expected observation size and the
// bound its observation values stay within.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/policy.hpp"
#include "envs/env.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/registry.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp {
namespace {

struct EnvCase {
  std::string name;                            // test-name suffix
  std::function<std::unique_ptr<Env>()> make;  // a freshly constructed env
  int expected_observation_size = 0;
  float observation_bound = 0.0F;  // every observation value must satisfy |v| <= bound
  int episodes = 0;                // episodes per random rollout
};

// Test names and failure messages show the case's name, not its bytes.
void PrintTo(const EnvCase& c, std::ostream* os) {
  *os << c.name;
}

std::unique_ptr<Env> make_hfo(bool noise, bool goalie = false, bool shoot_action = false) {
  hfo::SoccerSimConfig config;
  config.noise = noise;
  config.goalie = goalie;
  return std::make_unique<hfo::HfoEnv>(config, shoot_action);
}

const EnvCase kHandCases[] = {
    {"HfoNoise", [] { return make_hfo(true); }, hfo::kNumAgentFeatures, 1.0F, 30},
    {"HfoNoNoise", [] { return make_hfo(false); }, hfo::kNumAgentFeatures, 1.0F, 30},
    {"HfoGoalieNoise", [] { return make_hfo(true, true); }, hfo::feature_count(2), 1.0F, 30},
    {"HfoGoalieNoNoise", [] { return make_hfo(false, true); }, hfo::feature_count(2), 1.0F, 30},
    {"HfoGoalieShootAction", [] { return make_hfo(true, true, true); }, hfo::feature_count(2), 1.0F, 30},
    {"ReachStop", [] { return std::make_unique<toy::ReachStopEnv>(); }, toy::ReachStopEnv::kObservationSize,
     toy::ReachStopEnv::kObservationBound, 200},
};

// The hand-made cases, and every registered env that plays in-process (envs/registry.hpp) from
// its defaults, so that a new env passes the harness without a line here.
std::vector<EnvCase> env_cases() {
  std::vector<EnvCase> cases(std::begin(kHandCases), std::end(kHandCases));
  for (const EnvRegistration& r : env_registry().all()) {
    if (r.location) {
      continue;  // needs a server of its own (hfo-server: tests/hfo_server_integration_test.sh)
    }
    std::string name = "Registered_" + r.name;
    std::replace_if(
        name.begin(), name.end(), [](char ch) { return std::isalnum(static_cast<unsigned char>(ch)) == 0; }, '_');
    const EnvParams defaults = env_registry().defaults();
    cases.push_back(
        {name, [&r, defaults] { return r.make(defaults); }, r.observation_size(defaults), r.observation_bound, 30});
    // An env that can show its parameters over [-1, 1] (envs/scaled_parameters.hpp) passes as that too.
    if (env_registry().reads(r.name, "scaled_parameters")) {
      EnvParams scaled = defaults;
      scaled.set("scaled_parameters", true);
      cases.push_back({name + "_ScaledParameters", [&r, scaled] { return r.make(scaled); }, r.observation_size(scaled),
                       r.observation_bound, 30});
    }
  }
  return cases;
}

// Everything an episode sequence produced, in order: the observation after every reset and
// step, every reward and status, and the length of every episode.
struct Trace {
  std::vector<float> obs;
  std::vector<float> rewards;
  std::vector<int> statuses;
  std::vector<int> lengths;
};

// Bit patterns, so that "identical" means identical (and a NaN would not compare equal).
std::vector<uint32_t> bits(const std::vector<float>& v) {
  std::vector<uint32_t> out(v.size());
  std::transform(v.begin(), v.end(), out.begin(), [](float f) { return std::bit_cast<uint32_t>(f); });
  return out;
}

class EnvConformance : public ::testing::TestWithParam<EnvCase> {
 protected:
  // Plays `episodes` episodes with a RandomPolicy seeded `policy_seed`: the first reset uses
  // `seed`, later ones continue the env's stream. Stops an episode (and fails) if it runs past
  // max_episode_steps().
  // `episodes` episodes, the first from reset(seed) (or, with seeded = false, from reset()),
  // the rest from reset().
  static Trace rollout(Env& env, uint64_t seed, uint64_t policy_seed, int episodes, bool seeded = true) {
    Trace t;
    RandomPolicy policy(env.action_space(), policy_seed);
    std::vector<float> obs(static_cast<size_t>(env.observation_size()));
    for (int ep = 0; ep < episodes; ++ep) {
      if (ep == 0 && seeded) {
        env.reset(seed, obs);
      } else {
        env.reset(obs);
      }
      policy.begin_episode();
      t.obs.insert(t.obs.end(), obs.begin(), obs.end());
      int steps = 0;
      StepResult r;
      do {
        r = env.step(policy.act(obs), obs);
        ++steps;
        t.obs.insert(t.obs.end(), obs.begin(), obs.end());
        t.rewards.push_back(r.reward);
        t.statuses.push_back(r.status);
      } while (!r.terminal() && steps <= env.max_episode_steps());
      t.lengths.push_back(steps);
    }
    return t;
  }
  static Trace rollout_unseeded(Env& env, uint64_t policy_seed) { return rollout(env, 0, policy_seed, 1, false); }
};

TEST_P(EnvConformance, ObservationSizeMatchesAndResetWritesEveryValue) {
  const auto env = GetParam().make();
  const int n = env->observation_size();
  ASSERT_EQ(n, GetParam().expected_observation_size);

  // The env gets a span of exactly n floats inside a larger buffer: it must overwrite all n
  // (they start as NaN) and touch nothing after them.
  constexpr float kSentinel = 12345.0F;
  std::vector<float> buffer(static_cast<size_t>(n) + 8, kSentinel);
  std::fill_n(buffer.begin(), n, std::numeric_limits<float>::quiet_NaN());
  const std::span<float> obs(buffer.data(), static_cast<size_t>(n));
  env->reset(7, obs);
  for (int i = 0; i < n; ++i) {
    EXPECT_TRUE(std::isfinite(obs[static_cast<size_t>(i)])) << "reset left observation " << i << " unwritten";
  }
  std::fill(obs.begin(), obs.end(), std::numeric_limits<float>::quiet_NaN());
  RandomPolicy policy(env->action_space(), 7);
  env->step(policy.act(obs), obs);
  for (int i = 0; i < n; ++i) {
    EXPECT_TRUE(std::isfinite(obs[static_cast<size_t>(i)])) << "step left observation " << i << " unwritten";
  }
  for (size_t i = static_cast<size_t>(n); i < buffer.size(); ++i) {
    EXPECT_EQ(buffer[i], kSentinel) << "env wrote past observation_size() at " << i;
  }
}

TEST_P(EnvConformance, ActionSpaceIsConsistent) {
  const auto env = GetParam().make();
  const ActionSpace& space = env->action_space();
  ASSERT_GT(space.num_actions(), 0);
  EXPECT_EQ(space.output_width(), space.num_actions() + space.num_params());

  std::set<std::string> action_names;
  for (int a = 0; a < space.num_actions(); ++a) {
    const DiscreteActionSpec& spec = space.actions[static_cast<size_t>(a)];
    EXPECT_FALSE(spec.name.empty()) << "action " << a;
    EXPECT_TRUE(action_names.insert(spec.name).second) << "duplicate action name " << spec.name;
    EXPECT_EQ(space.find_action(spec.name), a);
    std::set<int> seen;
    for (int p : spec.param_indices) {
      EXPECT_GE(p, 0) << spec.name;
      EXPECT_LT(p, space.num_params()) << spec.name;
      EXPECT_TRUE(seen.insert(p).second) << spec.name << " lists parameter " << p << " twice";
    }
  }
  EXPECT_EQ(space.find_action("NO_SUCH_ACTION"), -1);

  std::set<std::string> param_names;
  for (const ParamSpec& p : space.params) {
    EXPECT_FALSE(p.name.empty());
    EXPECT_TRUE(param_names.insert(p.name).second) << "duplicate parameter name " << p.name;
    EXPECT_TRUE(std::isfinite(p.lo) && std::isfinite(p.hi)) << p.name;
    EXPECT_LT(p.lo, p.hi) << p.name;
  }
}

TEST_P(EnvConformance, OutcomesAreWellFormed) {
  const auto env = GetParam().make();
  const std::span<const int> outcomes = env->outcomes();
  ASSERT_GE(outcomes.size(), 2U) << "an env needs 0 and at least one terminal outcome";
  EXPECT_EQ(outcomes[0], 0);
  std::set<int> codes;
  std::set<std::string> names;
  for (int s : outcomes) {
    EXPECT_TRUE(codes.insert(s).second) << "status " << s << " listed twice";
    const std::string name(env->status_name(s));
    EXPECT_FALSE(name.empty()) << "status " << s;
    EXPECT_TRUE(names.insert(name).second) << "status name " << name << " used twice";
  }
  const int success = env->success_status();
  if (success != -1) {
    EXPECT_NE(success, 0);
    EXPECT_TRUE(codes.contains(success)) << "success_status " << success << " is not among outcomes()";
  }
  EXPECT_GE(env->max_episode_steps(), 1);
}

TEST_P(EnvConformance, RandomRolloutsStayFiniteBoundedAndEndInTime) {
  const EnvCase& c = GetParam();
  const auto env = c.make();
  const Trace t = rollout(*env, 11, 12, c.episodes);

  for (size_t i = 0; i < t.obs.size(); ++i) {
    const float v = t.obs[i];
    const size_t feature = i % static_cast<size_t>(env->observation_size());
    ASSERT_TRUE(std::isfinite(v)) << "observation value " << i << " (feature " << feature << ")";
    ASSERT_LE(std::fabs(v), c.observation_bound) << "observation value " << i << " (feature " << feature << ")";
  }
  for (float r : t.rewards) {
    ASSERT_TRUE(std::isfinite(r));
  }

  const std::span<const int> outcomes = env->outcomes();
  const std::set<int> codes(outcomes.begin(), outcomes.end());
  size_t step = 0;
  for (int len : t.lengths) {
    ASSERT_LE(len, env->max_episode_steps()) << "episode ran past max_episode_steps()";
    for (int k = 0; k < len - 1; ++k, ++step) {
      ASSERT_EQ(t.statuses[step], 0) << "non-final step of an episode reported a terminal status";
    }
    const int final_status = t.statuses[step++];
    EXPECT_NE(final_status, 0);
    EXPECT_TRUE(codes.contains(final_status)) << "terminal status " << final_status << " is not among outcomes()";
  }
  EXPECT_EQ(step, t.statuses.size());
}

TEST_P(EnvConformance, SameSeedOnFreshEnvsGivesBitIdenticalEpisodes) {
  const EnvCase& c = GetParam();
  const int episodes = std::min(c.episodes, 10);
  const auto a = c.make();
  const auto b = c.make();
  const Trace ta = rollout(*a, 2024, 99, episodes);
  const Trace tb = rollout(*b, 2024, 99, episodes);
  EXPECT_EQ(ta.lengths, tb.lengths);
  EXPECT_EQ(ta.statuses, tb.statuses);
  EXPECT_EQ(bits(ta.rewards), bits(tb.rewards));
  EXPECT_EQ(bits(ta.obs), bits(tb.obs));
}

// Different seeds give different episodes: the start states differ, or, for an env whose start
// is fixed (Platform), what its noise does along the way. The same policy stream plays both.
TEST_P(EnvConformance, DifferentSeedsGiveDifferentEpisodes) {
  const EnvCase& c = GetParam();
  const auto a = c.make();
  const auto b = c.make();
  const Trace ta = rollout(*a, 1, 99, 1);
  const Trace tb = rollout(*b, 2, 99, 1);
  EXPECT_NE(bits(ta.obs), bits(tb.obs));
}

// reset() without a seed goes on with the env's stream: the episode after it is not the one
// the previous seed gave (the same policy stream plays both).
TEST_P(EnvConformance, ResetWithoutSeedContinuesTheStream) {
  const EnvCase& c = GetParam();
  const auto env = c.make();
  const Trace seeded = rollout(*env, 5, 99, 1);
  const Trace next = rollout_unseeded(*env, 99);
  EXPECT_NE(bits(seeded.obs), bits(next.obs)) << "reset() repeated the previous episode";
}

INSTANTIATE_TEST_SUITE_P(AllEnvs, EnvConformance, ::testing::ValuesIn(env_cases()),
                         [](const ::testing::TestParamInfo<EnvCase>& info) { return info.param.name; });

}  // namespace
}  // namespace pamdp
