#include "actor/exploration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pamdp {

double linear_epsilon(int64_t updates, double start, double end, int64_t anneal) {
  if (anneal <= 0 || updates >= anneal) {
    return end;
  }
  const double frac = static_cast<double>(std::max<int64_t>(updates, 0)) / static_cast<double>(anneal);
  return start + (end - start) * frac;
}

double demo_share(int64_t updates, double fraction, int64_t anneal, double end) {
  if (anneal <= 0) {
    return fraction;
  }
  return linear_epsilon(updates, fraction, end, anneal);
}

int write_teacher_output(const ActionSpace& space, const ParamAction& a, std::span<const float> fill,
                         std::span<float> out) {
  const int num_actions = space.num_actions();
  std::copy(fill.begin(), fill.end(), out.begin());
  for (int k = 0; k < num_actions; ++k) {
    out[static_cast<size_t>(k)] = k == a.id ? 1.0F : -1.0F;
  }
  for (const int p : space.actions[static_cast<size_t>(a.id)].param_indices) {
    out[static_cast<size_t>(num_actions + p)] = a.params[static_cast<size_t>(p)];
  }
  return a.id;
}

double apex_epsilon(int actor_index, int num_actors, double base, double alpha) {
  if (num_actors <= 1) {
    return base;
  }
  return std::pow(base, 1.0 + alpha * actor_index / static_cast<double>(num_actors - 1));
}

EpsilonGreedy::EpsilonGreedy(const ActionSpace& space, const ExplorationConfig& config, uint64_t seed)
    : num_actions_(space.num_actions()), masked_(static_cast<size_t>(space.num_actions()), false), rng_(seed) {
  for (int a : config.masked_actions) {
    if (a < 0 || a >= num_actions_) {
      throw std::invalid_argument("exploration: masked action id out of range");
    }
    masked_[static_cast<size_t>(a)] = true;
  }
  if (std::all_of(masked_.begin(), masked_.end(), [](bool m) { return m; })) {
    throw std::invalid_argument("exploration: every action is masked");
  }
  for (const ActionGate& g : config.gates) {
    if (g.action < 0 || g.action >= num_actions_ || g.feature < 0) {
      throw std::invalid_argument("exploration: a gated action or its feature is out of range");
    }
  }
  gates_ = config.gates;
  if (!some_action_always_open(masked_, gates_)) {
    throw std::invalid_argument("exploration: every unmasked action is gated; leave one ungated");
  }
  for (const ParamSpec& p : space.params) {
    lo_.push_back(p.lo);
    hi_.push_back(p.hi);
  }
  bound_lo_ = lo_;
  bound_hi_ = hi_;
  uniform_random_params_ = config.uniform_random_params;
  if (!(config.param_noise >= 0.0 && config.param_noise <= 1.0)) {
    throw std::invalid_argument(
        "exploration: param_noise must lie in [0, 1] (a fraction of each parameter's half range)");
  }
  if (config.param_noise > 0.0) {
    for (size_t i = 0; i < bound_lo_.size(); ++i) {
      noise_std_.push_back(static_cast<float>(config.param_noise * 0.5 * (bound_hi_[i] - bound_lo_[i])));
    }
  }
  if (!config.random_param_lo.empty()) {
    if (config.random_param_lo.size() != lo_.size() || config.random_param_hi.size() != hi_.size()) {
      throw std::invalid_argument("exploration: random parameter ranges must list every parameter");
    }
    lo_ = config.random_param_lo;
    hi_ = config.random_param_hi;
  }
}

int EpsilonGreedy::greedy(std::span<const float> output) const {
  if (!gates_.empty()) {
    throw std::logic_error("EpsilonGreedy::greedy: with gated actions, pass the observation");
  }
  return greedy({}, output);
}

int EpsilonGreedy::greedy(std::span<const float> obs, std::span<const float> output) const {
  int best = -1;
  float best_score = -std::numeric_limits<float>::infinity();
  for (int a = 0; a < num_actions_; ++a) {
    const float s = output[static_cast<size_t>(a)];
    const bool shut = std::any_of(gates_.begin(), gates_.end(),
                                  [a, obs](const ActionGate& g) { return g.action == a && g.shut(obs); });
    if (!masked_[static_cast<size_t>(a)] && !shut && (best < 0 || s > best_score)) {
      best = a;
      best_score = s;
    }
  }
  return best;
}

int EpsilonGreedy::select(std::span<const float> net_output, double epsilon, std::span<float> stored) {
  if (!gates_.empty()) {
    throw std::logic_error("EpsilonGreedy::select: with gated actions, pass the observation");
  }
  return select({}, net_output, epsilon, stored);
}

int EpsilonGreedy::select(std::span<const float> obs, std::span<const float> net_output, double epsilon,
                          std::span<float> stored) {
  if (epsilon > 0.0 && rng_.uniform() < epsilon) {
    for (int a = 0; a < num_actions_; ++a) {
      stored[static_cast<size_t>(a)] = static_cast<float>(rng_.uniform(-1.0, 1.0));
    }
    if (uniform_random_params_) {
      for (size_t i = 0; i < lo_.size(); ++i) {
        stored[static_cast<size_t>(num_actions_) + i] = static_cast<float>(rng_.uniform(lo_[i], hi_[i]));
      }
    } else {
      std::copy(net_output.begin() + num_actions_, net_output.end(), stored.begin() + num_actions_);
    }
  } else {
    std::copy(net_output.begin(), net_output.end(), stored.begin());
    for (size_t i = 0; i < noise_std_.size(); ++i) {
      float& v = stored[static_cast<size_t>(num_actions_) + i];
      v = std::clamp(v + static_cast<float>(rng_.normal()) * noise_std_[i], bound_lo_[i], bound_hi_[i]);
    }
  }
  return greedy(obs, stored);
}

}  // namespace pamdp
