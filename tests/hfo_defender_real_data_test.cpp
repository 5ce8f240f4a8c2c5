// agent2d's field defenders (envs/hfo/defender.hpp) against the real server's, one recorded
// cycle at a time (tests/data/hfo-real-defense-{1v2,2v2,1v3}.csv, tools/hfo-record): from each
// recorded state, the defender's decision against the one its own .dcl log names and the body
// command the server's .rcl log holds. Prints the agreement; the floors below are what the
// defender reaches today, so that a change that loses agreement fails (issue 83's target is 97 %
// of command kinds).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "csv_rows.hpp"
#include "envs/hfo/defender.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {
namespace {

using testing::CsvRow;

PlayerState player_at(const CsvRow& r, const std::string& p, bool has_effort) {
  PlayerState s;
  s.pos = {r.num(p + "_x"), r.num(p + "_y")};
  s.vel = {r.num(p + "_vx"), r.num(p + "_vy")};
  s.body_deg = r.num(p + "_body");
  s.stamina = r.num(p + "_stamina");
  if (has_effort) {
    s.effort = r.num(p + "_effort");
    s.recovery = r.num(p + "_recovery");
  }
  return s;
}

const char* kind_name(agent2d::Command::Kind k) {
  switch (k) {
    case agent2d::Command::Kind::kDash: return "DASH";
    case agent2d::Command::Kind::kTurn: return "TURN";
    case agent2d::Command::Kind::kKick: return "KICK";
    case agent2d::Command::Kind::kTackle: return "TACKLE";
    case agent2d::Command::Kind::kCatch: return "CATCH";
    case agent2d::Command::Kind::kNone: break;
  }
  return "";
}

// The embedded game at a recorded row: the attackers (frozen as recorded), the goalie and the
// field defenders (a defender without a command is frozen by its tackle), the ball; noise off.
SoccerSim game_at(const CsvRow& r, int agents, int field_defenders) {
  SoccerSimConfig cfg;
  cfg.noise = false;
  cfg.offense_agents = agents;
  cfg.goalie = true;
  cfg.field_defenders = field_defenders;
  SoccerSim sim(cfg, 1);
  std::vector<PlayerState> offense;
  for (int a = 0; a < agents; ++a) {
    PlayerState p = player_at(r, "p" + std::to_string(a), true);
    p.tackle_cycles = static_cast<int>(r.num("p" + std::to_string(a) + "_frozen"));
    offense.push_back(p);
  }
  sim.set_state(offense, BallState{{r.num("bx"), r.num("by")}, {r.num("bvx"), r.num("bvy")}});
  PlayerState g = player_at(r, "g", true);
  g.tackle_cycles = static_cast<int>(r.num("g_frozen"));
  sim.set_goalie(g);
  for (int k = 0; k < field_defenders; ++k) {
    const std::string d = "d" + std::to_string(k + 1);
    PlayerState p = player_at(r, d, false);
    const std::string cmd = r.str(d + "_cmd");
    p.tackle_cycles = cmd.empty() || cmd == "NONE" ? 1 : 0;
    sim.set_defender(k, p);
  }
  return sim;
}

// Sends every attacker's recorded command of row `r` (a tackle's outcome from row `next`'s flags).
void send_attackers(SoccerSim& sim, const CsvRow& r, const CsvRow* next, int agents) {
  for (int a = 0; a < agents; ++a) {
    const std::string p = "p" + std::to_string(a);
    const std::string cmd = r.str(p + "_cmd");
    if (cmd.empty()) {
      continue;
    }
    std::optional<bool> tackle_ok;
    if (cmd == "TACKLE" && next != nullptr) {
      // The next row's flags: 0x1000 a tackle, 0x2000 its fault (as hfo_team_real_data_test reads them).
      const long flags = std::stol(next->str(p + "_state"), nullptr, 16);
      tackle_ok = (flags & 0x1000) != 0 && (flags & 0x2000) == 0;
    }
    sim.command_as_received(a, cmd.c_str(), r.num(p + "_c1"), r.num(p + "_c2"), tackle_ok);
  }
}

// The .dcl label's rule, in DefenderDecision's terms.
const char* rule_of_label(const std::string& label) {
  if (label.rfind("BasicMove", 0) == 0) {
    return "move";
  }
  if (label.rfind("Intercept", 0) == 0 || label.rfind("WaitTurn", 0) == 0) {
    return "intercept";  // Body_Intercept2009 and its doWaitTurn
  }
  if (label.rfind("BasicFoul", 0) == 0 || label.rfind("BasicTackle", 0) == 0) {
    return "tackle";
  }
  if (label == "ChainAction" || label.rfind("Chain:Turn:Keep", 0) == 0 || label == "IntentionTurnToForward") {
    return "turn-forward";  // Bhv_ChainAction::doTurnToForward and its IntentionTurnTo
  }
  if (label.rfind("NormalDribbleQ", 0) == 0) {
    return "dribble-queue";  // IntentionNormalDribble: the self-pass's queued turns and dashes
  }
  if (label.find("dribble|SelfPass") != std::string::npos) {
    return "self-pass";  // the chain action's self-pass, fresh or after a cancelled dribble
  }
  // hold, short dribble, pass, clear: the chain action with the ball kickable, and the dribble's
  // queued intention (NormalDribble…) in the cycles after it.
  return "kick";
}

// The recordings in tests/data, or the full ones behind them: PAMDP_DEFENSE_DATA_DIR names a
// folder holding files of the same names (tools/hfo-record's cycles.csv of each setting, joined).
std::string data_path(const std::string& file) {
  if (const char* dir = std::getenv("PAMDP_DEFENSE_DATA_DIR")) {
    return std::string(dir) + "/" + file;
  }
  return std::string(PAMDP_TEST_DATA_DIR) + "/data/" + file;
}

const char* rule_name(DefenderDecision::Rule r) {
  switch (r) {
    case DefenderDecision::Rule::kBasicMove: return "move";
    case DefenderDecision::Rule::kIntercept: return "intercept";
    case DefenderDecision::Rule::kTackle: return "tackle";
    case DefenderDecision::Rule::kKick: return "kick";
    case DefenderDecision::Rule::kSelfPass: return "self-pass";
    case DefenderDecision::Rule::kDribbleQueue: return "dribble-queue";
    case DefenderDecision::Rule::kTurnForward: return "turn-forward";
    case DefenderDecision::Rule::kFrozen: break;
  }
  return "frozen";
}

struct Tally {
  int cycles = 0;
  int kind = 0;
  int command = 0;  // the same kind and parameters (within 0.1; a kick's kind only)
  int rule = 0;
  int move_rows = 0;
  int target = 0;
  int force_kicks = 0;  // SamplePlayer::doForceKick's kicks, their power and direction checked
  int force_kicks_ok = 0;
  int self_passes = 0;  // the chain action's self-pass kicks, their power and direction checked
  int self_passes_ok = 0;
  int chain_kicks = 0;  // every chain-action kick, and those where the choice (self-pass or not) matches
  int chain_kicks_same_rule = 0;
};

// Each field defender's memory (its queued intention, Strategy's recover mode), carried from its
// own decision on the row before within an episode's consecutive cycles.
class DefenderMemory {
 public:
  // Forgets everything at a new episode or a gap in the cycles; returns the row's cycle.
  int at(const CsvRow& r) {
    const std::string episode = r.str("src") + "/" + r.str("ep");
    const int cycle = static_cast<int>(r.num("t"));
    if (episode != episode_ || cycle != cycle_ + 1) {
      kept_.fill({});
    }
    episode_ = episode;
    cycle_ = cycle;
    return cycle;
  }
  void give(int k, PlayerState* d) const {
    d->intention = kept_[static_cast<size_t>(k)].intention;
    d->recover_mode = kept_[static_cast<size_t>(k)].recover_mode;
  }
  void keep(int k, const PlayerState::Intention& intention, bool recover_mode) {
    kept_[static_cast<size_t>(k)] = {intention, recover_mode};
  }

 private:
  struct Kept {
    PlayerState::Intention intention;
    bool recover_mode = false;
  };
  std::array<Kept, 2> kept_{};
  std::string episode_;
  int cycle_ = -10;
};

Tally replay(const std::string& file, int agents, int field_defenders, bool verbose) {
  const std::vector<CsvRow> rows = testing::load_csv_rows(data_path(file));
  EXPECT_FALSE(rows.empty()) << file;
  Tally t;
  int shown = 0;
  DefenderMemory memory;
  for (const CsvRow& r : rows) {
    if (r.str("status") != "IN_GAME") {
      continue;
    }
    SoccerState s;
    s.cycle = memory.at(r);
    s.num_players = 0;
    for (int a = 0; a < agents; ++a) {
      PlayerState p = player_at(r, "p" + std::to_string(a), true);
      p.tackle_cycles = static_cast<int>(r.num("p" + std::to_string(a) + "_frozen"));  // as game_at does
      s.players[static_cast<size_t>(s.num_players++)] = p;
    }
    PlayerState g = player_at(r, "g", true);
    g.tackle_cycles = static_cast<int>(r.num("g_frozen"));
    g.team = Team::kDefense;
    g.goalie = true;
    s.players[static_cast<size_t>(s.num_players++)] = g;
    const int first_defender = s.num_players;
    for (int k = 1; k <= field_defenders; ++k) {
      PlayerState d = player_at(r, "d" + std::to_string(k), false);
      d.team = Team::kDefense;
      memory.give(k - 1, &d);
      s.players[static_cast<size_t>(s.num_players++)] = d;
    }
    s.ball.pos = {r.num("bx"), r.num("by")};
    s.ball.vel = {r.num("bvx"), r.num("bvy")};
    for (int k = 1; k <= field_defenders; ++k) {
      const std::string d = "d" + std::to_string(k);
      const std::string cmd = r.str(d + "_cmd");
      if (cmd.empty() || cmd == "NONE") {
        continue;  // frozen by its tackle (the recording says so only through the missing command)
      }
      const DefenderDecision dec = decide_defender(s, first_defender + k - 1, k + 1, false);
      memory.keep(k - 1, dec.intention, dec.recover_mode);
      ++t.cycles;
      const bool kind_ok = cmd == kind_name(dec.command.kind);
      t.kind += kind_ok ? 1 : 0;
      const std::string label = r.str(d + "_label");
      // A kick's parameters are checked where they are modelled: the simultaneous kick and the
      // self-pass, not the hold's or the other chain actions'.
      const bool self_pass = std::string(rule_of_label(label)) == "self-pass";
      const bool params_checked = cmd != "KICK" || label.rfind("SimultaneousKick", 0) == 0 || self_pass;
      const bool params_ok =
          kind_ok && (!params_checked ||
                      (std::fabs(dec.command.p1 - r.num(d + "_c1")) < 0.1 &&
                       (cmd == "TURN" || cmd == "TACKLE" || std::fabs(dec.command.p2 - r.num(d + "_c2")) < 0.1)));
      t.command += params_ok ? 1 : 0;
      if (label.rfind("SimultaneousKick", 0) == 0) {
        ++t.force_kicks;
        t.force_kicks_ok += params_ok ? 1 : 0;
      }
      if (self_pass) {
        ++t.self_passes;
        t.self_passes_ok += params_ok ? 1 : 0;
      }
      if (cmd == "KICK" && label.rfind("SimultaneousKick", 0) != 0) {
        ++t.chain_kicks;
        t.chain_kicks_same_rule += std::string(rule_of_label(label)) == rule_name(dec.rule) ? 1 : 0;
      }
      const bool rule_ok = std::string(rule_of_label(label)) == rule_name(dec.rule);
      t.rule += rule_ok ? 1 : 0;
      if (label.rfind("BasicMove", 0) == 0 && dec.rule == DefenderDecision::Rule::kBasicMove) {
        ++t.move_rows;
        const double err = std::hypot(dec.target.x - r.num(d + "_tx"), dec.target.y - r.num(d + "_ty"));
        t.target += err < 0.01 ? 1 : 0;
      }
      if (verbose && (!params_ok || !rule_ok) && shown < 60) {
        ++shown;
        std::printf("%s ep %s t %s %s: real %s %s %s [%s] target (%s, %s); ours %s %.3f %.3f [%s] (%.3f, %.3f)\n",
                    file.c_str(), r.str("ep").c_str(), r.str("t").c_str(), d.c_str(), cmd.c_str(),
                    r.str(d + "_c1").c_str(), r.str(d + "_c2").c_str(), label.c_str(), r.str(d + "_tx").c_str(),
                    r.str(d + "_ty").c_str(), kind_name(dec.command.kind), dec.command.p1, dec.command.p2,
                    rule_name(dec.rule), dec.target.x, dec.target.y);
      }
    }
  }
  std::printf(
      "%s: %d defender cycles; command kind %.1f %%, command %.1f %%, rule %.1f %%, home position within 1 cm %.1f "
      "%% of %d; simultaneous kicks with their power and direction %d of %d; self-passes %d of %d; chain action "
      "chosen %d of %d\n",
      file.c_str(), t.cycles, 100.0 * t.kind / std::max(1, t.cycles), 100.0 * t.command / std::max(1, t.cycles),
      100.0 * t.rule / std::max(1, t.cycles), 100.0 * t.target / std::max(1, t.move_rows), t.move_rows,
      t.force_kicks_ok, t.force_kicks, t.self_passes_ok, t.self_passes, t.chain_kicks_same_rule, t.chain_kicks);
  return t;
}

// Issue 83's target is 97 % of command kinds; these floors sit just under today's figures.
void expect_agreement(const Tally& t) {
  const double n = std::max(1, t.cycles);
  EXPECT_GE(t.kind / n, 0.99);
  EXPECT_GE(t.command / n, 0.985);
  EXPECT_GE(t.rule / n, 0.98);
  EXPECT_GE(static_cast<double>(t.target) / std::max(1, t.move_rows), 0.985);
  EXPECT_EQ(t.force_kicks_ok, t.force_kicks);  // librcsc's Body_KickOneStep, to 0.1 in power and direction
  // The chain action's choice (self-pass, turn to forward, or neither) on 97.1 % of the full
  // recordings' 837 chain-action kicks; the self-pass's kick exact on 514 of their 518.
  EXPECT_GE(t.chain_kicks_same_rule, 0.9 * t.chain_kicks);
  EXPECT_GE(t.self_passes_ok, 0.95 * t.self_passes);
}

// The embedded game stepped from each recorded state: the attackers send their recorded
// commands, the goalie and the field defenders decide for themselves (SoccerSim with
// field_defenders), and every field defender's next position, velocity and body must match the
// next recorded row (0.01 m, 0.01 m/cycle, 0.5 deg). Issue 83's target: 97 %.
struct Stepped {
  int defender_cycles = 0;
  int defender_ok = 0;
  int rows = 0;
  int all_ok = 0;  // every object (ball, attackers, goalie, defenders)
};

Stepped step_game(const std::string& file, int agents, int field_defenders, bool verbose) {
  const std::vector<CsvRow> rows = testing::load_csv_rows(data_path(file));
  Stepped out;
  int shown = 0;
  DefenderMemory memory;
  for (size_t i = 0; i + 1 < rows.size(); ++i) {
    const CsvRow& r = rows[i];
    const CsvRow& n = rows[i + 1];
    if (r.str("status") != "IN_GAME" || n.str("src") != r.str("src") || n.str("ep") != r.str("ep") || r.num("t") < 2) {
      continue;  // the reset cycles and the last row of an episode
    }
    SoccerSim sim = game_at(r, agents, field_defenders);
    sim.mutable_state().cycle = memory.at(r);
    for (int k = 0; k < field_defenders; ++k) {
      memory.give(k, &sim.mutable_state().players[static_cast<size_t>(sim.defender_index(k))]);
    }
    send_attackers(sim, r, &n, agents);
    sim.step();
    for (int k = 0; k < field_defenders; ++k) {
      const PlayerState& d = sim.state().players[static_cast<size_t>(sim.defender_index(k))];
      memory.keep(k, d.intention, d.recover_mode);
    }
    ++out.rows;
    const SoccerState& s = sim.state();
    const auto same = [&](const PlayerState& p, const std::string& col) {
      return std::hypot(p.pos.x - n.num(col + "_x"), p.pos.y - n.num(col + "_y")) <= 0.01 &&
             std::hypot(p.vel.x - n.num(col + "_vx"), p.vel.y - n.num(col + "_vy")) <= 0.01 &&
             std::fabs(wrap_deg(p.body_deg - n.num(col + "_body"))) <= 0.5;
    };
    bool all = std::hypot(s.ball.pos.x - n.num("bx"), s.ball.pos.y - n.num("by")) <= 0.01;
    for (int a = 0; a < agents; ++a) {
      all = all && same(s.players[static_cast<size_t>(a)], "p" + std::to_string(a));
    }
    all = all && same(s.players[static_cast<size_t>(sim.goalie_index())], "g");
    for (int k = 0; k < field_defenders; ++k) {
      const std::string d = "d" + std::to_string(k + 1);
      const PlayerState& p = s.players[static_cast<size_t>(sim.defender_index(k))];
      const bool ok = same(p, d);
      ++out.defender_cycles;
      out.defender_ok += ok ? 1 : 0;
      all = all && ok;
      if (!ok && verbose && shown < 30) {
        ++shown;
        std::printf(
            "%s ep %s t %s %s: next (%.4f, %.4f) body %.2f, real (%s, %s) body %s; cmd real %s %s, ours %s %.3f\n",
            file.c_str(), r.str("ep").c_str(), r.str("t").c_str(), d.c_str(), p.pos.x, p.pos.y, p.body_deg,
            n.str(d + "_x").c_str(), n.str(d + "_y").c_str(), n.str(d + "_body").c_str(), r.str(d + "_cmd").c_str(),
            r.str(d + "_c1").c_str(), kind_name(static_cast<agent2d::Command::Kind>(sim.last_defender_command(k).kind)),
            sim.last_defender_command(k).p1);
      }
    }
    out.all_ok += all ? 1 : 0;
  }
  std::printf("%s: stepped %d cycles; each field defender's next state on %.1f %% of %d, every object's on %.1f %%\n",
              file.c_str(), out.rows, 100.0 * out.defender_ok / std::max(1, out.defender_cycles), out.defender_cycles,
              100.0 * out.all_ok / std::max(1, out.rows));
  return out;
}

void expect_next_states(const Stepped& s) {
  EXPECT_GT(s.defender_cycles, 500);
  EXPECT_GE(static_cast<double>(s.defender_ok) / std::max(1, s.defender_cycles), 0.97);
}

// Whole recorded episodes played again from their first state two cycles in: the attackers send
// their recorded commands, the defense decides for itself; the episode must end as recorded
// (issue 83's target: 90 %). Commands that no longer fit a game drifted away are sent as recorded.
struct Endings {
  int episodes = 0;
  int same = 0;
};

Endings play_episodes(const std::string& file, int agents, int field_defenders, bool verbose) {
  const std::vector<CsvRow> rows = testing::load_csv_rows(data_path(file));
  Endings out;
  size_t i = 0;
  while (i < rows.size()) {
    size_t end = i;
    while (end + 1 < rows.size() && rows[end + 1].str("src") == rows[i].str("src") &&
           rows[end + 1].str("ep") == rows[i].str("ep")) {
      ++end;
    }
    const std::string recorded = rows[end].str("status");
    size_t first = i;
    while (first <= end && rows[first].num("t") < 2) {
      ++first;
    }
    if (first <= end && recorded != "IN_GAME" && rows[first].str("status") == "IN_GAME") {
      const CsvRow& r = rows[first];
      SoccerSim sim = game_at(r, agents, field_defenders);
      // The referee's counters at this state: the ball untouched since the reset, nobody held.
      sim.mutable_state().cycle = static_cast<int>(r.num("t"));
      sim.mutable_state().untouched = static_cast<int>(r.num("t"));
      int status = kInGame;
      for (size_t k = first; k <= end && status == kInGame; ++k) {
        send_attackers(sim, rows[k], k + 1 <= end ? &rows[k + 1] : nullptr, agents);
        status = sim.step();
      }
      ++out.episodes;
      const bool same = status_name(status) == recorded;
      out.same += same ? 1 : 0;
      if (!same && verbose) {
        std::printf("%s ep %s: recorded %s after %zu cycles, embedded %s\n", file.c_str(), r.str("ep").c_str(),
                    recorded.c_str(), end - first + 1, status_name(status));
      }
    }
    i = end + 1;
  }
  std::printf("%s: %d of %d whole episodes end as recorded (%.1f %%)\n", file.c_str(), out.same, out.episodes,
              100.0 * out.same / std::max(1, out.episodes));
  return out;
}

TEST(DefenderRealData, WholeEpisodesEndAsRecorded) {
  const bool verbose = std::getenv("PAMDP_VERBOSE") != nullptr;
  Endings all;
  for (const auto& [file, agents, defenders] :
       {std::tuple{"hfo-real-defense-1v2.csv", 1, 1}, std::tuple{"hfo-real-defense-2v2.csv", 2, 1},
        std::tuple{"hfo-real-defense-1v3.csv", 1, 2}}) {
    const Endings e = play_episodes(file, agents, defenders, verbose);
    all.episodes += e.episodes;
    all.same += e.same;
  }
  EXPECT_GE(all.episodes, 40);
  // Issue 83's target is 90 %: 49 of 52 (94.2 %) here, and 834 of 891 (93.6 %) over the full
  // recordings behind this subset (PAMDP_DEFENSE_DATA_DIR). Of the full recordings' 57 misses,
  // 46 are games the real defense captured while the embedded one, drifted from the recording
  // (the attackers' recorded commands then meet a ball that is elsewhere), is still playing when
  // the recording ends; 9 end captured on one side and out of bounds on the other. The floor
  // guards what is reached.
  EXPECT_GE(static_cast<double>(all.same) / std::max(1, all.episodes), 0.90);
}

TEST(DefenderRealData, TheGameStepsToTheRecordedDefenderStates) {
  const bool verbose = std::getenv("PAMDP_VERBOSE") != nullptr;
  expect_next_states(step_game("hfo-real-defense-1v2.csv", 1, 1, verbose));
  expect_next_states(step_game("hfo-real-defense-2v2.csv", 2, 1, verbose));
  expect_next_states(step_game("hfo-real-defense-1v3.csv", 1, 2, verbose));
}

TEST(DefenderRealData, OneAttackerAgainstTheGoalieAndAFieldDefender) {
  const Tally t = replay("hfo-real-defense-1v2.csv", 1, 1, std::getenv("PAMDP_VERBOSE") != nullptr);
  EXPECT_GT(t.cycles, 1000);
  expect_agreement(t);
}

TEST(DefenderRealData, TwoAttackersAgainstTheGoalieAndAFieldDefender) {
  const Tally t = replay("hfo-real-defense-2v2.csv", 2, 1, std::getenv("PAMDP_VERBOSE") != nullptr);
  EXPECT_GT(t.cycles, 500);
  expect_agreement(t);
}

TEST(DefenderRealData, OneAttackerAgainstTheGoalieAndTwoFieldDefenders) {
  const Tally t = replay("hfo-real-defense-1v3.csv", 1, 2, std::getenv("PAMDP_VERBOSE") != nullptr);
  EXPECT_GT(t.cycles, 1000);
  expect_agreement(t);
}

}  // namespace
}  // namespace pamdp::hfo
