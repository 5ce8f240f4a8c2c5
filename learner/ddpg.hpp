// DDPG for parameterized action spaces (paper §4–5, reference §7.4): an actor that outputs
// one score per discrete action plus every continuous parameter, a critic Q(s, a) over the
// whole output vector, target networks, and the actor trained through dQ/da with the
// parameter gradients kept in bounds (inverting, zeroing or squashing).
//
// One update: critic step on the (optionally Monte-Carlo-mixed) TD target with target
// networks, then an actor step through the just-updated critic (critic parameter gradients of
// that pass discarded), then soft target updates. update() allocates nothing; not thread-safe.
//
// With demonstrations (demo_bc_weight > 0 and a batch of demonstrated transitions), the actor
// step also clones them (DDPGfD, Nair et al. 2018 "Overcoming exploration in RL with
// demonstrations"): L = -sum Q(s, pi(s)) over the batch + demo_bc_weight * sum 1/2 |pi(s_d) -
// a_d|^2 over the demonstrations where the critic rates the demonstrated action above the
// actor's own (the Q-filter), each output measured in units of half its range (scores and
// the demonstrated action's parameters; the other parameters carry no demonstration).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "core/action_space.hpp"
#include "core/bounds.hpp"
#include "core/mlp.hpp"
#include "core/optim.hpp"
#include "core/rng.hpp"
#include "learner/algorithm.hpp"
#include "learner/gradient_bounds.hpp"

namespace pamdp {

struct DdpgConfig {
  std::vector<int> hidden = {1024, 512, 256, 128};  // both networks, as in the paper
  double actor_learning_rate = 1e-3;
  double critic_learning_rate = 1e-3;
  double adam_beta1 = 0.95;
  double adam_beta2 = 0.999;
  double adam_epsilon = 1e-8;
  double gamma = 0.99;
  double tau = 1e-4;  // paper text (its code used 1e-3)
  int batch_size = 32;
  double clip_grad_norm = 10.0;  // global L2 norm per network; <= 0 disables
  BoundMethod bound = BoundMethod::kInverting;
  double mc_mix = 0.0;  // beta: y = beta * MC return + (1 - beta) * TD target
  // The target networks' value of the next state, Q'(s', mu'(s')), is clamped to [-c, c] before
  // it enters y; 0 disables. The target critic can rate the target actor's action far above
  // any return in the data (it extrapolates where no stored action lies), and that value then
  // feeds itself through the targets: a bound above the largest return an episode can earn
  // stops the loop without touching a target that lies inside it (docs/learning.md).
  double bootstrap_clip = 0.0;
  // Both learning rates fall linearly from their value to lr_final_fraction of it over the
  // first lr_decay_updates updates, then stay there; 0 keeps them constant (the paper).
  int64_t lr_decay_updates = 0;
  double lr_final_fraction = 0.1;
  double init_std = 0.01;
  double critic_output_init_std = 0.05;  // the paper-era code's critic output layer
  double critic_output_init_bias = 1.0;
  UpdateDevice device = UpdateDevice::kAuto;  // read by make_update_backend, not by Ddpg itself
  // Behaviour cloning of demonstrations (see the top of this file); 0 disables. CPU only.
  double demo_bc_weight = 0.0;
  bool demo_q_filter = true;  // clone only where Q(s, a_demo) > Q(s, pi(s))
  // A Polyak average of the online actor's weights, moving by this rate per update (it spans
  // ~1/tau updates), kept for evaluation only: training never reads it. The online actor's
  // quality swings by several points between evaluations; its average over a long window plays
  // steadier (Polyak & Juditsky 1992; for deep RL, Nikishin et al. 2018). 0 disables.
  double actor_average_tau = 0.0;
  // MP-DQN's PA-DDPG (cycraig/MP-DQN agents/paddpg.py) adds a fixed pass-through layer, the env's
  // hand-made parameter policy, to the actor's parameter outputs (core/passthrough.hpp): the
  // parameters start at that policy and the actor learns corrections to it. Needs an env with a
  // parameter_prior (envs/registry.hpp). CPU only.
  bool passthrough = false;
  // The actor's output layer's initial weight scale; 0: init_std (MP-DQN starts its hidden layers
  // at Kaiming's scale and its output layers at 0.01).
  double actor_output_init_std = 0.0;
  // Rewards (and Monte-Carlo returns) are multiplied by this in the critic's target (MP-DQN's
  // Goal runs scale by 1/50). CPU only when it is not 1.
  double reward_scale = 1.0;
};

class Ddpg {
 public:
  // `prior` is read when config.passthrough (std::invalid_argument when it is null or does not fit).
  Ddpg(int obs_dim, const ActionSpace& space, const DdpgConfig& config, uint64_t seed,
       const ParameterPrior* prior = nullptr);

  // The actor's output for one observation, as actors execute and store it (after the squash
  // when the method is squashing). Writes output_width() values.
  void act(std::span<const float> obs, std::span<float> out, ActorCopy copy = ActorCopy::kOnline);
  [[nodiscard]] int output_width() const { return bounds_.width(); }
  [[nodiscard]] int obs_dim() const { return obs_dim_; }
  [[nodiscard]] int num_actions() const { return num_actions_; }  // discrete scores before the parameters

  // `demos`, when given and demo_bc_weight > 0, is a batch of demonstrated transitions (states
  // and actions are read; at most batch_size of them) cloned by the actor step.
  UpdateStats update(const BatchView& batch, const BatchView* demos = nullptr);
  [[nodiscard]] int64_t updates() const { return updates_; }
  // Sets both optimizers' learning rates for the next update from the decay schedule and
  // updates(); update() calls it, and so does any other backend before each step.
  void schedule_learning_rates();
  void set_updates(int64_t n) { updates_ = n; }

  // Moves the actor average toward the online actor as far as the updates since the last call
  // would have moved it one update at a time: by 1 - (1 - actor_average_tau)^k, exact for an
  // actor that changed only at the last of the k updates and close (the window is ~1/tau, k ~100)
  // otherwise. Reads the host actor, so it is called where that is current: the backend's
  // sync_actor_to_host calls it. No-op with actor_average_tau = 0.
  void track_actor_average();
  // Restarts the average at the online actor, as of updates() (a warm start; a checkpoint
  // written without an average).
  void reset_actor_average();
  [[nodiscard]] bool averages_actor() const { return config_.actor_average_tau > 0.0; }
  Mlp<float>& actor_average() { return actor_average_; }
  [[nodiscard]] int64_t actor_average_updates() const { return actor_average_at_; }  // updates() it last absorbed
  void set_actor_average_updates(int64_t n) { actor_average_at_ = n; }

  [[nodiscard]] const DdpgConfig& config() const { return config_; }
  [[nodiscard]] const OutputBounds& bounds() const { return bounds_; }

  Mlp<float>& actor() { return actor_; }
  Mlp<float>& critic() { return critic_; }
  Mlp<float>& target_actor() { return target_actor_; }
  Mlp<float>& target_critic() { return target_critic_; }
  Adam<float>& actor_optimizer() { return actor_adam_; }
  Adam<float>& critic_optimizer() { return critic_adam_; }
  // The fixed pass-through layer (widths {obs, P}), shared by the actor, its target and its
  // average; all zeros and unused without config.passthrough.
  Mlp<float>& passthrough() { return passthrough_; }

 private:
  void actor_outputs(Mlp<float>& net, const Eigen::Ref<const Eigen::MatrixXf>& states, int batch, Eigen::MatrixXf& out);

  int obs_dim_;
  DdpgConfig config_;
  OutputBounds bounds_;
  Mlp<float> actor_;
  Mlp<float> critic_;
  Mlp<float> target_actor_;
  Mlp<float> target_critic_;
  Mlp<float> actor_average_;
  Mlp<float> passthrough_;
  int64_t actor_average_at_ = 0;
  Adam<float> actor_adam_;
  Adam<float> critic_adam_;
  int64_t updates_ = 0;
  int num_actions_ = 0;  // the discrete scores come first in the output; parameters follow

  // Scratch, sized in the constructor for batch_size (twice that with demonstrations: the
  // actor step runs the batch and the demonstrations as one).
  Eigen::MatrixXf critic_in_;            // (obs + width) x B
  Eigen::MatrixXf actions_;              // width x B (executed/squashed outputs)
  Eigen::MatrixXf pre_;                  // width x B: actor(s) + passthrough(s), before a squash
  Eigen::MatrixXf targets_;              // 1 x B
  Eigen::MatrixXf d_q_;                  // 1 x B
  Eigen::MatrixXf d_action_;             // width x B
  Eigen::MatrixXf single_in_;            // obs x 1
  Eigen::MatrixXf states_in_;            // obs x 2B: the batch's states, then the demonstrations'
  Eigen::MatrixXf demo_q_;               // 1 x B: Q(s_d, a_d)
  std::vector<float> bc_scale_;          // per output: 2 / (hi - lo), squared in the loss's gradient
  std::vector<std::vector<int>> owned_;  // per discrete action: its output rows (score, parameters)
};

}  // namespace pamdp
