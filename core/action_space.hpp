// Parameterized action spaces (PAMDP): a finite set of discrete actions, each owning a subset
// of one shared vector of continuous parameters.
//
// The shared layout follows the paper's actor output: the network emits one score per discrete
// action and one value per parameter; discrete action k reads only the parameters listed in
// `actions[k].param_indices`. Every env describes itself with one ActionSpace, so the learner,
// the actors and exploration never need to know which env they drive.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace pamdp {

struct ParamSpec {
  std::string name;  // e.g. "dash_power"
  float lo = 0.0F;   // bounds the actor's output is kept within (paper §5, reference §7.4)
  float hi = 0.0F;
};

struct DiscreteActionSpec {
  std::string name;                // e.g. "DASH"
  std::vector<int> param_indices;  // indices into ActionSpace::params
};

struct ActionSpace {
  std::vector<DiscreteActionSpec> actions;
  std::vector<ParamSpec> params;

  [[nodiscard]] int num_actions() const { return static_cast<int>(actions.size()); }
  [[nodiscard]] int num_params() const { return static_cast<int>(params.size()); }
  // Width of the actor's output: one score per action plus every parameter.
  [[nodiscard]] int output_width() const { return num_actions() + num_params(); }
  // Index of the action with this name, or -1.
  [[nodiscard]] int find_action(std::string_view name) const;
};

// A hand-made policy for every continuous parameter, affine in the observation:
// x = weights * obs + bias, in the parameters' units as the action space declares them. An env
// may offer one (envs/registry.hpp, EnvRegistration::parameter_prior) for learners that start
// from it (P-DQN's pass-through layer, pdqn.passthrough).
struct ParameterPrior {
  int obs_dim = 0;
  std::vector<float> weights;  // num_params x obs_dim, row-major
  std::vector<float> bias;     // num_params
};

// An action that acts only where one observation feature is on (> 0), and is a no-op elsewhere:
// HFO's KICK without the kickable bit (feature 12), which the client never sends (librcsc's
// doKick; ../shared/hfo-reference.md §2.7). A learner told of a gate neither takes the action nor
// counts its value where the gate is shut (exploration.gated_actions).
struct ActionGate {
  int action = -1;
  int feature = -1;
  [[nodiscard]] bool shut(std::span<const float> obs) const { return !(obs[static_cast<size_t>(feature)] > 0.0F); }
};

// Whether some action is neither masked nor gated, so that every state leaves one to take.
[[nodiscard]] inline bool some_action_always_open(const std::vector<bool>& masked, std::span<const ActionGate> gates) {
  for (size_t a = 0; a < masked.size(); ++a) {
    if (!masked[a] && std::none_of(gates.begin(), gates.end(),
                                   [a](const ActionGate& g) { return g.action == static_cast<int>(a); })) {
      return true;
    }
  }
  return false;
}

// One chosen action: the discrete id and a view of the whole parameter vector (only the
// entries the action owns are read). Non-owning; valid for the duration of a step() call.
struct ParamAction {
  int id = 0;
  std::span<const float> params;
};

}  // namespace pamdp
