#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "envs/hfo/features.hpp"
#include "envs/hfo/settings.hpp"
#include "envs/hfo/soccer_sim.hpp"
#include "envs/hfo_server/hfo_server_env.hpp"
#include "envs/hfo_server/lockstep_team.hpp"
#include "envs/registry.hpp"

namespace pamdp {
namespace hfo_server {
namespace {

constexpr const char* kEncodingNames[] = {"native", "embedded"};

// env.server_agents players of one server, each a one-player env: one env, or a lockstep team.
std::unique_ptr<Env> make_server_players(const EnvParams& p) {
  const HfoServerConfig config = server_config(p);
  const int64_t agents = p.integer("server_agents");
  const int64_t offense = p.integer("offense_agents");
  if (agents > offense) {
    throw std::runtime_error("env.server_agents = " + std::to_string(agents) +
                             ": this env would play more agents than "
                             "the server has (env.offense_agents = " +
                             std::to_string(offense) +
                             ", bin/HFO --offense-agents); set env.server_agents to at most " +
                             std::to_string(offense));
  }
  if (agents == 1) {
    return make_hfo_server_env(config);
  }
  std::vector<std::unique_ptr<Env>> players;
  for (int64_t i = 0; i < agents; ++i) {
    HfoServerConfig player = config;
    player.join_delay_ms = static_cast<int>(i * p.integer("server_join_interval_ms"));
    players.push_back(make_hfo_server_env(player));
  }
  return std::make_unique<LockstepTeamEnv>(std::move(players), p.boolean("team_reward"));
}

}  // namespace

HfoServerConfig server_config(const EnvParams& p) {
  HfoServerConfig s;
  s.host = p.text("server_host");
  s.port = static_cast<int>(p.integer("server_port"));
  s.encoding = p.text("server_encoding") == "embedded" ? Encoding::kEmbedded : Encoding::kNative;
  s.team = p.text("server_team");
  s.config_dir = p.text("server_config_dir");
  s.opponents = hfo::defense_players(p);
  s.teammates = static_cast<int>(p.integer("offense_agents")) - 1;
  s.max_steps = static_cast<int>(p.integer("max_steps"));
  s.connect_timeout_s = static_cast<int>(p.integer("server_connect_timeout_s"));
  s.shoot_action = p.boolean("shoot_action");
  return s;
}

}  // namespace hfo_server

void register_hfo_server_env(EnvRegistry& registry) {
  const hfo_server::HfoServerConfig d;
  EnvRegistration r;
  r.name = "hfo-server";
  r.description =
      "the real HFO server through its C++ client (a build with -DHFO_ROOT; the server's own flags set up the game, "
      "docs/hfo-server.md)";
  // Of the embedded simulator's keys, goalie says the server runs one (bin/HFO --defense-npcs 1),
  // max_steps is its --frames-per-trial and shoot_action adds SHOOT, sent as a KICK.
  r.keys = {hfo::goalie_key(), hfo::defense_npcs_key(), hfo::max_steps_key(), EnvKey::text("server_host", d.host),
            EnvKey::integer("server_port", d.port, 1, 65535),
            // The server of the greedy evaluations that `pamdp train` and `pamdp learner` run; 0 = none.
            EnvKey::integer("server_eval_port", 0, 0, 65535),
            EnvKey::choice("server_encoding", hfo_server::kEncodingNames[static_cast<int>(d.encoding)],
                           {hfo_server::kEncodingNames[0], hfo_server::kEncodingNames[1]}),
            EnvKey::text("server_team", d.team), EnvKey::text_or_empty("server_config_dir", d.config_dir),
            EnvKey::integer("server_connect_timeout_s", d.connect_timeout_s, 1, 3600), hfo::shoot_action_key(),
            // bin/HFO --offense-agents N: this env plays env.server_agents of the N (each on a thread
            // of its own, in lockstep: a team env); the others are other processes.
            hfo::offense_agents_key(), EnvKey::integer("server_agents", 1, 1, hfo::kMaxOffenseAgents),
            // With env.server_agents > 1: every player earns the team's mean shaped reward (as env 'hfo').
            EnvKey::boolean("team_reward", false),
            // With env.server_agents > 1: player i joins i times this many ms after player 0.
            // Measured: 0.7 s from one agent's join to the trainer's wait for the next, 3 NPC
            // slots apart, on 2 cores with one training run beside it (docs/hfo-server.md).
            EnvKey::integer("server_join_interval_ms", 3000, 0, 600000)};
  r.make = [](const EnvParams& p) { return hfo_server::make_server_players(p); };
  r.observation_size = [](const EnvParams& p) { return hfo_server::observation_size(hfo_server::server_config(p)); };
  r.gives_embedded_hfo_features = [](const EnvParams& p) { return p.text("server_encoding") == "embedded"; };
  r.use_embedded_hfo_features = [](EnvParams& p) {
    p.set("server_encoding", std::string("embedded"));
    return std::string("env.server_encoding = embedded");
  };
  // Greedy evaluations beside training need a server of their own, asked for only when they run.
  r.eval_params = [](const EnvParams& p, bool evaluating) {
    const int64_t eval_port = p.integer("server_eval_port");
    if (!evaluating) {
      return p;
    }
    if (eval_port == 0 || eval_port == p.integer("server_port")) {
      throw std::runtime_error(
          "greedy evaluations on env 'hfo-server' (train.eval_episodes > 0) need an HFO server of their own: start "
          "one and set env.server_eval_port to its port, or set train.eval_episodes=0");
    }
    EnvParams e = p;
    e.set("server_port", eval_port);
    return e;
  };
  r.location = [](const EnvParams& p) {
    return " at " + p.text("server_host") + ":" + std::to_string(p.integer("server_port"));
  };
  r.hfo_actions = true;
  r.action_gates = {{"KICK", hfo::feat::kKickable}};  // the real server's feature 12, as the embedded one
  r.max_per_process = 1;
  r.max_per_process_note =
      "plays one HFO server per actor; start one actor per server, each with --envs 1 --server-port PORT";
  registry.add(std::move(r));
}

}  // namespace pamdp
