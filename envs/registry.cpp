#include "envs/registry.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace pamdp {
namespace {

template <typename T>
const T& get(const std::map<std::string, EnvValue, std::less<>>& values, std::string_view key, const char* type) {
  const auto it = values.find(key);
  if (it == values.end() || !std::holds_alternative<T>(it->second)) {
    throw std::logic_error("env setting '" + std::string(key) + "' is " +
                           (it == values.end() ? "not declared by any registered env" : "not a " + std::string(type)));
  }
  return std::get<T>(it->second);
}

}  // namespace

bool EnvParams::boolean(std::string_view key) const {
  return get<bool>(values_, key, "boolean");
}

int64_t EnvParams::integer(std::string_view key) const {
  return get<int64_t>(values_, key, "integer");
}

const std::string& EnvParams::text(std::string_view key) const {
  return get<std::string>(values_, key, "string");
}

void EnvParams::set(const std::string& key, EnvValue value) {
  values_.insert_or_assign(key, std::move(value));
}

EnvValue& EnvParams::at(std::string_view key) {
  const auto it = values_.find(key);
  if (it == values_.end()) {
    throw std::logic_error("env setting '" + std::string(key) + "' is not declared by any registered env");
  }
  return it->second;
}

EnvKey EnvKey::boolean(std::string name, bool default_value) {
  return {std::move(name), Type::kBoolean, default_value, 0, 0, {}};
}

EnvKey EnvKey::integer(std::string name, int64_t default_value, int64_t lo, int64_t hi) {
  return {std::move(name), Type::kInteger, default_value, lo, hi, {}};
}

EnvKey EnvKey::text(std::string name, std::string default_value) {
  return {std::move(name), Type::kText, std::move(default_value), 0, 0, {}};
}

EnvKey EnvKey::text_or_empty(std::string name, std::string default_value) {
  return {std::move(name), Type::kTextOrEmpty, std::move(default_value), 0, 0, {}};
}

EnvKey EnvKey::choice(std::string name, std::string default_value, std::vector<std::string> choices) {
  return {std::move(name), Type::kChoice, std::move(default_value), 0, 0, std::move(choices)};
}

void EnvRegistry::add(EnvRegistration registration) {
  const std::string& name = registration.name;
  if (name.empty() || !registration.make || !registration.observation_size) {
    throw std::logic_error("env registration '" + name + "': needs a name, make and observation_size");
  }
  if (find_if(name) != nullptr) {
    throw std::logic_error("env '" + name + "' is registered twice");
  }
  // Shared keys are stored once in the config; two envs declaring one differently would make its
  // default depend on the registration order.
  std::vector<EnvKey> added;
  for (const EnvKey& key : registration.keys) {
    const auto same_name = [&key](const EnvKey& k) { return k.name == key.name; };
    const auto known = std::find_if(keys_.begin(), keys_.end(), same_name);
    if (known == keys_.end()) {
      if (std::find_if(added.begin(), added.end(), same_name) != added.end()) {
        throw std::logic_error("env '" + name + "' declares key '" + key.name + "' twice");
      }
      added.push_back(key);
    } else if (!(*known == key)) {
      throw std::logic_error("env '" + name + "' declares key '" + key.name +
                             "' differently from an env registered before it");
    }
  }
  keys_.insert(keys_.end(), added.begin(), added.end());
  envs_.push_back(std::move(registration));
}

const EnvRegistration* EnvRegistry::find_if(std::string_view name) const {
  for (const EnvRegistration& e : envs_) {
    if (e.name == name) {
      return &e;
    }
  }
  return nullptr;
}

const EnvRegistration& EnvRegistry::find(std::string_view name) const {
  if (const EnvRegistration* e = find_if(name)) {
    return *e;
  }
  throw std::runtime_error("env.name '" + std::string(name) + "' is unknown (valid: " + names_joined() + ")");
}

std::vector<std::string> EnvRegistry::names() const {
  std::vector<std::string> out;
  out.reserve(envs_.size());
  for (const EnvRegistration& e : envs_) {
    out.push_back(e.name);
  }
  return out;
}

std::string EnvRegistry::names_joined() const {
  std::string out;
  for (const EnvRegistration& e : envs_) {
    out += (out.empty() ? "" : ", ") + e.name;
  }
  return out;
}

EnvParams EnvRegistry::defaults() const {
  EnvParams p;
  for (const EnvKey& k : keys_) {
    p.set(k.name, k.default_value);
  }
  return p;
}

bool EnvRegistry::reads(std::string_view name, std::string_view key) const {
  const EnvRegistration& e = find(name);
  return std::any_of(e.keys.begin(), e.keys.end(), [key](const EnvKey& k) { return k.name == key; });
}

}  // namespace pamdp
