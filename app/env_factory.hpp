// Builds the env an experiment config names.
#pragma once

#include <memory>
#include <stdexcept>

#include "app/experiment_config.hpp"
#include "envs/env.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp::app {

inline std::unique_ptr<Env> make_env(const EnvConfig& c) {
  if (c.name == "hfo") {
    return std::make_unique<hfo::HfoEnv>(c.hfo);
  }
  if (c.name == "reach_stop") {
    return std::make_unique<toy::ReachStopEnv>();
  }
  throw std::runtime_error("env.name '" + c.name + "' is unknown (valid: hfo, reach_stop)");
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
