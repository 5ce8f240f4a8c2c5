// Builds the env an experiment config names, through the env registry (envs/registry.hpp).
#pragma once

#include <algorithm>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include "app/experiment_config.hpp"
#include "envs/env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/hfo/scripted_team.hpp"
#include "envs/hfo/settings.hpp"
#include "envs/registry.hpp"

namespace pamdp::app {

// Throws for a name that is not registered (listing those that are) and for an env this build
// cannot make (hfo-server without -DHFO_ROOT: the fix).
inline std::unique_ptr<Env> make_env(const EnvConfig& c) {
  return env_registry().find(c.name).make(c.params);
}

// The observation width of the env `c` describes, without making it (a checkpoint trained on the
// real server can still be inspected in a build without HFO).
inline int observation_size(const EnvConfig& c) {
  return env_registry().find(c.name).observation_size(c.params);
}

// The env of the greedy evaluations `pamdp train` and `pamdp learner` run beside acting; an env
// may need settings of its own for them (hfo-server: a server of its own, env.server_eval_port),
// demanded only when evaluations are on (train.eval_episodes > 0).
inline std::unique_ptr<Env> make_eval_env(const ExperimentConfig& c) {
  const EnvRegistration& r = env_registry().find(c.env.name);
  if (!r.eval_params) {
    return r.make(c.env.params);
  }
  return r.make(r.eval_params(c.env.params, c.train.eval_episodes > 0));
}

// The teacher of demonstrations and labels (exploration.demo_fraction, demo_relabel) for one
// player: the scripted offense (exploration.demo_shot), or in a team (env.offense_agents > 1) the
// scripted team player (passing as exploration.demo_pass_within says). A team game takes one per
// player.
inline std::unique_ptr<Policy> make_teacher(const ExperimentConfig& c) {
  const bool shoot = hfo::shoot_action(c.env.params);
  const int agents =
      c.env.params.contains("offense_agents") ? static_cast<int>(c.env.params.integer("offense_agents")) : 1;
  if (agents > 1) {
    const int opponents = hfo::defense_players(c.env.params);
    return std::make_unique<hfo::ScriptedTeamPlayer>(agents - 1, opponents, shoot, c.demo_pass_within);
  }
  return std::make_unique<hfo::ScriptedOffense>(c.demo_shot, shoot);
}

// The registered envs with their descriptions, for the --help of the commands that take env.name.
inline std::string env_help_footer() {
  std::string out = "Envs (env.name):";
  for (const EnvRegistration& r : env_registry().all()) {
    out += "\n  " + r.name + std::string(r.name.size() < 12 ? 12 - r.name.size() : 1, ' ') + r.description;
  }
  return out;
}

// The registered learners, for the --help of the commands that train.
inline std::string algorithm_help_footer() {
  std::string out = "Learners (train.algorithm):";
  for (const AlgorithmRegistration& r : algorithm_registry().all()) {
    out += "\n  " + r.name + std::string(r.name.size() < 12 ? 12 - r.name.size() : 1, ' ') + r.description;
  }
  // Each own key once, with its default (keys shared by learners are declared alike).
  std::string keys;
  for (const AlgorithmKey& k : algorithm_registry().keys()) {
    std::ostringstream value;
    if (k.is_boolean()) {
      value << (std::get<bool>(k.default_value) ? "true" : "false");
    } else {
      value << std::get<double>(k.default_value);
    }
    keys += "\n  " + k.name + " = " + value.str() + ": " + k.help;
  }
  if (!keys.empty()) {
    out += "\nTheir own keys (defaults):" + keys;
  }
  return out;
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
  e.gates.clear();
  const auto& gates = env_registry().find(c.env.name).action_gates;
  for (const auto& name : c.gated_actions) {
    const auto g = std::find_if(gates.begin(), gates.end(), [&name](const auto& ag) { return ag.first == name; });
    if (g == gates.end()) {
      std::string valid;
      for (const auto& ag : gates) {
        valid += (valid.empty() ? "" : ", ") + ag.first;
      }
      throw std::runtime_error("exploration.gated_actions: env '" + c.env.name + "' has no feature that gates '" +
                               name + "' (it gates: " + (valid.empty() ? "none" : valid) +
                               "); remove it from the list");
    }
    e.gates.push_back({space.find_action(name), g->second});
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
    // Names are checked on HFO's action space only: the default (dash_power) is HFO's, and other
    // envs keep their own ranges.
    if (!found && env_registry().find(c.env.name).hfo_actions) {
      throw std::runtime_error("exploration.random_param_ranges: '" + name + "' is not a parameter of env '" +
                               c.env.name + "'");
    }
  }
  return e;
}

}  // namespace pamdp::app
