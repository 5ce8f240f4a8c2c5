// The envs the Python module offers, by id, and how each is built from its keyword options. This
// is the one place the binding depends on env construction; the envs and their keys come from the
// project's env registry (envs/registry.hpp).
//
// Ids: "hfo-1v0" (no goalie), "hfo-1v1" (the NPC goalie on), then every registered env by its
// env.name: "hfo" (goalie chosen by option), "reach_stop" (the toy task) and "hfo-server" (the
// real server; needs a build with -DHFO_ROOT). Options are the env.* keys the env reads, without
// the "env." prefix ("noise", "start", ...), each a TOML value as text ("false", "\"dec2015\"",
// "300"), validated by the config file's own reader.
// Not thread-safe only in the sense that nothing here is shared: every call builds fresh objects.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "app/experiment_config.hpp"
#include "envs/env.hpp"

namespace pamdp::python {

struct EnvId {
  std::string id;
  std::string description;
};

// Every id make() accepts, in listing order.
const std::vector<EnvId>& env_ids();

// The option names `id` takes as keyword arguments, sorted. Throws std::invalid_argument (an
// unknown id, naming the valid ones).
std::vector<std::string> option_names(const std::string& id);

// The env config `id` with `options` ({name, TOML value text}) describes. Throws
// std::invalid_argument naming the id or key, the problem and the valid choices.
app::EnvConfig resolve_env(const std::string& id, const std::vector<std::pair<std::string, std::string>>& options);

// A fresh env for `config`. Throws std::runtime_error when this build cannot make it. A team
// (hfo with env.offense_agents > 1) is refused, naming make_team, unless `team` is true (the
// team vector env, make_team_vec).
std::unique_ptr<Env> build_env(const app::EnvConfig& config, bool team = false);

// The id whose defaults `config` follows ("hfo-1v1" for hfo with the goalie), and a config file
// holding `config` as its [env] table (every key, defaults included).
std::string id_of(const app::EnvConfig& config);
std::string env_toml(const app::EnvConfig& config);

// Whether a seeded reset should start from a freshly built env, so that the seed alone decides
// the episode as Gymnasium expects (HFO carries the body angle from episode to episode with
// env.body_at_reset = carry; Env::reset(seed) promises the same episode only on a fresh env).
// False for hfo-server, whose connection a rebuild would drop (the server's own --seed rules).
bool fresh_env_per_seed(const app::EnvConfig& config);

// A bound on every |observation value| of the env `config` describes.
float observation_bound(const app::EnvConfig& config);

}  // namespace pamdp::python
