// The real HFO server (LARG/HFO with its rcssserver fork) behind the Env interface, through
// HFO's own C++ client library (HFO.hpp, libhfo). Built only when CMake is given
// -DHFO_ROOT=/path/to/HFO; without it make_hfo_server_env() throws the one-line fix.
//
// Contract beyond envs/env.hpp:
//  - One env is one player of one running server (`bin/HFO --offense-agents 1 --fullstate
//    --headless --port P`); the server must be started before the env's first reset() and
//    ends when the env disconnects (HFO's trainer stops the game when its agent leaves). With
//    --offense-agents N (env.offense_agents = N) each of N envs plays one of them, and the server,
//    in synchronous mode, runs a cycle once every agent has acted: a team plays in lockstep by
//    itself. The N envs are N processes, or one process's team env (env.server_agents = N:
//    lockstep_team.hpp, each player on a thread of its own, joining join_delay_ms apart).
//  - Connects lazily, on the first reset(): constructing one (to learn the observation size, as
//    the learner and replay shards do) opens no socket. Connecting allocates; steps then do not,
//    apart from what HFO's client library does inside.
//  - The server's random seed (bin/HFO --seed) governs start positions and noise; reset(seed)
//    cannot reseed it and behaves as reset().
//  - Episode boundaries are the server's: after a terminal status, HFO's client plays three
//    NOOPs, so the observation returned with a terminal status already shows the next episode's
//    start, and reset() returns that state without stepping. reset() in the middle of an
//    episode sends NOOPs until the server ends it (the untouched-ball rule does, within about
//    100 cycles). The env also ends an episode itself (OUT_OF_TIME) at `max_steps` agent steps,
//    in case the server allows longer trials.
//  - The reward is the embedded env's (reference §6.2, hfo::ShapedReward), always computed from
//    the 58-feature encoding, whichever encoding the agent sees.
//  - The first reset() waits up to connect_timeout_s for the server to answer (server_probe.hpp);
//    one that came up while it waited gets kTrainerFillS more to fill its NPC slots. A server
//    that goes down (SERVER_DOWN) or never answers is a std::runtime_error naming host:port and
//    how to start one.
//  - Parameters outside the server's ranges are clipped or wrapped as HFO's client would
//    (server_action.hpp) and counted: counters() gives kick_power_clamped, dash_power_clamped
//    and direction_wrapped since construction.
//  - Not thread-safe; one env per thread. HFO's client keeps process-wide parameter singletons
//    (librcsc's ServerParam, PlayerParam), which every player of a process sets to the server's
//    same values; HFO's own example/thread_agents.cpp plays two agents of one process this way,
//    and so does the team env (tested live: tests/hfo_server_integration_test.sh).
#pragma once

#include <memory>
#include <string>

#include "envs/env.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo_server/feature_encoding.hpp"
#include "envs/registry.hpp"

namespace pamdp::hfo_server {

enum class Encoding {
  kNative,    // the server's own features: 59 in 1v0, + 9 per opponent (reference §3.4)
  kEmbedded,  // converted to the embedded simulator's: 58, + 8 per opponent (§3.2), exact
};

struct HfoServerConfig {
  std::string host = "localhost";
  int port = 6000;  // bin/HFO --port
  Encoding encoding = Encoding::kNative;
  std::string team = "base_left";  // HFO's offense team name
  // agent2d formation files; empty: the HFO_ROOT given to CMake + bin/teams/base/config/formations-dt.
  std::string config_dir;
  int opponents = 0;           // defense players on the server: 1 with bin/HFO --defense-npcs 1 (a goalie)
  int teammates = 0;           // the other learned offense players: bin/HFO --offense-agents N gives N - 1
  int max_steps = 500;         // the server's --frames-per-trial (500 for dqn-hfo); the env ends longer episodes
  int connect_timeout_s = 30;  // how long the first reset() waits for a server to answer (env.server_connect_timeout_s)
  bool shoot_action = false;   // the action space with SHOOT, a second kick (env.shoot_action, envs/hfo/hfo_env.hpp)
  // How long the first reset() waits, once the server answers, before this player joins: player i
  // of a team env joins i * env.server_join_interval_ms after player 0 (HFO's trainer takes its
  // agents one at a time, in its own order of unums, launching agent2d NPCs for the slots between).
  int join_delay_ms = 0;
};

// How long a server that came up while the first reset() waited is given to fill its NPC slots
// before the agent joins (an agent that joins earlier breaks the server, server_probe.hpp). No
// message tells when bin/HFO's trainer is done; it took 0.7 s for the 10 offense slots on 2
// cores running two other jobs, and more than 3.5 s at a load average of 12 (docs/hfo-server.md).
inline constexpr double kTrainerFillS = 10.0;

// Observation width for `config` (native: 59 + 9 * (teammates + opponents); embedded:
// 58 + 8 * (teammates + opponents)).
inline int observation_size(const HfoServerConfig& config) {
  return config.encoding == Encoding::kNative ? e3_feature_count(config.teammates, config.opponents)
                                              : hfo::feature_count(1 + config.teammates + config.opponents);
}

// The settings the env.* keys of env 'hfo-server' give (envs/hfo_server/registration.cpp).
HfoServerConfig server_config(const EnvParams& params);

// True when this build links HFO's client library.
bool built_with_hfo();

// A new env for `config`. Throws std::runtime_error("... rebuild with -DHFO_ROOT=...") when the
// build has no HFO. Does not connect (see above).
std::unique_ptr<Env> make_hfo_server_env(const HfoServerConfig& config);

}  // namespace pamdp::hfo_server
