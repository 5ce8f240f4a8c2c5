// The actor side of the algorithm seam (learner/algorithm.hpp): how an actor plays the networks a
// learner publishes. Each algorithm registers an acting policy under its own name; an actor
// builds the one the first PolicyWeights names, and loads every later message's networks into it.
// Its output for one observation is the algorithm's output vector (scores, then parameters),
// which ε-greedy exploration reads as it reads any other.
//
// Registration: `void register_<name>_acting_policy(ActingPolicyRegistry&)`, called from
// acting_policy_registry() in actor/acting_policy.cpp (one line each); see envs/registry.hpp for
// why not static registrar objects.
//
// act() allocates nothing; load() allocates only when the widths change. Not thread-safe.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/action_space.hpp"
#include "core/mlp.hpp"
#include "core/network_view.hpp"

namespace pamdp {

class ActingPolicy {
 public:
  virtual ~ActingPolicy() = default;

  // Why `networks` (each already checked to be a well-formed network of finite parameters)
  // cannot be played here: a network missing, or widths that do not fit the observations and
  // the output. Null when they can.
  [[nodiscard]] virtual const char* check(std::span<const NetworkView> networks, uint8_t bound) const = 0;
  // Takes the parameters of networks check() accepted.
  virtual void load(std::span<const NetworkView> networks, uint8_t bound) = 0;
  // The output vector (output_width values) for one observation.
  virtual void act(std::span<const float> obs, std::span<float> out) = 0;
  [[nodiscard]] virtual int64_t num_params() const = 0;
};

struct ActingPolicyRegistration {
  std::string name;  // the algorithm's registry name
  std::function<std::unique_ptr<ActingPolicy>(int obs_dim, const ActionSpace& space)> make;
};

class ActingPolicyRegistry {
 public:
  void add(ActingPolicyRegistration registration);  // std::logic_error when the name is taken
  [[nodiscard]] const ActingPolicyRegistration* find(std::string_view name) const;
  [[nodiscard]] std::string names() const;

 private:
  std::vector<ActingPolicyRegistration> registrations_;
};

const ActingPolicyRegistry& acting_policy_registry();

// Copies the parameters of `n` into `net`, which it makes anew (for batches of `batch` columns)
// only when there is none or its widths differ: on the first weights, or after a learner restart
// with other widths, not per message.
void load_network(const NetworkView& n, std::unique_ptr<Mlp<float>>& net, int batch);

}  // namespace pamdp
