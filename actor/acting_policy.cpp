#include "actor/acting_policy.hpp"

#include <algorithm>
#include <stdexcept>

namespace pamdp {

void register_ddpg_acting_policy(ActingPolicyRegistry& registry);    // actor/ddpg_acting_policy.cpp
void register_pdqn_acting_policies(ActingPolicyRegistry& registry);  // actor/pdqn_acting_policy.cpp

void ActingPolicyRegistry::add(ActingPolicyRegistration registration) {
  if (find(registration.name) != nullptr) {
    throw std::logic_error("acting policy '" + registration.name + "' is registered twice");
  }
  registrations_.push_back(std::move(registration));
}

const ActingPolicyRegistration* ActingPolicyRegistry::find(std::string_view name) const {
  for (const ActingPolicyRegistration& r : registrations_) {
    if (r.name == name) {
      return &r;
    }
  }
  return nullptr;
}

std::string ActingPolicyRegistry::names() const {
  std::string s;
  for (const ActingPolicyRegistration& r : registrations_) {
    s += (s.empty() ? "" : ", ") + r.name;
  }
  return s;
}

void load_network(const NetworkView& n, std::unique_ptr<Mlp<float>>& net, int batch) {
  if (net == nullptr || !std::equal(n.widths.begin(), n.widths.end(), net->widths().begin(), net->widths().end())) {
    net = std::make_unique<Mlp<float>>(std::vector<int>(n.widths.begin(), n.widths.end()), batch);
  }
  std::copy(n.params.begin(), n.params.end(), net->params().begin());
}

const ActingPolicyRegistry& acting_policy_registry() {
  static const ActingPolicyRegistry kRegistry = [] {
    ActingPolicyRegistry r;
    register_ddpg_acting_policy(r);  // one line per algorithm
    register_pdqn_acting_policies(r);
    return r;
  }();
  return kRegistry;
}

}  // namespace pamdp
