#include "learner/algorithm.hpp"

#include <stdexcept>

#include "learner/ddpg_algorithm.hpp"
#include "learner/pdqn.hpp"

namespace pamdp {

void AlgorithmRegistry::add(AlgorithmRegistration registration) {
  if (find(registration.name) != nullptr) {
    throw std::logic_error("algorithm '" + registration.name + "' is registered twice");
  }
  registrations_.push_back(std::move(registration));
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
