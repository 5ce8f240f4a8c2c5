// The env registry (envs/registry.hpp): the envs of this build, their keys and factories, and the
// registrations it refuses.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "envs/hfo/hfo_env.hpp"
#include "envs/registry.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp {
namespace {

EnvRegistration toy_registration(const std::string& name, std::vector<EnvKey> keys = {}) {
  EnvRegistration r;
  r.name = name;
  r.description = "test env";
  r.keys = std::move(keys);
  r.make = [](const EnvParams&) { return std::make_unique<toy::ReachStopEnv>(); };
  r.observation_size = [](const EnvParams&) { return toy::ReachStopEnv::kObservationSize; };
  return r;
}

// The folders of PAMDP_ENVS (envs/CMakeLists.txt), as the build passes them to this test, give
// the registry's order; their envs' names are checked for the folders this test knows.
TEST(EnvRegistry, ListsTheBuildsEnvsInTheBuildFilesOrder) {
  const std::vector<std::string> names = env_registry().names();
  const std::map<std::string, std::string> known{{"hfo", "hfo"}, {"toy", "reach_stop"}, {"hfo_server", "hfo-server"}};
  std::vector<std::string> expected;
  std::stringstream folders(PAMDP_ENVS_FOR_TEST);
  for (std::string folder; std::getline(folders, folder, ',');) {
    const auto it = known.find(folder);
    expected.push_back(it != known.end() ? it->second : folder);
  }
  EXPECT_EQ(names, expected);
  std::string joined;
  for (const std::string& n : names) {
    joined += (joined.empty() ? "" : ", ") + n;
  }
  EXPECT_EQ(env_registry().names_joined(), joined);
}

TEST(EnvRegistry, AnUnknownNameIsAnErrorListingTheRegisteredNames) {
  EXPECT_EQ(env_registry().find_if("hfo_server"), nullptr);
  try {
    (void)env_registry().find("hfo_server");
    FAIL() << "found an unregistered env";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'hfo_server' is unknown (valid: " + env_registry().names_joined() + ")"),
              std::string::npos)
        << e.what();
  }
}

// Every env makes itself from the defaults and reports the width its registration gives without
// making it. An env that plays out of process may be missing from this build (hfo-server without
// HFO): making it then says why.
TEST(EnvRegistry, EveryEnvConstructsFromItsDefaultsAndReportsItsSizes) {
  const EnvParams defaults = env_registry().defaults();
  for (const EnvRegistration& r : env_registry().all()) {
    SCOPED_TRACE(r.name);
    EXPECT_FALSE(r.description.empty());
    const int width = r.observation_size(defaults);
    EXPECT_GT(width, 0);
    std::unique_ptr<Env> env;
    try {
      env = r.make(defaults);
    } catch (const std::runtime_error& e) {
      EXPECT_TRUE(r.location) << "an in-process env failed to build: " << e.what();
      EXPECT_NE(std::string(e.what()).find(r.name), std::string::npos) << e.what();
      continue;
    }
    EXPECT_EQ(env->name(), r.name);
    EXPECT_EQ(env->observation_size(), width);
    EXPECT_GT(env->action_space().num_actions(), 0);
    EXPECT_GT(env->max_episode_steps(), 0);
    for (const EnvKey& k : r.keys) {
      EXPECT_TRUE(defaults.contains(k.name)) << k.name;
      EXPECT_TRUE(env_registry().reads(r.name, k.name));
    }
  }
}

TEST(EnvRegistry, SizesFollowTheSettings) {
  EnvParams p = env_registry().defaults();
  p.set("goalie", true);
  EXPECT_EQ(env_registry().find("hfo").observation_size(p), 66);
  EXPECT_EQ(env_registry().find("hfo").make(p)->observation_size(), 66);
  EXPECT_EQ(env_registry().find("hfo-server").observation_size(p), 68);  // native encoding, no server needed
  p.set("server_encoding", std::string("embedded"));
  EXPECT_EQ(env_registry().find("hfo-server").observation_size(p), 66);
}

// env.start_curriculum_* reach the embedded simulator, and only through set_training_updates:
// an env never told (an evaluation's) plays the full starts.
TEST(EnvRegistry, TheHfoStartCurriculumActsOnlyWhenTold) {
  EnvParams p = env_registry().defaults();
  EXPECT_EQ(p.integer("start_curriculum_updates"), 0);
  EXPECT_EQ(p.integer("start_curriculum_percent"), 25);
  EXPECT_FALSE(env_registry().reads("hfo-server", "start_curriculum_updates"));
  p.set("start_curriculum_updates", int64_t{100});
  p.set("start_curriculum_percent", int64_t{40});
  const auto told = env_registry().find("hfo").make(p);
  const auto untold = env_registry().find("hfo").make(p);
  const auto& sim = [](const Env& e) -> const hfo::SoccerSim& { return dynamic_cast<const hfo::HfoEnv&>(e).sim(); };
  told->set_training_updates(50);
  EXPECT_DOUBLE_EQ(sim(*told).start_scale(), 0.7);
  EXPECT_DOUBLE_EQ(sim(*untold).start_scale(), 1.0);
  std::vector<float> obs(static_cast<size_t>(told->observation_size()));
  told->reset(5, obs);
  untold->reset(5, obs);
  const hfo::Vec2 near = sim(*told).state().ball.pos;
  const hfo::Vec2 far = sim(*untold).state().ball.pos;
  EXPECT_NEAR(52.5 - near.x, 0.7 * (52.5 - far.x), 1e-9);
}

TEST(EnvRegistry, ADuplicateRegistrationIsRefused) {
  EnvRegistry r;
  r.add(toy_registration("toy", {EnvKey::integer("steps", 10, 1, 100)}));
  EXPECT_THROW(r.add(toy_registration("toy")), std::logic_error);
  // A key another env reads must be declared alike: its one value in the config has one default.
  EXPECT_THROW(r.add(toy_registration("toy2", {EnvKey::integer("steps", 20, 1, 100)})), std::logic_error);
  EXPECT_THROW(r.add(toy_registration("toy2", {EnvKey::boolean("a", true), EnvKey::boolean("a", true)})),
               std::logic_error);
  r.add(toy_registration("toy2", {EnvKey::integer("steps", 10, 1, 100), EnvKey::boolean("fast", false)}));
  EXPECT_EQ(r.names_joined(), "toy, toy2");
  ASSERT_EQ(r.keys().size(), 2U);
  EXPECT_EQ(r.defaults().integer("steps"), 10);
  EXPECT_FALSE(r.reads("toy", "fast"));
  EXPECT_TRUE(r.reads("toy2", "fast"));
  EnvRegistration incomplete = toy_registration("toy3");
  incomplete.make = nullptr;
  EXPECT_THROW(r.add(std::move(incomplete)), std::logic_error);
}

TEST(EnvParams, ReadingAnAbsentKeyOrAnotherTypeIsMisuse) {
  EnvParams p;
  p.set("n", int64_t{3});
  EXPECT_EQ(p.integer("n"), 3);
  EXPECT_THROW((void)p.boolean("n"), std::logic_error);
  EXPECT_THROW((void)p.text("missing"), std::logic_error);
  EXPECT_THROW((void)p.at("missing"), std::logic_error);
}

}  // namespace
}  // namespace pamdp
