// Replays every single-step transition recorded from the real HFO server (noise off,
// tests/data/hfo-real-transitions.csv, a copy of shared/data) through SoccerSim and compares the next state.
// Requirement: >= 99% of rows within 0.01 m, 0.01 m/cycle and 0.5 deg. A faithful
// implementation of the reference gets all of them, so the test also reports every miss.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "csv_rows.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {
namespace {

using Row = testing::CsvRow;

std::vector<Row> load_rows(const std::string& path) {
  return testing::load_csv_rows(path);
}

int status_code(const std::string& s) {
  static const std::map<std::string, int> kCodes{
      {"IN_GAME", kInGame}, {"GOAL", kGoal}, {"OUT_OF_BOUNDS", kOutOfBounds}, {"OUT_OF_TIME", kOutOfTime}};
  return kCodes.at(s);
}

struct Errors {
  double pos = 0.0;
  double vel = 0.0;
  double body = 0.0;
  double stamina = 0.0;
  bool status_ok = true;
};

Errors replay(const Row& r, uint64_t seed) {
  SoccerSimConfig cfg;
  cfg.noise = false;
  SoccerSim sim(cfg, seed);
  PlayerState agent;
  agent.pos = {r.num("ax"), r.num("ay")};
  agent.vel = {r.num("avx"), r.num("avy")};
  agent.body_deg = r.num("body");
  agent.stamina = r.num("stamina");
  BallState ball{{r.num("bx"), r.num("by")}, {r.num("bvx"), r.num("bvy")}};
  sim.set_state(agent, ball);

  const std::string& action = r.str("action");
  const double p1 = r.num("p1");
  const double p2 = r.num("p2");
  if (action == "DASH") {
    sim.dash(p1, p2);
  } else if (action == "TURN") {
    sim.turn(p1);
  } else if (action == "KICK") {
    sim.kick(p1, p2);
  } else if (action == "TACKLE") {
    sim.tackle(p1);
  }
  const int status = sim.step();

  const PlayerState& a = sim.agent();
  const BallState& b = sim.state().ball;
  Errors e;
  e.pos = std::max({std::fabs(a.pos.x - r.num("n_ax")), std::fabs(a.pos.y - r.num("n_ay")),
                    std::fabs(b.pos.x - r.num("n_bx")), std::fabs(b.pos.y - r.num("n_by"))});
  e.vel = std::max({std::fabs(a.vel.x - r.num("n_avx")), std::fabs(a.vel.y - r.num("n_avy")),
                    std::fabs(b.vel.x - r.num("n_bvx")), std::fabs(b.vel.y - r.num("n_bvy"))});
  e.body = std::fabs(wrap_deg(a.body_deg - r.num("n_body")));
  e.stamina = std::fabs(a.stamina - r.num("n_stamina"));
  // The referee's counters are not in the data; GOAL and OUT_OF_BOUNDS follow from the state.
  const int expected = status_code(r.str("n_status"));
  if (expected != kOutOfTime) {
    e.status_ok = status == expected;
  }
  return e;
}

TEST(HfoRealData, ReplaysRealServerTransitions) {
  const std::vector<Row> rows = load_rows(std::string(PAMDP_REAL_DATA_DIR) + "/hfo-real-transitions.csv");
  ASSERT_GT(rows.size(), 1000U) << "tests/data/hfo-real-transitions.csv is missing or truncated";

  std::map<std::string, std::pair<int, int>> per_kind;  // kind -> (rows, misses)
  int misses = 0;
  int status_misses = 0;
  int stamina_misses = 0;
  double max_pos = 0.0;
  double max_vel = 0.0;
  double max_body = 0.0;
  std::string report;
  for (size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    const Errors e = replay(r, 1000 + i);
    max_pos = std::max(max_pos, e.pos);
    max_vel = std::max(max_vel, e.vel);
    max_body = std::max(max_body, e.body);
    const bool ok = e.pos <= 0.01 && e.vel <= 0.01 && e.body <= 0.5;
    auto& k = per_kind[r.str("kind")];
    ++k.first;
    if (!ok) {
      ++misses;
      ++k.second;
      report += "  row " + r.str("id") + " " + r.str("kind") + " [" + r.str("tags") + "]: pos " +
                std::to_string(e.pos) + " vel " + std::to_string(e.vel) + " body " + std::to_string(e.body) + "\n";
    }
    status_misses += e.status_ok ? 0 : 1;
    stamina_misses += e.stamina <= 0.01 ? 0 : 1;
  }
  std::string summary;
  for (const auto& [kind, c] : per_kind) {
    summary += "  " + kind + ": " + std::to_string(c.first - c.second) + "/" + std::to_string(c.first) + "\n";
  }
  std::printf("real-server transitions matched per kind:\n%s", summary.c_str());
  std::printf("max error: pos %.3g m, vel %.3g m/cycle, body %.3g deg; status misses %d; stamina misses %d\n", max_pos,
              max_vel, max_body, status_misses, stamina_misses);
  if (!report.empty()) {
    std::printf("rows outside tolerance:\n%s", report.c_str());
  }
  const double match_rate = 1.0 - static_cast<double>(misses) / static_cast<double>(rows.size());
  EXPECT_GE(match_rate, 0.99) << misses << " of " << rows.size() << " rows outside tolerance";
  EXPECT_LE(status_misses, static_cast<int>(rows.size() / 100));
  EXPECT_LE(stamina_misses, static_cast<int>(rows.size() / 100));
}

}  // namespace
}  // namespace pamdp::hfo
