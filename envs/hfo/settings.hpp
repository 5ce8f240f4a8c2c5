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
