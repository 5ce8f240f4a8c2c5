#include "learner/algorithm.hpp"

#include <algorithm>
#include <stdexcept>

#include "learner/ddpg_algorithm.hpp"
#include "learner/pdqn.hpp"

namespace pamdp {

AlgorithmKey AlgorithmKey::real(std::string name, double default_value, double lo, double hi, std::string help) {
  return {std::move(name), default_value, lo, hi, std::move(help)};
}

AlgorithmKey AlgorithmKey::boolean(std::string name, bool default_value, std::string help) {
  return {std::move(name), default_value, 0.0, 0.0, std::move(help)};
}

namespace {

template <typename T>
T get(const std::map<std::string, AlgorithmValue, std::less<>>& values, std::string_view key, const char* type) {
  const auto it = values.find(key);
  if (it == values.end() || !std::holds_alternative<T>(it->second)) {
    throw std::logic_error("algorithm setting '" + std::string(key) + "' is not a declared " + type + " key");
  }
  return std::get<T>(it->second);
}

}  // namespace

double AlgorithmParams::real(std::string_view key) const {
  return get<double>(values_, key, "real");
}

bool AlgorithmParams::boolean(std::string_view key) const {
  return get<bool>(values_, key, "boolean");
}

void AlgorithmParams::set(const std::string& key, AlgorithmValue value) {
  values_.insert_or_assign(key, value);
}

AlgorithmValue& AlgorithmParams::at(std::string_view key) {
  const auto it = values_.find(key);
  if (it == values_.end()) {
    throw std::logic_error("algorithm setting '" + std::string(key) + "' is not declared by any registered algorithm");
  }
  return it->second;
}

void AlgorithmRegistry::add(AlgorithmRegistration registration) {
  if (find(registration.name) != nullptr) {
    throw std::logic_error("algorithm '" + registration.name + "' is registered twice");
  }
  for (const AlgorithmKey& k : registration.keys) {
    const auto same = std::find_if(keys_.begin(), keys_.end(), [&](const AlgorithmKey& o) { return o.name == k.name; });
    if (same == keys_.end()) {
      if (k.name.find('.') == std::string::npos || k.name.rfind("ddpg.", 0) == 0) {
        throw std::logic_error("algorithm '" + registration.name + "': key '" + k.name +
                               "' needs a section of its own (\"pdqn.q_tau\")");
      }
      keys_.push_back(k);
    } else if (!(*same == k)) {
      throw std::logic_error("algorithm '" + registration.name + "' declares key '" + k.name +
                             "' unlike an algorithm registered before");
    }
  }
  registrations_.push_back(std::move(registration));
}

AlgorithmParams AlgorithmRegistry::defaults() const {
  AlgorithmParams p;
  for (const AlgorithmKey& k : keys_) {
    p.set(k.name, k.default_value);
  }
  return p;
}

const AlgorithmRegistration* AlgorithmRegistry::find(std::string_view name) const {
  for (const AlgorithmRegistration& r : registrations_) {
    if (r.name == name) {
      return &r;
    }
  }
  return nullptr;
}

std::string AlgorithmRegistry::names() const {
  std::string s;
  for (const AlgorithmRegistration& r : registrations_) {
    s += (s.empty() ? "" : ", ") + r.name;
  }
  return s;
}

const AlgorithmRegistry& algorithm_registry() {
  static const AlgorithmRegistry kRegistry = [] {
    AlgorithmRegistry r;
    register_ddpg_algorithm(r);  // one line per algorithm
    register_pdqn_algorithms(r);
    return r;
  }();
  return kRegistry;
}

std::unique_ptr<Algorithm> make_algorithm(std::string_view name, const AlgorithmArgs& args) {
  const AlgorithmRegistration* r = algorithm_registry().find(name);
  if (r == nullptr) {
    throw std::runtime_error("unknown algorithm '" + std::string(name) + "' (train.algorithm); this build has " +
                             algorithm_registry().names());
  }
  return r->make(args);
}

}  // namespace pamdp
