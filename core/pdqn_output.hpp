// The output of a P-DQN or MP-DQN policy for one observation, as every player of one computes it
// (the learner's act() in learner/pdqn.cpp, and the actors' acting policy): the parameter
// network's x(s) for every action's parameters (squashed into their bounds when the learner
// bounds by squashing), then one Q-value per discrete action as its score, then x(s):
//   P-DQN (Xiong et al. 2018): Q(s, x(s)) in one pass, all parameters at once;
//   MP-DQN (Bester, James & Konidaris 2019): pass k sees only action k's parameters (the others
//   zero) and gives Q_k; the K passes run as one batch of K columns.
// So the output vector is laid out as DDPG's (scores, then parameters), and ε-greedy selection,
// replay and the wire treat it alike. Allocates nothing after construction.
#pragma once

#include <Eigen/Core>
#include <cassert>
#include <span>
#include <vector>

#include "core/action_space.hpp"
#include "core/bounds.hpp"
#include "core/mlp.hpp"

namespace pamdp {

// The parameters' own bounds (OutputBounds::for_actor without the scores).
inline OutputBounds parameter_bounds(const ActionSpace& space) {
  OutputBounds b;
  for (const ParamSpec& p : space.params) {
    b.lo.push_back(p.lo);
    b.hi.push_back(p.hi);
  }
  return b;
}

class PdqnForward {
 public:
  PdqnForward(int obs_dim, const ActionSpace& space, bool multipass)
      : obs_dim_(obs_dim),
        num_actions_(space.num_actions()),
        num_params_(space.num_params()),
        multipass_(multipass),
        state_(obs_dim, 1),
        q_in_(obs_dim + space.num_params(), multipass ? space.num_actions() : 1),
        x_(space.num_params()),
        pre_(space.num_params()) {
    for (const DiscreteActionSpec& a : space.actions) {
      owned_.push_back(a.param_indices);
    }
  }

  // `squash_into`: the parameter bounds when the learner squashes, else null. `passthrough`: a
  // fixed linear layer added to the parameter network's output (before a squash), or null. The
  // networks must take batches of K (multi-pass) or 1 columns.
  void operator()(Mlp<float>& param_net, Mlp<float>& q_net, const OutputBounds* squash_into, std::span<const float> obs,
                  std::span<float> out, Mlp<float>* passthrough = nullptr) {
    assert(static_cast<int>(obs.size()) == obs_dim_ && static_cast<int>(out.size()) == num_actions_ + num_params_);
    state_.col(0) = Eigen::Map<const Eigen::VectorXf>(obs.data(), obs_dim_);
    pre_ = param_net.forward(state_).col(0);
    if (passthrough != nullptr) {
      pre_ += passthrough->forward(state_).col(0);
    }
    if (squash_into != nullptr) {
      squash({pre_.data(), static_cast<size_t>(num_params_)}, *squash_into,
             {x_.data(), static_cast<size_t>(num_params_)});
    } else {
      x_ = pre_;
    }
    if (!multipass_) {
      q_in_.col(0).head(obs_dim_) = state_.col(0);
      q_in_.col(0).tail(num_params_) = x_;
      const auto q = q_net.forward(q_in_);
      for (int k = 0; k < num_actions_; ++k) {
        out[static_cast<size_t>(k)] = q(k, 0);
      }
    } else {
      for (int k = 0; k < num_actions_; ++k) {
        q_in_.col(k).head(obs_dim_) = state_.col(0);
        q_in_.col(k).tail(num_params_).setZero();
        for (const int p : owned_[static_cast<size_t>(k)]) {
          q_in_(obs_dim_ + p, k) = x_(p);
        }
      }
      const auto q = q_net.forward(q_in_);
      for (int k = 0; k < num_actions_; ++k) {
        out[static_cast<size_t>(k)] = q(k, k);
      }
    }
    for (int p = 0; p < num_params_; ++p) {
      out[static_cast<size_t>(num_actions_ + p)] = x_(p);
    }
  }

  [[nodiscard]] int passes() const { return multipass_ ? num_actions_ : 1; }

 private:
  int obs_dim_;
  int num_actions_;
  int num_params_;
  bool multipass_;
  std::vector<std::vector<int>> owned_;
  Eigen::MatrixXf state_;  // obs x 1
  Eigen::MatrixXf q_in_;   // (obs + P) x passes
  Eigen::VectorXf x_;      // P
  Eigen::VectorXf pre_;    // P: before a squash
};

}  // namespace pamdp
