// LockstepTeamEnv (envs/hfo_server/lockstep_team.hpp): N one-player envs of one synchronous game
// as one team env. The fake server below runs a cycle only once every player has sent its
// command, as rcssserver in synchronous mode does, and refuses (throws) after 2 s without one:
// players stepped one after another on one thread would never get there. Counts operator new, so
// a binary of its own.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "counting_new.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/soccer_sim.hpp"
#include "envs/hfo_server/lockstep_team.hpp"
#include "envs/registry.hpp"

namespace pamdp::hfo_server {
namespace {

// The cycle advances when all `players` have arrived; each then sees the sum of every player's
// (action id + 1) of that cycle. Episodes end (GOAL) at cycle `end_cycle`.
struct SyncServer {
  explicit SyncServer(int players) : players(players) {}
  int players;
  int end_cycle = 1000;
  int disagreeing_player = -1;  // this player reports IN_GAME when the others report GOAL
  int failing_player = -1;      // this player's step throws
  std::mutex m;
  std::condition_variable cv;
  int arrived = 0;
  int sum = 0;
  int last_sum = 0;
  int cycle = 0;

  // Blocks until every player has called it in this cycle; returns the new cycle.
  int wait_for_all(int contribution) {
    std::unique_lock lock(m);
    const int now = cycle;
    sum += contribution;
    if (++arrived == players) {
      last_sum = sum;
      sum = 0;
      arrived = 0;
      ++cycle;
      cv.notify_all();
    } else if (!cv.wait_for(lock, std::chrono::seconds(2), [&] { return cycle != now; })) {
      throw std::runtime_error("fake server: the other players never acted (not in lockstep)");
    }
    return cycle;
  }
};

class SyncPlayer final : public Env {
 public:
  SyncPlayer(SyncServer& server, int index) : server_(server), index_(index) {}
  [[nodiscard]] std::string_view name() const override { return "sync"; }
  [[nodiscard]] const ActionSpace& action_space() const override { return hfo::hfo_action_space(false); }
  [[nodiscard]] int observation_size() const override { return 3; }
  [[nodiscard]] int max_episode_steps() const override { return 1000; }
  [[nodiscard]] std::string_view status_name(int status) const override { return hfo::status_name(status); }
  [[nodiscard]] std::span<const int> outcomes() const override { return hfo::kStatuses; }
  [[nodiscard]] int success_status() const override { return hfo::kGoal; }
  [[nodiscard]] std::span<const EnvCounter> counters() const override {
    counter_[0] = {"steps", steps_};
    return counter_;
  }
  void reset(uint64_t seed, std::span<float> obs) override {
    seeds.push_back(seed);
    reset(obs);
  }
  void reset(std::span<float> obs) override {
    const int cycle = server_.wait_for_all(0);
    obs[0] = static_cast<float>(cycle);
    obs[1] = static_cast<float>(index_);
    obs[2] = 0.0F;
  }
  StepResult step(const ParamAction& action, std::span<float> obs) override {
    if (index_ == server_.failing_player) {
      throw std::runtime_error("player " + std::to_string(index_) + " lost its server");
    }
    const int cycle = server_.wait_for_all(action.id + 1);
    ++steps_;
    obs[0] = static_cast<float>(cycle);
    obs[1] = static_cast<float>(index_);
    obs[2] = static_cast<float>(server_.last_sum);
    int status = cycle >= server_.end_cycle ? hfo::kGoal : hfo::kInGame;
    if (index_ == server_.disagreeing_player) {
      status = hfo::kInGame;
    }
    return {static_cast<float>(index_ + 1), status};
  }
  std::vector<uint64_t> seeds;

 private:
  SyncServer& server_;
  int index_;
  int64_t steps_ = 0;
  mutable std::array<EnvCounter, 1> counter_{};
};

std::unique_ptr<LockstepTeamEnv> team_of(SyncServer& server, bool team_reward = false,
                                         std::vector<SyncPlayer*>* players = nullptr) {
  std::vector<std::unique_ptr<Env>> envs;
  for (int i = 0; i < server.players; ++i) {
    auto p = std::make_unique<SyncPlayer>(server, i);
    if (players != nullptr) {
      players->push_back(p.get());
    }
    envs.push_back(std::move(p));
  }
  return std::make_unique<LockstepTeamEnv>(std::move(envs), team_reward);
}

std::vector<ParamAction> actions_of(std::initializer_list<int> ids) {
  std::vector<ParamAction> a;
  for (const int id : ids) {
    a.push_back({id, std::vector<float>(6, 0.0F)});
  }
  return a;
}

TEST(LockstepTeam, EveryPlayerActsInTheSameCycle) {
  SyncServer server(3);
  auto team = team_of(server);
  EXPECT_EQ(team->agents(), 3);
  EXPECT_EQ(team->observation_size(), 3);
  std::vector<float> obs(9);
  team->reset(obs);
  EXPECT_EQ(obs[0], 1.0F);  // the reset was one cycle of all three
  const auto actions = actions_of({0, 1, 3});
  std::vector<float> rewards(3);
  for (int step = 2; step <= 4; ++step) {
    const StepResult r = team->step_team(actions, obs, rewards);
    EXPECT_EQ(r.status, hfo::kInGame);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(obs[3 * i + 0], static_cast<float>(step)) << "player " << i;  // one cycle per team step
      EXPECT_EQ(obs[3 * i + 1], static_cast<float>(i));                       // player-major
      EXPECT_EQ(obs[3 * i + 2], 1.0F + 2.0F + 4.0F);                          // all three actions
      EXPECT_EQ(rewards[i], static_cast<float>(i + 1));                       // each its own
    }
    EXPECT_FLOAT_EQ(r.reward, 2.0F);  // the mean
  }
}

TEST(LockstepTeam, TeamRewardGivesEveryPlayerTheMean) {
  SyncServer server(2);
  auto team = team_of(server, /*team_reward=*/true);
  std::vector<float> obs(6);
  std::vector<float> rewards(2);
  team->reset(obs);
  const StepResult r = team->step_team(actions_of({0, 0}), obs, rewards);
  EXPECT_FLOAT_EQ(rewards[0], 1.5F);
  EXPECT_FLOAT_EQ(rewards[1], 1.5F);
  EXPECT_FLOAT_EQ(r.reward, 1.5F);
}

TEST(LockstepTeam, TheGameEndsForTheTeamAndSeedsGoToEachPlayer) {
  SyncServer server(2);
  server.end_cycle = 3;
  std::vector<SyncPlayer*> players;
  auto team = team_of(server, false, &players);
  std::vector<float> obs(6);
  std::vector<float> rewards(2);
  team->reset(40, obs);
  EXPECT_EQ(players[0]->seeds, std::vector<uint64_t>{40});
  EXPECT_EQ(players[1]->seeds, std::vector<uint64_t>{41});
  EXPECT_EQ(team->step_team(actions_of({0, 0}), obs, rewards).status, hfo::kInGame);
  EXPECT_EQ(team->step_team(actions_of({0, 0}), obs, rewards).status, hfo::kGoal);
}

TEST(LockstepTeam, PlayersThatDisagreeOnTheStatusAreNotOneGame) {
  SyncServer server(2);
  server.end_cycle = 2;
  server.disagreeing_player = 1;
  auto team = team_of(server);
  std::vector<float> obs(6);
  std::vector<float> rewards(2);
  team->reset(obs);
  try {
    (void)team->step_team(actions_of({0, 0}), obs, rewards);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("player 0: GOAL, player 1: IN_GAME"), std::string::npos) << e.what();
  }
}

TEST(LockstepTeam, APlayersErrorReachesTheCaller) {
  SyncServer server(2);
  auto team = team_of(server);
  std::vector<float> obs(6);
  std::vector<float> rewards(2);
  team->reset(obs);
  server.failing_player = 1;
  server.players = 1;  // player 0 alone completes its cycle, as a server whose other client left
  try {
    (void)team->step_team(actions_of({0, 0}), obs, rewards);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "player 1 lost its server");
  }
}

TEST(LockstepTeam, CountersAreSummedOverThePlayers) {
  SyncServer server(2);
  auto team = team_of(server);
  std::vector<float> obs(6);
  std::vector<float> rewards(2);
  team->reset(obs);
  for (int i = 0; i < 5; ++i) {
    (void)team->step_team(actions_of({0, 0}), obs, rewards);
  }
  ASSERT_EQ(team->counters().size(), 1U);
  EXPECT_EQ(team->counters()[0].name, "steps");
  EXPECT_EQ(team->counters()[0].value, 10);
}

TEST(LockstepTeam, AStepAllocatesNothing) {
  SyncServer server(3);
  auto team = team_of(server);
  std::vector<float> obs(9);
  std::vector<float> rewards(3);
  const auto actions = actions_of({0, 1, 3});
  team->reset(obs);
  (void)team->step_team(actions, obs, rewards);
  long allocations = 0;
  {
    const testing::alloc::CountAllocations count;
    for (int i = 0; i < 200; ++i) {
      (void)team->step_team(actions, obs, rewards);
    }
    allocations = count.count();
  }
  EXPECT_EQ(allocations, 0);
}

TEST(LockstepTeam, RefusesPlayersOfDifferentGames) {
  SyncServer server(1);
  std::vector<std::unique_ptr<Env>> envs;
  envs.push_back(std::make_unique<SyncPlayer>(server, 0));
  envs.push_back(std::make_unique<hfo::HfoEnv>(hfo::SoccerSimConfig{}));
  EXPECT_THROW(LockstepTeamEnv(std::move(envs), false), std::invalid_argument);
  EXPECT_THROW(LockstepTeamEnv({}, false), std::invalid_argument);
}

// env.server_agents on env 'hfo-server': at most the server's agents, checked before any
// server is looked for (so in builds without HFO too).
TEST(LockstepTeam, ServerAgentsAreAtMostTheServersAgents) {
  app::ExperimentConfig c =
      app::parse_experiment_config("[env]\nname = \"hfo-server\"\noffense_agents = 2\nserver_agents = 3\n", "test", {});
  try {
    (void)app::make_env(c.env);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("env.server_agents = 3"), std::string::npos) << what;
    EXPECT_NE(what.find("at most 2"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace pamdp::hfo_server
