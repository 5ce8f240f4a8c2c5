#include "python/env_registry.hpp"

#include <algorithm>
#include <stdexcept>

#include "app/env_factory.hpp"
#include "envs/registry.hpp"

namespace pamdp::python {
namespace {

struct Entry {
  EnvId id;
  std::string name;                  // env.name
  std::vector<std::string> fixed;    // env.* assignments the id makes ("goalie=true")
  std::vector<std::string> options;  // the env.* keys a user may set
};

// The keys env `name` reads (envs/registry.hpp), less `fixed_keys`.
std::vector<std::string> options_of(const std::string& name, const std::vector<std::string>& fixed_keys = {}) {
  std::vector<std::string> out;
  for (const EnvKey& k : env_registry().find(name).keys) {
    if (std::find(fixed_keys.begin(), fixed_keys.end(), k.name) == fixed_keys.end()) {
      out.push_back(k.name);
    }
  }
  return out;
}

// The two HFO set-ups by id, then every registered env by its name, so that a new env is offered
// here without a line in this file.
const std::vector<Entry>& entries() {
  static const std::vector<Entry> kEntries = [] {
    std::vector<Entry> e{
        {{"hfo-1v0", "embedded Half Field Offense, the agent alone against an empty goal (58 features)"},
         "hfo",
         {"goalie=false", "defense_npcs=0"},
         options_of("hfo", {"goalie", "defense_npcs"})},
        {{"hfo-1v1", "embedded Half Field Offense against the NPC goalie (66 features)"},
         "hfo",
         {"goalie=true", "defense_npcs=0"},
         options_of("hfo", {"goalie", "defense_npcs"})},
    };
    for (const EnvRegistration& r : env_registry().all()) {
      e.push_back({{r.name, r.description}, r.name, {}, options_of(r.name)});
    }
    return e;
  }();
  return kEntries;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) {
    out += (out.empty() ? "" : ", ") + n;
  }
  return out.empty() ? "none" : out;
}

const Entry& find(const std::string& id) {
  for (const Entry& e : entries()) {
    if (e.id.id == id) {
      return e;
    }
  }
  std::vector<std::string> ids;
  for (const Entry& e : entries()) {
    ids.push_back(e.id.id);
  }
  throw std::invalid_argument("pamdp: unknown env '" + id + "' (valid: " + join(ids) + ")");
}

}  // namespace

const std::vector<EnvId>& env_ids() {
  static const std::vector<EnvId> kIds = [] {
    std::vector<EnvId> ids;
    for (const Entry& e : entries()) {
      ids.push_back(e.id);
    }
    return ids;
  }();
  return kIds;
}

std::vector<std::string> option_names(const std::string& id) {
  std::vector<std::string> names = find(id).options;
  std::sort(names.begin(), names.end());
  return names;
}

app::EnvConfig resolve_env(const std::string& id, const std::vector<std::pair<std::string, std::string>>& options) {
  const Entry& e = find(id);
  const std::string source = "pamdp.make('" + id + "')";
  std::vector<std::string> sets{"env.name=\"" + e.name + "\""};
  for (const std::string& f : e.fixed) {
    sets.push_back("env." + f);
  }
  for (const auto& [key, value] : options) {
    if (std::find(e.options.begin(), e.options.end(), key) == e.options.end()) {
      for (const std::string& f : e.fixed) {
        if (f.rfind(key + "=", 0) == 0) {
          throw std::invalid_argument(source + ": '" + key + "' is fixed by the id ('" + f + "'); make('hfo', " + key +
                                      "=...) chooses it");
        }
      }
      throw std::invalid_argument(source + ": unknown option '" + key + "' (valid: " + join(option_names(id)) + ")");
    }
    sets.push_back("env." + key + "=" + value);
  }
  try {
    return app::parse_experiment_config("", source, sets).env;
  } catch (const std::runtime_error& err) {
    throw std::invalid_argument(err.what());
  }
}

std::unique_ptr<Env> build_env(const app::EnvConfig& config, bool team) {
  if (!team && config.params.contains("offense_agents") && config.params.integer("offense_agents") > 1 &&
      config.name == "hfo") {
    throw std::invalid_argument("offense_agents = " + std::to_string(config.params.integer("offense_agents")) +
                                " is a team of learned players: pamdp.make_team(env_id, agents) plays it, one "
                                "observation, action and reward per player (pamdp.make_team_vec(env_id, agents, "
                                "num_envs) steps many such games)");
  }
  return app::make_env(config);
}

std::string id_of(const app::EnvConfig& config) {
  // The id whose fixed assignments the config holds (the goalie picks between hfo-1v0 and
  // hfo-1v1, both without field defenders); else the env's name.
  for (const Entry& e : entries()) {
    if (e.name != config.name || e.fixed.empty()) {
      continue;
    }
    const bool all = std::all_of(e.fixed.begin(), e.fixed.end(), [&](const std::string& f) {
      const auto eq = f.find('=');
      const std::string key = f.substr(0, eq);
      if (!config.params.contains(key)) {
        return false;
      }
      const EnvValue& v = config.params.values().at(key);
      const std::string value = f.substr(eq + 1);
      if (const auto* b = std::get_if<bool>(&v)) {
        return (*b ? "true" : "false") == value;
      }
      if (const auto* i = std::get_if<int64_t>(&v)) {
        return std::to_string(*i) == value;
      }
      return false;
    });
    if (all) {
      return e.id.id;
    }
  }
  return config.name;
}

std::string env_toml(const app::EnvConfig& config) {
  app::ExperimentConfig c;
  c.env = config;
  return app::to_toml(c);
}

bool fresh_env_per_seed(const app::EnvConfig& config) {
  return !env_registry().find(config.name).location;
}

float observation_bound(const app::EnvConfig& config) {
  return env_registry().find(config.name).observation_bound;
}

}  // namespace pamdp::python
