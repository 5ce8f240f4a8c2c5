// Builds the env an experiment config names.
#pragma once

#include <memory>
#include <stdexcept>

#include "app/experiment_config.hpp"
#include "envs/env.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo_server/hfo_server_env.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp::app {

// The settings of the real-server env (env.name = "hfo-server") that `c` describes.
inline hfo_server::HfoServerConfig server_config(const EnvConfig& c) {
  hfo_server::HfoServerConfig s;
  s.host = c.server_host;
  s.port = c.server_port;
  s.encoding = c.server_encoding;
  s.team = c.server_team;
  s.config_dir = c.server_config_dir;
  s.opponents = c.hfo.goalie ? 1 : 0;
  s.max_steps = c.hfo.max_steps;
  s.connect_timeout_s = c.server_connect_timeout_s;
  return s;
}

// Throws for a name this build cannot make (hfo-server without -DHFO_ROOT: the fix). An
// hfo-server env connects on its first reset(), so making one only to learn its sizes is free.
inline std::unique_ptr<Env> make_env(const EnvConfig& c) {
  if (c.name == "hfo") {
    return std::make_unique<hfo::HfoEnv>(c.hfo);
  }
  if (c.name == "reach_stop") {
    return std::make_unique<toy::ReachStopEnv>();
  }
  if (c.name == "hfo-server") {
    return hfo_server::make_hfo_server_env(server_config(c));
  }
  throw std::runtime_error("env.name '" + c.name + "' is unknown (valid: hfo, reach_stop, hfo-server)");
}

// The observation width of the env `c` describes, also for an hfo-server env in a build without
// HFO (a checkpoint trained on the real server can still be inspected there).
inline int observation_size(const EnvConfig& c) {
  return c.name == "hfo-server" ? hfo_server::observation_size(server_config(c)) : make_env(c)->observation_size();
}

// The env of the greedy evaluations `pamdp train` and `pamdp learner` run beside acting. On the
// real server it needs a server of its own (env.server_eval_port), demanded only when
// evaluations are on (train.eval_episodes > 0).
inline std::unique_ptr<Env> make_eval_env(const ExperimentConfig& c) {
  if (c.env.name != "hfo-server" || c.train.eval_episodes == 0) {
    return make_env(c.env);
  }
  if (c.env.server_eval_port == 0 || c.env.server_eval_port == c.env.server_port) {
    throw std::runtime_error(
        "greedy evaluations on env 'hfo-server' (train.eval_episodes > 0) need an HFO server of their own: start "
        "one and set env.server_eval_port to its port, or set train.eval_episodes=0");
  }
  EnvConfig e = c.env;
  e.server_port = c.env.server_eval_port;
  return make_env(e);
}

// Resolves action names ("TACKLE") and parameter ranges by name against the env's space.
inline ExplorationConfig resolve_exploration(const ExperimentConfig& c, const ActionSpace& space) {
  ExplorationConfig e = c.exploration;
  e.masked_actions.clear();
  for (const auto& name : c.masked_actions) {
    const int id = space.find_action(name);
    if (id < 0) {
      std::string valid;
      for (const auto& a : space.actions) {
        valid += (valid.empty() ? "" : ", ") + a.name;
      }
      throw std::runtime_error("exploration.masked_actions: '" + name + "' is not an action of env '" + c.env.name +
                               "' (valid: " + valid + ")");
    }
    e.masked_actions.push_back(id);
  }
  e.random_param_lo.clear();
  e.random_param_hi.clear();
  for (const auto& p : space.params) {
    e.random_param_lo.push_back(p.lo);
    e.random_param_hi.push_back(p.hi);
  }
  for (const auto& [name, range] : c.random_param_ranges) {
    bool found = false;
    for (size_t i = 0; i < space.params.size(); ++i) {
      if (space.params[i].name == name) {
        e.random_param_lo[i] = range.first;
        e.random_param_hi[i] = range.second;
        found = true;
      }
    }
    if (!found && c.env.name == "hfo") {
      throw std::runtime_error("exploration.random_param_ranges: '" + name + "' is not a parameter of env '" +
                               c.env.name + "'");
    }
  }
  return e;
}

}  // namespace pamdp::app
