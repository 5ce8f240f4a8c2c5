#include <cstdio>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/cli_checks.hpp"
#include "app/commands.hpp"
#include "app/sim_options.hpp"
#include "envs/hfo/goalie.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/state_io.hpp"

namespace pamdp::app {
namespace {

struct TraceOptions {
  std::string init;
  std::string actions;
  uint64_t seed = 1;
  SimOptions sim;
};

void print_row(int step, int status, float reward, std::span<const float> obs) {
  std::printf("%d,%s,%.9g", step, hfo::status_name(status), static_cast<double>(reward));
  for (float v : obs) {
    std::printf(",%.9g", static_cast<double>(v));
  }
}

// A defense player's columns: the command it sent in the step that produced the row (in the
// server's units, as the real server's logs give them; empty on the first row and where a
// command has no such parameter; "on" as the second parameter of a foul tackle), then its state
// after that step.
void print_npc(const hfo::SoccerSim::GoalieCommandLog& c, const hfo::PlayerState& p, bool first) {
  const auto kind = static_cast<hfo::GoalieCommand::Kind>(c.kind);
  using K = hfo::GoalieCommand::Kind;
  if (first) {
    std::printf(",,,");
  } else {
    std::printf(",%s", hfo::goalie_command_name(kind));
    if (kind == K::kNone) {
      std::printf(",,");
    } else if (kind == K::kDash || kind == K::kKick) {
      std::printf(",%.9g,%.9g", c.p1, c.p2);
    } else if (kind == K::kTackle && c.foul) {
      std::printf(",%.9g,on", c.p1);
    } else {
      std::printf(",%.9g,", c.p1);
    }
  }
  std::printf(",%.9g,%.9g,%.9g,%.9g,%.9g", p.pos.x, p.pos.y, p.vel.x, p.vel.y, p.body_deg);
}

// The goalie's columns (g_cmd ... g_body).
void print_goalie(const hfo::SoccerSim& sim, bool first) {
  print_npc(sim.last_goalie_command(), sim.state().players[static_cast<size_t>(sim.goalie_index())], first);
}

// Field defender k's columns (agent2d's unum k + 2, numbered d1, d2 as in the recordings).
void print_defender(const hfo::SoccerSim& sim, int k, bool first) {
  print_npc(sim.last_defender_command(k), sim.state().players[static_cast<size_t>(sim.defender_index(k))], first);
}

// Several offense players (STATE.json with "teammates"), or field defenders ("defenders"): the
// rows are player 0's, as with one, and each ends with every offense player's state after the
// step, then the ball's, then each field defender's command and state.
void run_team_trace(const TraceOptions& o, const hfo::InitialState& init) {
  hfo::SoccerSimConfig cfg = o.sim.resolved();
  cfg.offense_agents = 1 + static_cast<int>(init.teammates.size());
  if (init.has_goalie && !cfg.goalie) {
    throw std::runtime_error(o.init + ": has a \"goalie\" object but the simulator has no goalie: add --goalie");
  }
  if (!init.defenders.empty() && !cfg.goalie) {
    throw std::runtime_error(o.init +
                             ": has \"defenders\" but the simulator has no goalie, which field defenders "
                             "need (HFO's --defense-npcs counts the goalie first): add --goalie");
  }
  cfg.field_defenders = static_cast<int>(init.defenders.size());
  const int n = cfg.offense_agents;
  const std::vector<hfo::TeamActions> rows = hfo::load_team_actions_csv(o.actions, n);
  hfo::HfoTeamEnv env(cfg);
  const auto width = static_cast<size_t>(env.observation_size());
  std::vector<float> obs(width * static_cast<size_t>(n));
  std::vector<float> rewards(static_cast<size_t>(n));
  env.reset(o.seed, obs);  // seeds the noise stream
  std::vector<hfo::PlayerState> offense{init.agent};
  offense.insert(offense.end(), init.teammates.begin(), init.teammates.end());
  env.set_state(offense, init.ball, init.has_goalie ? &init.goalie : nullptr, obs, init.defenders);
  const int defenders = cfg.field_defenders;

  std::printf("step,status,reward");
  for (size_t i = 0; i < width; ++i) {
    std::printf(",f%zu", i);
  }
  if (cfg.goalie) {
    std::printf(",g_cmd,g_p1,g_p2,g_x,g_y,g_vx,g_vy,g_body");
  }
  for (int i = 0; i < n; ++i) {
    std::printf(",p%d_x,p%d_y,p%d_vx,p%d_vy,p%d_body", i, i, i, i, i);
  }
  std::printf(",b_x,b_y,b_vx,b_vy");
  for (int k = 1; k <= defenders; ++k) {
    std::printf(",d%d_cmd,d%d_p1,d%d_p2,d%d_x,d%d_y,d%d_vx,d%d_vy,d%d_body", k, k, k, k, k, k, k, k);
  }
  std::printf("\n");
  const hfo::SoccerSim& sim = env.sim();
  auto row = [&](int step, int status, float reward, bool first) {
    print_row(step, status, reward, std::span<const float>(obs).first(width));
    if (cfg.goalie) {
      print_goalie(sim, first);
    }
    for (int i = 0; i < n; ++i) {
      const hfo::PlayerState& p = sim.state().players[static_cast<size_t>(i)];
      std::printf(",%.9g,%.9g,%.9g,%.9g,%.9g", p.pos.x, p.pos.y, p.vel.x, p.vel.y, p.body_deg);
    }
    const hfo::BallState& b = sim.state().ball;
    std::printf(",%.9g,%.9g,%.9g,%.9g", b.pos.x, b.pos.y, b.vel.x, b.vel.y);
    for (int k = 0; k < defenders; ++k) {
      print_defender(sim, k, first);
    }
    std::printf("\n");
  };
  row(0, hfo::kInGame, 0.0F, true);
  std::vector<ParamAction> actions(static_cast<size_t>(n));
  int step = 0;
  for (const auto& r : rows) {
    for (int i = 0; i < n; ++i) {
      actions[static_cast<size_t>(i)] = {r[static_cast<size_t>(i)].id, r[static_cast<size_t>(i)].params};
    }
    const int status = env.step(actions, obs, rewards);
    row(++step, status, rewards[0], false);
    if (status != hfo::kInGame) {
      if (static_cast<size_t>(step) < rows.size()) {
        std::fprintf(stderr, "pamdp sim trace: episode ended (%s) after %d of %zu action rows; the rest were not run\n",
                     hfo::status_name(status), step, rows.size());
      }
      break;
    }
  }
}

void run_trace(const TraceOptions& o) {
  const hfo::InitialState init = hfo::load_state_json(o.init);
  if (!init.teammates.empty() || !init.defenders.empty()) {
    run_team_trace(o, init);
    return;
  }
  const std::vector<hfo::ScriptedAction> actions = hfo::load_actions_csv(o.actions);
  const hfo::SoccerSimConfig cfg = o.sim.resolved();
  if (init.has_goalie && !cfg.goalie) {
    throw std::runtime_error(o.init + ": has a \"goalie\" object but the simulator has no goalie: add --goalie");
  }
  hfo::HfoEnv env(cfg);
  std::vector<float> obs(static_cast<size_t>(env.observation_size()));
  std::vector<float> discard(obs.size());
  env.reset(o.seed, discard);  // seeds the noise stream
  if (init.has_goalie) {
    env.set_state(init.agent, init.ball, init.goalie, obs);
  } else {
    env.set_state(init.agent, init.ball, obs);
  }

  std::printf("step,status,reward");
  for (size_t i = 0; i < obs.size(); ++i) {
    std::printf(",f%zu", i);
  }
  if (cfg.goalie) {
    std::printf(",g_cmd,g_p1,g_p2,g_x,g_y,g_vx,g_vy,g_body");
  }
  std::printf("\n");
  auto end_row = [&](bool first) {
    if (cfg.goalie) {
      print_goalie(env.sim(), first);
    }
    std::printf("\n");
  };
  print_row(0, hfo::kInGame, 0.0F, obs);
  end_row(true);
  int step = 0;
  for (const auto& a : actions) {
    const StepResult r = env.step({a.id, a.params}, obs);
    print_row(++step, r.status, r.reward, obs);
    end_row(false);
    if (r.terminal()) {
      if (static_cast<size_t>(step) < actions.size()) {
        std::fprintf(stderr, "pamdp sim trace: episode ended (%s) after %d of %zu actions; the rest were not run\n",
                     hfo::status_name(r.status), step, actions.size());
      }
      break;
    }
  }
}

}  // namespace

void register_sim(CLI::App& app) {
  CLI::App* sim = app.add_subcommand("sim", "the embedded HFO simulator");
  sim->require_subcommand(1);
  auto opts = std::make_shared<TraceOptions>();
  CLI::App* trace = sim->add_subcommand(
      "trace",
      "replay an action script from a given state and print step,status,reward,f0..f57 as CSV (with --goalie: "
      "f0..f65, then the goalie's command and state g_cmd,g_p1,g_p2,g_x,g_y,g_vx,g_vy,g_body; with teammates in "
      "STATE.json: player 0's reward and features, 8 more per other player, then every offense player's state "
      "p0_x,p0_y,p0_vx,p0_vy,p0_body,p1_x,... and the ball's b_x,b_y,b_vx,b_vy; with defenders in STATE.json (and "
      "--goalie), the same team columns, then per field defender d1_cmd,d1_p1,d1_p2,d1_x,d1_y,d1_vx,d1_vy,d1_body, "
      "d2_...)");
  trace
      ->add_option(
          "--init", opts->init,
          "STATE.json: {agent: {x, y, vx, vy, body_deg, stamina}, ball: {x, y, vx, vy}, "
          "teammates (optional: the other offense players, 1-3): [{x, y, vx, vy, body_deg, stamina}, ...], "
          "goalie (optional, with --goalie): {x, y, vx, vy, body_deg, stamina, since_catch, tackle_cycles, caught}, "
          "defenders (optional, with --goalie: agent2d's field defenders, 1-2): [{x, y, vx, vy, body_deg, stamina, "
          "tackle_cycles, recover_mode, intention: {kind: dribble|turn_to_forward, x, y, turns, dashes}}, ...]}")
      ->required()
      ->check(existing_file("give a STATE.json (an example: tests/golden/kick_to_goal.state.json)"));
  trace
      ->add_option("--actions", opts->actions,
                   "ACTIONS.csv: rows DASH,power,dir | TURN,dir | TACKLE,dir | KICK,power,dir; with teammates one "
                   "action per offense player in a row, in player order, separated by '|' (DASH,80,0|KICK,60,-20)")
      ->required()
      ->check(existing_file("give an ACTIONS.csv (an example: tests/golden/kick_to_goal.actions.csv)"));
  trace->add_option("--seed", opts->seed, "seed of the noise stream")->capture_default_str();
  opts->sim.add_to(*trace);
  trace->callback([opts] { run_trace(*opts); });
}

}  // namespace pamdp::app
