// The fixed pass-through layer of MP-DQN's code (cycraig/MP-DQN, agents/pdqn.py and
// agents/paddpg.py, action_parameters_passthrough_layer): one linear layer {obs_dim, P} that
// holds an env's hand-made parameter policy (core/action_space.hpp, ParameterPrior) and is added
// to a network's parameter outputs, before any squash, for the whole run without being trained.
// P-DQN and MP-DQN (pdqn.passthrough) and PA-DDPG (ddpg.passthrough) start from it.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>

#include "core/action_space.hpp"
#include "core/mlp.hpp"

namespace pamdp {

// Writes `prior` into `layer` (widths {obs_dim, P}). Throws std::invalid_argument naming `key`
// when there is no prior or it does not fit the layer.
inline void load_passthrough(Mlp<float>& layer, const ParameterPrior* prior, const std::string& key) {
  const int obs_dim = layer.widths().front();
  const int num_params = layer.widths().back();
  if (prior == nullptr) {
    throw std::invalid_argument(key +
                                " = true starts the parameters from the env's hand-made parameter policy, and this env "
                                "has none (envs/registry.hpp, parameter_prior); set " +
                                key + " = false");
  }
  if (prior->obs_dim != obs_dim || prior->bias.size() != static_cast<size_t>(num_params) ||
      prior->weights.size() != static_cast<size_t>(obs_dim) * static_cast<size_t>(num_params)) {
    throw std::invalid_argument(key + ": the env's parameter policy does not fit its observation and parameter widths");
  }
  for (int p = 0; p < num_params; ++p) {
    for (int j = 0; j < obs_dim; ++j) {
      layer.weight(0)(p, j) = prior->weights[static_cast<size_t>(p * obs_dim + j)];
    }
    layer.bias(0)(p) = prior->bias[static_cast<size_t>(p)];
  }
}

}  // namespace pamdp
