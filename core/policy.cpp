#include "core/policy.hpp"

#include <cmath>
#include <stdexcept>

namespace pamdp {

RandomPolicy::RandomPolicy(const ActionSpace& space, uint64_t seed, std::vector<int> allowed_actions)
    : allowed_(std::move(allowed_actions)), params_(space.params.size()), rng_(seed) {
  if (space.num_actions() == 0) {
    throw std::invalid_argument("RandomPolicy: the action space has no actions");
  }
  if (allowed_.empty()) {
    for (int i = 0; i < space.num_actions(); ++i) {
      allowed_.push_back(i);
    }
  }
  for (int a : allowed_) {
    if (a < 0 || a >= space.num_actions()) {
      throw std::invalid_argument("RandomPolicy: allowed action id out of range");
    }
  }
  for (const ParamSpec& p : space.params) {
    lo_.push_back(p.lo);
    hi_.push_back(p.hi);
  }
}

void RandomPolicy::set_param_range(int index, float lo, float hi) {
  if (!(lo <= hi) || !std::isfinite(lo) || !std::isfinite(hi)) {
    throw std::invalid_argument("RandomPolicy: parameter range needs finite lo <= hi");
  }
  lo_.at(static_cast<size_t>(index)) = lo;
  hi_.at(static_cast<size_t>(index)) = hi;
}

ParamAction RandomPolicy::act(std::span<const float> /*obs*/) {
  const int id = allowed_[rng_.below(allowed_.size())];
  for (size_t i = 0; i < params_.size(); ++i) {
    params_[i] = static_cast<float>(rng_.uniform(lo_[i], hi_[i]));
  }
  return {id, params_};
}

}  // namespace pamdp
