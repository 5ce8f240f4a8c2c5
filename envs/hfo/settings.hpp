// The embedded simulator's env.* settings (env.name = "hfo"): their names and values as the
// config file spells them, and the conversion to and from SoccerSimConfig. The hfo env registers
// these keys (envs/hfo/registration.cpp); the real-server env shares goalie and max_steps.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "envs/hfo/soccer_sim.hpp"
#include "envs/registry.hpp"

namespace pamdp::hfo {

template <typename E>
using Names = std::vector<std::pair<std::string, E>>;
const Names<StartDistribution>& start_names();    // paper, dec2015, hfo
const Names<Referee>& referee_names();            // server, trainer
const Names<BodyAtReset>& body_at_reset_names();  // carry, zero, uniform

// The keys, with SoccerSimConfig's defaults.
EnvKey goalie_key();
// env.defense_npcs: HFO's --defense-npcs K (0-3): the goalie, then K - 1 of agent2d's field
// defenders (SoccerSimConfig::field_defenders). K >= 1 implies env.goalie; 0 leaves it to
// env.goalie.
EnvKey defense_npcs_key();
// The defense players of a game the env.* keys describe: the goalie (env.goalie or
// env.defense_npcs >= 1) and the field defenders (env.defense_npcs - 1); keys missing count 0.
int defense_players(const EnvParams& params);
EnvKey max_steps_key();
// env.offense_agents: HFO's --offense-agents N (1-4). The embedded game plays all N as one team
// env (Env::agents() = N); on the real server each env is one of the N.
EnvKey offense_agents_key();
// env.shoot_action: the action space with SHOOT, a second kick (hfo_env.hpp); read by hfo and
// hfo-server alike, so a policy trained with it plays on the real server.
EnvKey shoot_action_key();
// Its value in `params`; false for an env without the key.
bool shoot_action(const EnvParams& params);
std::vector<EnvKey> sim_keys();  // every key of SoccerSimConfig, goalie and max_steps included

// `params` holds every key of sim_keys() (EnvRegistry::defaults() does).
SoccerSimConfig sim_config(const EnvParams& params);
void set_sim_config(EnvParams& params, const SoccerSimConfig& config);

}  // namespace pamdp::hfo
