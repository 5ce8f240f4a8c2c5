#include "app/experiment_config.hpp"

#include <toml++/toml.h>
#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "app/env_factory.hpp"
#include "envs/hfo/settings.hpp"

namespace pamdp::app {
namespace {

const Choices<BoundMethod> kBounds{
    {"inverting", BoundMethod::kInverting}, {"zeroing", BoundMethod::kZeroing}, {"squashing", BoundMethod::kSquashing}};
const Choices<UpdateDevice> kDevices{
    {"auto", UpdateDevice::kAuto}, {"cpu", UpdateDevice::kCpu}, {"cuda", UpdateDevice::kCuda}};

// Splits "a.b.c" into {"a", "b", "c"}.
std::vector<std::string> split_path(const std::string& key) {
  std::vector<std::string> parts;
  std::stringstream ss(key);
  std::string p;
  while (std::getline(ss, p, '.')) {
    parts.push_back(p);
  }
  return parts;
}

// An env.* key as its env declares it (envs/registry.hpp).
template <typename V>
void visit_env_key(V& v, const EnvKey& k, EnvValue& value) {
  const std::string key = "env." + k.name;
  switch (k.type) {
    case EnvKey::Type::kBoolean: v.boolean(key, std::get<bool>(value)); break;
    case EnvKey::Type::kInteger: v.integer(key, std::get<int64_t>(value), k.lo, k.hi); break;
    case EnvKey::Type::kText: v.text(key, std::get<std::string>(value)); break;
    case EnvKey::Type::kTextOrEmpty: v.text_or_empty(key, std::get<std::string>(value)); break;
    case EnvKey::Type::kChoice: {
      Choices<std::string> choices;
      for (const std::string& name : k.choices) {
        choices.emplace_back(name, name);
      }
      v.choice(key, std::get<std::string>(value), choices);
      break;
    }
  }
}

// Every field of the config is listed once, in visit(); the reader and the writer below are the
// two visitors, so the file format and the struct cannot drift apart.
template <typename V>
void visit(V& v, ExperimentConfig& c) {
  v.integer("seed", c.seed, 0, INT64_MAX);
  v.choice("env.name", c.env.name, env_choices());
  for (const EnvKey& k : env_registry().keys()) {
    visit_env_key(v, k, c.env.params.at(k.name));
  }

  v.int_list("ddpg.hidden", c.ddpg.hidden, 1, 1 << 16);
  v.real("ddpg.actor_learning_rate", c.ddpg.actor_learning_rate, 0.0, 1.0);
  v.real("ddpg.critic_learning_rate", c.ddpg.critic_learning_rate, 0.0, 1.0);
  v.real("ddpg.adam_beta1", c.ddpg.adam_beta1, 0.0, 0.999999);
  v.real("ddpg.adam_beta2", c.ddpg.adam_beta2, 0.0, 0.999999999);
  v.real("ddpg.adam_epsilon", c.ddpg.adam_epsilon, 0.0, 1.0);
  v.real("ddpg.gamma", c.ddpg.gamma, 0.0, 1.0);
  v.real("ddpg.tau", c.ddpg.tau, 0.0, 1.0);
  v.integer("ddpg.batch_size", c.ddpg.batch_size, 1, 65536);
  v.real("ddpg.clip_grad_norm", c.ddpg.clip_grad_norm, 0.0, 1e12);
  v.choice("ddpg.bound", c.ddpg.bound, kBounds);
  v.real("ddpg.mc_mix", c.ddpg.mc_mix, 0.0, 1.0);
  v.real("ddpg.bootstrap_clip", c.ddpg.bootstrap_clip, 0.0, 1e12);
  v.integer("ddpg.lr_decay_updates", c.ddpg.lr_decay_updates, 0, INT64_MAX);
  v.real("ddpg.lr_final_fraction", c.ddpg.lr_final_fraction, 0.0, 1.0);
  v.real("ddpg.init_std", c.ddpg.init_std, 0.0, 10.0);
  v.real("ddpg.critic_output_init_std", c.ddpg.critic_output_init_std, 0.0, 10.0);
  v.real("ddpg.critic_output_init_bias", c.ddpg.critic_output_init_bias, -1e6, 1e6);
  v.choice("ddpg.device", c.ddpg.device, kDevices);
  v.real("ddpg.demo_bc_weight", c.ddpg.demo_bc_weight, 0.0, 1e6);
  v.boolean("ddpg.demo_q_filter", c.ddpg.demo_q_filter);
  v.real("ddpg.actor_average_tau", c.ddpg.actor_average_tau, 0.0, 1.0);
  v.boolean("ddpg.passthrough", c.ddpg.passthrough);
  v.real("ddpg.actor_output_init_std", c.ddpg.actor_output_init_std, 0.0, 10.0);
  v.real("ddpg.reward_scale", c.ddpg.reward_scale, 1e-9, 1e9);
  // Each algorithm's own keys, as its registration declares them (learner/algorithm.hpp).
  for (const AlgorithmKey& k : algorithm_registry().keys()) {
    AlgorithmValue& value = c.algorithm_params.at(k.name);
    if (k.is_boolean()) {
      v.boolean(k.name, std::get<bool>(value));
    } else {
      v.real(k.name, std::get<double>(value), k.lo, k.hi);
    }
  }

  v.real("exploration.epsilon_start", c.exploration.epsilon_start, 0.0, 1.0);
  v.real("exploration.epsilon_end", c.exploration.epsilon_end, 0.0, 1.0);
  v.integer("exploration.epsilon_anneal_updates", c.exploration.epsilon_anneal_updates, 0, INT64_MAX);
  v.str_list("exploration.masked_actions", c.masked_actions);
  v.str_list("exploration.gated_actions", c.gated_actions);
  v.ranges("exploration.random_param_ranges", c.random_param_ranges);
  v.real("exploration.param_noise", c.exploration.param_noise, 0.0, 1.0);
  v.boolean("exploration.uniform_random_params", c.exploration.uniform_random_params);
  v.real("exploration.demo_fraction", c.exploration.demo_fraction, 0.0, 1.0);
  v.integer("exploration.demo_anneal_updates", c.exploration.demo_anneal_updates, 0, INT64_MAX);
  v.real("exploration.demo_fraction_end", c.exploration.demo_fraction_end, 0.0, 1.0);
  v.boolean("exploration.demo_relabel", c.exploration.demo_relabel);
  v.choice("exploration.demo_shot", c.demo_shot, shot_aim_choices());
  v.real("exploration.demo_pass_within", c.demo_pass_within, 0.0, 100.0);

  v.integer("replay.capacity", c.replay.capacity, 1, int64_t{1} << 32);
  v.integer("replay.warmup", c.replay.warmup, 1, int64_t{1} << 32);
  v.integer("replay.shards", c.replay.shards, 1, 1024);

  v.choice("train.algorithm", c.train.algorithm, algorithm_choices());
  v.integer("train.max_updates", c.train.max_updates, 0, INT64_MAX);
  v.integer("train.max_episodes", c.train.max_episodes, 0, INT64_MAX);
  v.real("train.max_seconds", c.train.max_seconds, 0.0, 1e9);
  v.real("train.updates_per_step", c.train.updates_per_step, 0.0, 1000.0);
  v.integer("train.eval_every_updates", c.train.eval_every_updates, 0, INT64_MAX);
  v.integer("train.eval_episodes", c.train.eval_episodes, 0, 1000000);
  v.integer("train.confirm_episodes", c.train.confirm_episodes, 0, 1000000);
  v.real("train.best_steps_limit", c.train.best_steps_limit, 0.0, 1e9);
  v.boolean("train.recheck_best", c.train.recheck_best);
  v.real("train.checkpoint_every_seconds", c.train.checkpoint_every_seconds, 0.0, 1e9);
  v.real("train.log_every_seconds", c.train.log_every_seconds, 0.0, 1e9);
  v.text_or_empty("train.init_from", c.train.init_from);

  v.text("cluster.learner_bind", c.cluster.learner_bind);
  v.text("cluster.weights_bind", c.cluster.weights_bind);
  v.text("cluster.advertise_host", c.cluster.advertise_host);
  v.integer("cluster.publish_every_updates", c.cluster.publish_every_updates, 1, INT64_MAX);
  v.integer("cluster.actor_batch_transitions", c.cluster.actor_batch_transitions, 1, 65536);
  v.integer("cluster.actor_batches_in_flight", c.cluster.actor_batches_in_flight, 1, 1024);
  v.real("cluster.samples_per_insert", c.cluster.samples_per_insert, 0.0, 1e6);
  v.integer("cluster.rate_limit_slack", c.cluster.rate_limit_slack, 1, INT64_MAX);
  v.integer("cluster.requests_in_flight_per_shard", c.cluster.requests_in_flight_per_shard, 1, 64);
  v.integer("cluster.heartbeat_ms", c.cluster.heartbeat_ms, 10, 600000);
  v.integer("cluster.peer_timeout_ms", c.cluster.peer_timeout_ms, 100, 3600000);
  v.boolean("cluster.curve", c.cluster.curve);
  v.text("cluster.curve_keys_dir", c.cluster.curve_keys_dir);
  v.boolean("cluster.insecure", c.cluster.insecure);

  v.text("metrics.bind", c.metrics.bind);
  v.integer("metrics.port", c.metrics.port, 0, 65535);
}

class Reader {
 public:
  // `set_by`: the keys that --set gave (dotted, as written) and the assignment that gave each, so
  // that an error names the command line rather than the file when the bad value came from there.
  Reader(const toml::table& root, std::string source, std::map<std::string, std::string> set_by)
      : root_(root), source_(std::move(source)), set_by_(std::move(set_by)) {}

  template <typename T>
  void integer(const std::string& key, T& out, int64_t lo, int64_t hi) {
    if (const toml::node* n = find(key)) {
      const auto v = n->value_exact<int64_t>();
      if (!v) {
        fail(key, "must be an integer");
      }
      if (*v < lo || *v > hi) {
        fail(key, "must be within [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::to_string(*v));
      }
      out = static_cast<T>(*v);
    }
  }
  void real(const std::string& key, double& out, double lo, double hi) {
    if (const toml::node* n = find(key)) {
      const auto v = n->value<double>();  // accepts integers too
      if (!v || n->is_boolean()) {
        fail(key, "must be a number");
      }
      if (!(*v >= lo && *v <= hi)) {
        std::ostringstream ss;
        ss << "must be within [" << lo << ", " << hi << "], got " << *v;
        fail(key, ss.str());
      }
      out = *v;
    }
  }
  void text(const std::string& key, std::string& out) {
    if (const toml::node* n = find(key)) {
      const auto v = n->value_exact<std::string>();
      if (!v || v->empty()) {
        fail(key, "must be a non-empty string");
      }
      out = *v;
    }
  }
  void text_or_empty(const std::string& key, std::string& out) {
    if (const toml::node* n = find(key)) {
      const auto v = n->value_exact<std::string>();
      if (!v) {
        fail(key, "must be a string");
      }
      out = *v;
    }
  }
  void boolean(const std::string& key, bool& out) {
    if (const toml::node* n = find(key)) {
      const auto v = n->value_exact<bool>();
      if (!v) {
        fail(key, "must be true or false");
      }
      out = *v;
    }
  }
  template <typename E>
  void choice(const std::string& key, E& out, const Choices<E>& choices) {
    if (const toml::node* n = find(key)) {
      const auto v = n->value_exact<std::string>();
      std::string valid;
      for (const auto& [name, value] : choices) {
        valid += (valid.empty() ? "" : ", ") + name;
        if (v && *v == name) {
          out = value;
          return;
        }
      }
      fail(key, "must be one of: " + valid);
    }
  }
  void int_list(const std::string& key, std::vector<int>& out, int lo, int hi) {
    if (const toml::node* n = find(key)) {
      const toml::array* arr = n->as_array();
      if (arr == nullptr || arr->empty()) {
        fail(key, "must be a non-empty array of integers, e.g. [1024, 512, 256, 128]");
      }
      std::vector<int> values;
      for (const auto& e : *arr) {
        const auto v = e.value_exact<int64_t>();
        if (!v || *v < lo || *v > hi) {
          fail(key, "entries must be integers within [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        }
        values.push_back(static_cast<int>(*v));
      }
      out = values;
    }
  }
  void str_list(const std::string& key, std::vector<std::string>& out) {
    if (const toml::node* n = find(key)) {
      const toml::array* arr = n->as_array();
      if (arr == nullptr) {
        fail(key, "must be an array of strings");
      }
      std::vector<std::string> values;
      for (const auto& e : *arr) {
        const auto v = e.value_exact<std::string>();
        if (!v) {
          fail(key, "must be an array of strings");
        }
        values.push_back(*v);
      }
      out = values;
    }
  }
  void ranges(const std::string& key, std::vector<std::pair<std::string, std::pair<float, float>>>& out) {
    const toml::node* n = find(key, /*leaf=*/false);
    if (n == nullptr) {
      return;
    }
    const toml::table* t = n->as_table();
    if (t == nullptr) {
      fail(key, "must be a table of name = [lo, hi]");
    }
    out.clear();
    for (const auto& [name, value] : *t) {
      const toml::array* arr = value.as_array();
      if (arr == nullptr || arr->size() != 2 || !(*arr)[0].value<double>() || !(*arr)[1].value<double>()) {
        fail(key + "." + std::string(name.str()), "must be [lo, hi]");
      }
      const double lo = *(*arr)[0].value<double>();
      const double hi = *(*arr)[1].value<double>();
      if (!(lo < hi)) {
        fail(key + "." + std::string(name.str()), "needs lo < hi");
      }
      out.emplace_back(std::string(name.str()), std::make_pair(static_cast<float>(lo), static_cast<float>(hi)));
    }
  }

  // Any key in the file that no field read is an error naming its section's valid keys.
  void reject_unknown() const { check_table(root_, ""); }

 private:
  const toml::node* find(const std::string& key, bool leaf = true) {
    known_.insert(key);
    const toml::node* node = &root_;
    for (const std::string& part : split_path(key)) {
      const toml::table* t = node->as_table();
      if (t == nullptr) {
        return nullptr;
      }
      node = t->get(part);
      if (node == nullptr) {
        return nullptr;
      }
    }
    if (leaf && node->is_table()) {
      fail(key, "must be a value, not a table");
    }
    return node;
  }

  void check_table(const toml::table& t, const std::string& prefix) const {
    for (const auto& [k, v] : t) {
      const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
      if (known_.count(key) != 0) {
        continue;
      }
      if (v.is_table() && is_section(key)) {
        check_table(*v.as_table(), key);
        continue;
      }
      // Valid names in this section: known keys and sub-sections directly under `prefix`.
      std::set<std::string> valid;
      for (const std::string& kk : known_) {
        if (!prefix.empty() && kk.rfind(prefix + ".", 0) != 0) {
          continue;
        }
        const std::string rest = prefix.empty() ? kk : kk.substr(prefix.size() + 1);
        const auto dot = rest.find('.');
        valid.insert(dot == std::string::npos ? rest : "[" + rest.substr(0, dot) + "]");
      }
      std::string list;
      for (const auto& name : valid) {
        list += (list.empty() ? "" : ", ") + name;
      }
      throw std::runtime_error(origin(key) + ": unknown key '" + key + "' (valid" +
                               (prefix.empty() ? std::string() : " in [" + prefix + "]") + ": " + list + ")");
    }
  }
  [[nodiscard]] bool is_section(const std::string& key) const {
    for (const std::string& kk : known_) {
      if (kk.rfind(key + ".", 0) == 0) {
        return true;
      }
    }
    return false;
  }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::runtime_error(origin(key) + ": '" + key + "' " + what);
  }

  // Where `key`'s value came from: "--set key=value" when an override set it (or a table above
  // it), else the file.
  [[nodiscard]] std::string origin(const std::string& key) const {
    for (const auto& [set_key, assignment] : set_by_) {
      if (key == set_key || key.rfind(set_key + ".", 0) == 0) {
        return "--set " + assignment;
      }
    }
    return source_;
  }

  const toml::table& root_;
  std::string source_;
  std::map<std::string, std::string> set_by_;
  std::set<std::string> known_;
};

class Writer {
 public:
  template <typename T>
  void integer(const std::string& key, const T& v, int64_t /*lo*/, int64_t /*hi*/) {
    put(key, static_cast<int64_t>(v));
  }
  void real(const std::string& key, const double& v, double /*lo*/, double /*hi*/) { put(key, v); }
  void boolean(const std::string& key, const bool& v) { put(key, v); }
  void text(const std::string& key, const std::string& v) { put(key, v); }
  void text_or_empty(const std::string& key, const std::string& v) { put(key, v); }
  template <typename E>
  void choice(const std::string& key, const E& v, const Choices<E>& choices) {
    for (const auto& [name, value] : choices) {
      if (value == v) {
        put(key, name);
      }
    }
  }
  void int_list(const std::string& key, const std::vector<int>& v, int /*lo*/, int /*hi*/) {
    toml::array arr;
    for (int x : v) {
      arr.push_back(static_cast<int64_t>(x));
    }
    put(key, std::move(arr));
  }
  void str_list(const std::string& key, const std::vector<std::string>& v) {
    toml::array arr;
    for (const auto& s : v) {
      arr.push_back(s);
    }
    put(key, std::move(arr));
  }
  void ranges(const std::string& key, const std::vector<std::pair<std::string, std::pair<float, float>>>& v) {
    toml::table t;
    for (const auto& [name, r] : v) {
      t.insert(name, toml::array{static_cast<double>(r.first), static_cast<double>(r.second)});
    }
    put(key, std::move(t));
  }
  toml::table root;

 private:
  template <typename T>
  void put(const std::string& key, T&& value) {
    const auto parts = split_path(key);
    toml::table* t = &root;
    for (size_t i = 0; i + 1 < parts.size(); ++i) {
      auto [it, inserted] = t->insert(parts[i], toml::table{});
      t = it->second.as_table();
    }
    t->insert_or_assign(parts.back(), std::forward<T>(value));
  }
};

// Applies "a.b=value": the value is parsed as a TOML value (numbers, true/false, "strings",
// [arrays]); a bare word that is not valid TOML is taken as a string. Returns the dotted key set.
std::string apply_override(toml::table& root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw std::runtime_error("--set '" + assignment + "': expected key=value, e.g. --set ddpg.gamma=0.95");
  }
  std::string key = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  while (!key.empty() && key.back() == ' ') {
    key.pop_back();
  }
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    try {
      parsed = toml::parse("v = \"" + value + "\"");
    } catch (const toml::parse_error&) {
      throw std::runtime_error("--set '" + assignment + "': cannot parse the value");
    }
  }
  const auto parts = split_path(key);
  if (parts.empty() || std::any_of(parts.begin(), parts.end(), [](const std::string& p) { return p.empty(); })) {
    throw std::runtime_error("--set '" + assignment + "': expected section.key=value, e.g. --set ddpg.gamma=0.95");
  }
  toml::table* t = &root;
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    auto [it, inserted] = t->insert(parts[i], toml::table{});
    t = it->second.as_table();
    if (t == nullptr) {
      throw std::runtime_error("--set '" + assignment + "': '" + parts[i] + "' is not a section");
    }
  }
  t->insert_or_assign(parts.back(), *parsed.get("v"));
  std::string dotted;
  for (const std::string& p : parts) {
    dotted += (dotted.empty() ? "" : ".") + p;
  }
  return dotted;
}

// The registered envs that give the embedded HFO features, and the setting that makes them
// ("env.name = \"hfo\" or env.name = \"hfo-server\" with env.server_encoding = embedded").
std::string envs_giving_embedded_features() {
  std::string out;
  for (const EnvRegistration& r : env_registry().all()) {
    EnvParams p = env_registry().defaults();
    std::string with;
    if (r.use_embedded_hfo_features) {
      with = " with " + r.use_embedded_hfo_features(p);
    }
    if (r.gives_embedded_hfo_features && r.gives_embedded_hfo_features(p)) {
      out += (out.empty() ? "" : " or ") + ("env.name = \"" + r.name + "\"") + with;
    }
  }
  return out;
}

void validate(const ExperimentConfig& c, const std::string& src) {
  if (c.exploration.epsilon_end > c.exploration.epsilon_start) {
    throw std::runtime_error(src + ": exploration.epsilon_end must not exceed exploration.epsilon_start");
  }
  if (c.replay.warmup > c.replay.capacity) {
    throw std::runtime_error(src + ": replay.warmup must not exceed replay.capacity");
  }
  if (c.replay.warmup < c.ddpg.batch_size) {
    throw std::runtime_error(src + ": replay.warmup must be at least ddpg.batch_size");
  }
  if (c.exploration.demo_fraction > 0.0 && !gives_embedded_features(c.env)) {
    throw std::runtime_error(src +
                             ": exploration.demo_fraction > 0 needs the scripted offense, which reads the embedded "
                             "HFO features: use " +
                             envs_giving_embedded_features() + ", or set exploration.demo_fraction = 0");
  }
  if (c.exploration.demo_fraction_end > c.exploration.demo_fraction) {
    throw std::runtime_error(src +
                             ": exploration.demo_fraction_end is the share the teacher's episodes fall to, and it is "
                             "above exploration.demo_fraction: set it at or below demo_fraction");
  }
  if (c.exploration.demo_fraction_end > 0.0 && c.exploration.demo_anneal_updates <= 0) {
    throw std::runtime_error(src +
                             ": exploration.demo_fraction_end is the share after the anneal, and "
                             "exploration.demo_anneal_updates = 0 keeps demo_fraction throughout: set "
                             "demo_anneal_updates > 0, or demo_fraction_end = 0");
  }
  if (c.ddpg.demo_bc_weight > 0.0 && c.exploration.demo_fraction <= 0.0) {
    throw std::runtime_error(src +
                             ": ddpg.demo_bc_weight > 0 clones demonstrations, and there are none: set "
                             "exploration.demo_fraction > 0 (the share of episodes the scripted offense plays), or "
                             "ddpg.demo_bc_weight = 0");
  }
  if (c.exploration.demo_relabel && c.ddpg.demo_bc_weight <= 0.0) {
    throw std::runtime_error(src +
                             ": exploration.demo_relabel = true labels the agent's steps for cloning, and nothing "
                             "clones: set ddpg.demo_bc_weight > 0 (with exploration.demo_fraction > 0), or "
                             "exploration.demo_relabel = false");
  }
  const bool team = c.env.params.contains("offense_agents") && c.env.params.integer("offense_agents") > 1;
  if (c.demo_pass_within != hfo::ScriptedTeamPlayer::kPassWhenOpponentWithin && !team) {
    throw std::runtime_error(src +
                             ": exploration.demo_pass_within sets when the scripted team player passes, and there "
                             "is no team: set env.offense_agents > 1, or leave exploration.demo_pass_within out");
  }
  if (c.demo_shot != hfo::ShotAim::kBestCourse && c.exploration.demo_fraction <= 0.0) {
    throw std::runtime_error(src +
                             ": exploration.demo_shot aims the scripted offense's shots, and it plays no episodes: "
                             "set exploration.demo_fraction > 0, or leave exploration.demo_shot = \"best-course\"");
  }
  for (const auto& [key, endpoint] :
       {std::pair<const char*, const std::string&>{"cluster.learner_bind", c.cluster.learner_bind},
        {"cluster.weights_bind", c.cluster.weights_bind}}) {
    if (endpoint.rfind("tcp://", 0) != 0 && endpoint.rfind("ipc://", 0) != 0 && endpoint.rfind("inproc://", 0) != 0) {
      throw std::runtime_error(src + ": " + key + " '" + endpoint +
                               "' is not an endpoint: write tcp://HOST:PORT, e.g. tcp://127.0.0.1:5555");
    }
  }
}

}  // namespace

const Choices<hfo::StartDistribution>& start_choices() {
  return hfo::start_names();
}

const Choices<hfo::Referee>& referee_choices() {
  return hfo::referee_names();
}

const Choices<hfo::BodyAtReset>& body_at_reset_choices() {
  return hfo::body_at_reset_names();
}

const Choices<std::string>& algorithm_choices() {
  static const Choices<std::string> kChoices = [] {
    Choices<std::string> c;
    for (const AlgorithmRegistration& r : algorithm_registry().all()) {
      c.emplace_back(r.name, r.name);
    }
    return c;
  }();
  return kChoices;
}

const Choices<std::string>& env_choices() {
  static const Choices<std::string> kChoices = [] {
    Choices<std::string> c;
    for (const std::string& name : env_registry().names()) {
      c.emplace_back(name, name);
    }
    return c;
  }();
  return kChoices;
}

const Choices<hfo::ShotAim>& shot_aim_choices() {
  static const Choices<hfo::ShotAim> kChoices{{"best-course", hfo::ShotAim::kBestCourse},
                                              {"bottom-post", hfo::ShotAim::kBottomPost},
                                              {"bottom-side", hfo::ShotAim::kBottomSide},
                                              {"close-in", hfo::ShotAim::kCloseIn},
                                              {"close-in-post", hfo::ShotAim::kCloseInPost}};
  return kChoices;
}

ExperimentConfig parse_experiment_config(const std::string& toml_text, const std::string& source_name,
                                         const std::vector<std::string>& overrides) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    std::ostringstream ss;
    ss << source_name << ":" << e.source().begin.line << ": not valid TOML: " << e.description();
    throw std::runtime_error(ss.str());
  }
  std::map<std::string, std::string> set_by;
  std::string sets;
  for (const auto& o : overrides) {
    set_by[apply_override(root, o)] = o;
    sets += " --set " + o;
  }
  ExperimentConfig c;
  Reader reader(root, source_name, set_by);
  visit(reader, c);
  reader.reject_unknown();
  validate(c, overrides.empty() ? source_name : source_name + " with" + sets);
  return c;
}

ExperimentConfig load_experiment_config(const std::string& path, const std::vector<std::string>& overrides) {
  if (path.empty()) {
    return parse_experiment_config("", "defaults", overrides);
  }
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("cannot open config '" + path + "': check the path (presets: deploy/configs/*.toml)");
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_experiment_config(ss.str(), path, overrides);
}

std::string to_toml(const ExperimentConfig& config) {
  Writer w;
  visit(w, const_cast<ExperimentConfig&>(config));
  std::ostringstream ss;
  ss << w.root << "\n";
  return ss.str();
}

std::unique_ptr<Algorithm> make_learner(const ExperimentConfig& config, int obs_dim, const ActionSpace& space,
                                        uint64_t seed, std::optional<UpdateDevice> device) {
  AlgorithmArgs args;
  args.obs_dim = obs_dim;
  args.space = &space;
  args.ddpg = &config.ddpg;
  args.seed = seed;
  args.device = device.value_or(config.ddpg.device);
  const ExplorationConfig exploration = resolve_exploration(config, space);
  args.masked_actions = exploration.masked_actions;
  args.gates = exploration.gates;
  args.params = &config.algorithm_params;
  std::optional<ParameterPrior> prior;
  if (const auto& of = env_registry().find(config.env.name).parameter_prior) {
    prior = of(config.env.params);
  }
  args.prior = prior ? &*prior : nullptr;
  return make_algorithm(config.train.algorithm, args);
}

}  // namespace pamdp::app
