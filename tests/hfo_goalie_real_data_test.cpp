// The embedded goalie against the real HFO server's (agent2d's), one cycle at a time:
// tests/data/hfo-real-goalie-transitions.csv (a copy of shared/data, README there) holds 1,500
// recorded cycles with noise off and the goalie's own command. For each row the state at t is
// set, the goalie decides, and both players' commands run one cycle.
// Targets (issue 26): the command kind agrees in >= 97 % of rows with its parameters within
// 1 unit or degree, and the goalie's next position is within 0.01 m and its body within 0.5
// degrees in >= 97 %. Measured (docs/simulator.md): kind 100.0 %, kind and parameters 99.9 %,
// next state 99.1 % deciding and 99.1 % with the logged command. The bounds below sit just
// under what is measured, so that any step back fails; docs/simulator.md lists the rows that
// still disagree. Set PAMDP_GOALIE_MISMATCHES=FILE to write every disagreeing row there.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "csv_rows.hpp"
#include "envs/hfo/goalie.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {
namespace {

using testing::CsvRow;

SoccerSimConfig replay_config(bool goalie) {
  SoccerSimConfig cfg;
  cfg.noise = false;
  cfg.goalie = goalie;
  cfg.start = StartDistribution::kHfo;
  return cfg;
}

PlayerState attacker_at(const CsvRow& r) {
  PlayerState a;
  a.pos = {r.num("ax"), r.num("ay")};
  a.vel = {r.num("avx"), r.num("avy")};
  a.body_deg = r.num("abody");
  a.stamina = r.num("astamina");
  a.effort = r.num("aeffort");
  return a;
}

PlayerState goalie_at(const CsvRow& r) {
  PlayerState g;
  g.pos = {r.num("gx"), r.num("gy")};
  g.vel = {r.num("gvx"), r.num("gvy")};
  g.body_deg = r.num("gbody");
  g.stamina = r.num("gstamina");
  g.effort = r.num("geffort");
  g.since_catch = r.empty("g_since_catch") ? PlayerState::kNoCatchYet : static_cast<int>(r.num("g_since_catch"));
  return g;
}

// What a row alone does not hold but the recording does: the memory that carries over from
// earlier cycles of the same game. Both come from the goalie's own recorded commands and the
// server's state flags, never from the row's outcome.
struct Memory {
  int tackle_cycles = 0;     // the server's tackle freeze (tackle_cycles = 10 from its tackle)
  bool ball_caught = false;  // it caught the ball earlier in this episode (state flag 0x10 without 0x20)
};

std::vector<Memory> memory_of(const std::vector<CsvRow>& rows) {
  std::map<std::string, std::vector<long>> tackles;            // src -> cycles
  std::map<std::pair<std::string, std::string>, long> caught;  // (src, ep) -> cycle
  for (const CsvRow& r : rows) {
    const long cycle = static_cast<long>(r.num("cycle"));
    if (r.str("g_cmd") == "TACKLE") {
      tackles[r.str("src")].push_back(cycle);
    }
    const long flags = std::stol(r.str("n_gstate"), nullptr, 16);
    if (r.str("g_cmd") == "CATCH" && (flags & 0x10) != 0 && (flags & 0x20) == 0) {
      caught.emplace(std::make_pair(r.str("src"), r.str("ep")), cycle);
    }
  }
  std::vector<Memory> out;
  out.reserve(rows.size());
  for (const CsvRow& r : rows) {
    const long cycle = static_cast<long>(r.num("cycle"));
    Memory m;
    if (auto t = tackles.find(r.str("src")); t != tackles.end()) {
      for (const long tackle : t->second) {
        if (tackle < cycle && cycle - tackle < kTackleCycles) {
          m.tackle_cycles = static_cast<int>(kTackleCycles - (cycle - tackle));
        }
      }
    }
    if (auto c = caught.find(std::make_pair(r.str("src"), r.str("ep"))); c != caught.end()) {
      m.ball_caught = c->second < cycle;
    }
    out.push_back(m);
  }
  return out;
}

// A sim in the state of row `r`, the goalie under the sim's control or not.
SoccerSim sim_at(const CsvRow& r, bool goalie_plays, const Memory& m = {}) {
  SoccerSim sim(replay_config(true), 1);
  sim.set_state(attacker_at(r), BallState{{r.num("bx"), r.num("by")}, {r.num("bvx"), r.num("bvy")}});
  sim.set_goalie(goalie_at(r));
  if (!goalie_plays) {
    // The same sim, but the goalie's logged command replaces its decision: decide nothing.
    sim = SoccerSim(replay_config(false), 1);
    sim.set_state(attacker_at(r), BallState{{r.num("bx"), r.num("by")}, {r.num("bvx"), r.num("bvy")}});
    SoccerState& s = sim.mutable_state();
    PlayerState g = goalie_at(r);
    g.team = Team::kDefense;
    g.goalie = true;
    s.players[kGoalieIndex] = g;
    s.num_players = kGoalieIndex + 1;
  }
  sim.mutable_state().players[kGoalieIndex].tackle_cycles = m.tackle_cycles;
  sim.mutable_state().players[kGoalieIndex].caught = m.ball_caught;
  return sim;
}

struct NextErrors {
  double pos = 0.0;
  double body = 0.0;
};

NextErrors goalie_error(const SoccerSim& sim, const CsvRow& r) {
  const PlayerState& g = sim.state().players[kGoalieIndex];
  return {std::hypot(g.pos.x - r.num("n_gx"), g.pos.y - r.num("n_gy")),
          std::fabs(wrap_deg(g.body_deg - r.num("n_gbody")))};
}

std::vector<CsvRow> load() {
  return testing::load_csv_rows(std::string(PAMDP_REAL_DATA_DIR) + "/hfo-real-goalie-transitions.csv");
}

// Parameter agreement: dash power and direction, turn moment, catch and tackle direction.
bool params_agree(const GoalieCommand& c, const CsvRow& r) {
  auto near = [](double a, double b, bool angle) { return std::fabs(angle ? wrap_deg(a - b) : a - b) <= 1.0; };
  switch (c.kind) {
    case GoalieCommand::Kind::kDash: return near(c.p1, r.num("g_p1"), false) && near(c.p2, r.num("g_p2"), true);
    // A moment of 180 and one of -180 are the same command at rest; the log's rounding to
    // 1e-3 degrees decides the sign of an exact half turn.
    case GoalieCommand::Kind::kTurn: return near(c.p1, r.num("g_p1"), std::fabs(c.p1) > 179.0);
    case GoalieCommand::Kind::kCatch:
    case GoalieCommand::Kind::kTackle: return near(c.p1, r.num("g_p1"), true);
    case GoalieCommand::Kind::kKick: return near(c.p1, r.num("g_p1"), false) && near(c.p2, r.num("g_p2"), true);
    case GoalieCommand::Kind::kNone: return true;
  }
  return false;
}

TEST(HfoGoalieRealData, CommandAndNextStateAgreeWithTheRealGoalie) {
  const std::vector<CsvRow> rows = load();
  ASSERT_EQ(rows.size(), 1500U) << "tests/data/hfo-real-goalie-transitions.csv is missing or truncated";
  std::FILE* mismatches = nullptr;
  if (const char* path = std::getenv("PAMDP_GOALIE_MISMATCHES")) {
    mismatches = std::fopen(path, "w");
  }
  std::map<std::string, std::array<int, 3>> by_kind;  // rows, kind agrees, params agree
  int kind_ok = 0;
  int cmd_ok = 0;
  int next_ok = 0;
  int physics_ok = 0;
  int skipped = 0;
  const std::vector<Memory> memory = memory_of(rows);
  for (size_t i = 0; i < rows.size(); ++i) {
    const CsvRow& r = rows[i];
    // From episode 801 of scripted_bottomside_s403 on, the goalie's client had left (its 800
    // trials were over): the server parks a disconnected right-side player 1 at (3, -37)
    // (rcssserver Player::disable) and it sends nothing. Those rows show no goalie.
    if (r.num("gx") == 3.0 && r.num("gy") == -37.0) {
      ++skipped;
      continue;
    }
    const std::string logged = r.str("g_cmd");
    // The decision.
    SoccerSim sim = sim_at(r, true, memory[i]);
    const GoalieCommand c = decide_goalie(sim.state(), kGoalieIndex, /*server_noise=*/false);
    const std::string mine = goalie_command_name(c.kind);
    const bool same_kind = mine == logged;
    const bool same = same_kind && params_agree(c, r);
    kind_ok += same_kind ? 1 : 0;
    cmd_ok += same ? 1 : 0;
    auto& k = by_kind[logged];
    k[0] += 1;
    k[1] += same_kind ? 1 : 0;
    k[2] += same ? 1 : 0;
    // The whole cycle with the goalie deciding.
    sim.command_as_received(0, r.str("a_cmd").c_str(), r.num("a_p1"), r.num("a_p2"));
    sim.step();
    const NextErrors e = goalie_error(sim, r);
    const bool next_good = e.pos <= 0.01 && e.body <= 0.5;
    next_ok += next_good ? 1 : 0;
    // The physics alone: the logged goalie command.
    SoccerSim phys = sim_at(r, false, memory[i]);
    phys.command_as_received(0, r.str("a_cmd").c_str(), r.num("a_p1"), r.num("a_p2"));
    phys.command_as_received(kGoalieIndex, logged.c_str(), r.num("g_p1"), r.num("g_p2"));
    phys.step();
    const NextErrors pe = goalie_error(phys, r);
    physics_ok += (pe.pos <= 0.01 && pe.body <= 0.5) ? 1 : 0;
    if (mismatches != nullptr && (!same || !next_good)) {
      std::fprintf(mismatches, "%s,%s,%s,logged=%s %s %s,mine=%s %.3f %.3f,next_err=%.4f/%.2f,phys_err=%.4f/%.2f\n",
                   r.str("id").c_str(), r.str("tags").c_str(), r.str("src").c_str(), logged.c_str(),
                   r.str("g_p1").c_str(), r.str("g_p2").c_str(), mine.c_str(), c.p1, c.p2, e.pos, e.body, pe.pos,
                   pe.body);
    }
  }
  if (mismatches != nullptr) {
    std::fclose(mismatches);
  }
  EXPECT_LT(skipped, 150) << "rows without a goalie";
  const double n = static_cast<double>(rows.size() - skipped);
  std::printf("goalie command: kind %.1f %%, kind and parameters %.1f %% of %.0f rows (%d without a goalie left out)\n",
              100.0 * kind_ok / n, 100.0 * cmd_ok / n, n, skipped);
  for (const auto& [kind, k] : by_kind) {
    std::printf("  %-7s %4d rows: kind %5.1f %%, with parameters %5.1f %%\n", kind.c_str(), k[0], 100.0 * k[1] / k[0],
                100.0 * k[2] / k[0]);
  }
  std::printf("goalie next state within 0.01 m and 0.5 deg: %.1f %% deciding, %.1f %% replaying its command\n",
              100.0 * next_ok / n, 100.0 * physics_ok / n);
  EXPECT_GE(kind_ok, 0.998 * n);
  EXPECT_GE(cmd_ok, 0.998 * n);
  EXPECT_GE(next_ok, 0.99 * n);
  EXPECT_GE(physics_ok, 0.99 * n);
}

// Whole episodes (tests/data/hfo-real-goalie-episodes.csv: episodes 1-50 of scripted_s401,
// every cycle): each starts from its recorded t = 0 state, the attacker's recorded commands
// are replayed as the server received them, and the embedded goalie plays. With noise off the
// real game is deterministic, so the goalie's path and the outcome must follow the recording
// for as long as its decisions do. Measured: the goalie within 0.01 m of its recorded position
// in 100.0 % of all cycles and the same outcome in 45 of the 50 episodes; the bounds guard that.
TEST(HfoGoalieRealData, WholeEpisodesFollowTheRecording) {
  const std::vector<CsvRow> rows =
      testing::load_csv_rows(std::string(PAMDP_REAL_DATA_DIR) + "/hfo-real-goalie-episodes.csv");
  ASSERT_EQ(rows.size(), 3740U) << "tests/data/hfo-real-goalie-episodes.csv is missing or truncated";
  static const std::map<std::string, int> kStatus{{"IN_GAME", kInGame},
                                                  {"GOAL", kGoal},
                                                  {"CAPTURED_BY_DEFENSE", kCapturedByDefense},
                                                  {"OUT_OF_BOUNDS", kOutOfBounds},
                                                  {"OUT_OF_TIME", kOutOfTime}};
  int cycles = 0;
  int close = 0;
  int episodes = 0;
  int same_outcome = 0;
  size_t i = 0;
  while (i < rows.size()) {
    const std::string ep = rows[i].str("ep");
    SoccerSim sim = sim_at(rows[i], true);
    int status = kInGame;
    int recorded = kInGame;
    for (; i < rows.size() && rows[i].str("ep") == ep; ++i) {
      const CsvRow& r = rows[i];
      recorded = kStatus.at(r.str("n_status"));
      if (status != kInGame) {
        continue;  // our episode already ended: the rest of the recording is not comparable
      }
      sim.command_as_received(0, r.str("a_cmd").c_str(), r.num("a_p1"), r.num("a_p2"));
      status = sim.step();
      const NextErrors e = goalie_error(sim, r);
      ++cycles;
      // Open loop: the attacker's recorded commands act on our state, which the goalie changes
      // only through collisions and catches.
      close += e.pos <= 0.01 ? 1 : 0;
    }
    ++episodes;
    same_outcome += status == recorded ? 1 : 0;
  }
  std::printf("whole episodes: goalie within 0.01 m in %.1f %% of %d cycles; same outcome in %d of %d episodes\n",
              100.0 * close / cycles, cycles, same_outcome, episodes);
  EXPECT_EQ(episodes, 50);
  EXPECT_GE(close, 0.998 * cycles);
  EXPECT_GE(same_outcome, 45);
}

}  // namespace
}  // namespace pamdp::hfo
