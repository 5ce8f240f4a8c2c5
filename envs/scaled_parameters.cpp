#include "envs/scaled_parameters.hpp"

#include <cassert>
#include <cstddef>

namespace pamdp {
namespace {

float half_range(const ParamSpec& p) {
  return (p.hi - p.lo) / 2.0F;
}

float middle(const ParamSpec& p) {
  return (p.hi + p.lo) / 2.0F;
}

}  // namespace

ActionSpace scaled_action_space(const ActionSpace& space) {
  ActionSpace s = space;
  for (ParamSpec& p : s.params) {
    p.lo = -1.0F;
    p.hi = 1.0F;
  }
  return s;
}

ScaledParametersEnv::ScaledParametersEnv(std::unique_ptr<Env> inner)
    : inner_(std::move(inner)),
      space_(scaled_action_space(inner_->action_space())),
      params_(inner_->action_space().params.size(), 0.0F) {}

StepResult ScaledParametersEnv::step(const ParamAction& action, std::span<float> obs) {
  const std::vector<ParamSpec>& specs = inner_->action_space().params;
  const size_t n = std::min(action.params.size(), params_.size());
  for (size_t i = 0; i < n; ++i) {
    params_[i] = middle(specs[i]) + action.params[i] * half_range(specs[i]);
  }
  return inner_->step({action.id, std::span<const float>(params_.data(), n)}, obs);
}

std::unique_ptr<Env> scaled_if(bool scaled, std::unique_ptr<Env> env) {
  if (scaled) {
    return std::make_unique<ScaledParametersEnv>(std::move(env));
  }
  return env;
}

ParameterPrior prior_in_units_of(const ParameterPrior& scaled, const ActionSpace& space) {
  assert(scaled.bias.size() == space.params.size());
  ParameterPrior p = scaled;
  for (size_t i = 0; i < space.params.size(); ++i) {
    const float h = half_range(space.params[i]);
    for (int j = 0; j < p.obs_dim; ++j) {
      p.weights[i * static_cast<size_t>(p.obs_dim) + static_cast<size_t>(j)] *= h;
    }
    p.bias[i] = middle(space.params[i]) + h * scaled.bias[i];
  }
  return p;
}

ParameterPrior prior_in_scaled_units(const ParameterPrior& in_units, const ActionSpace& space) {
  assert(in_units.bias.size() == space.params.size());
  ParameterPrior p = in_units;
  for (size_t i = 0; i < space.params.size(); ++i) {
    const float h = half_range(space.params[i]);
    for (int j = 0; j < p.obs_dim; ++j) {
      p.weights[i * static_cast<size_t>(p.obs_dim) + static_cast<size_t>(j)] /= h;
    }
    p.bias[i] = (in_units.bias[i] - middle(space.params[i])) / h;
  }
  return p;
}

}  // namespace pamdp
