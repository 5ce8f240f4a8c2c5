// P-DQN (Xiong et al. 2018, "Parametrized Deep Q-Networks Learning: Reinforcement Learning with
// Discrete-Continuous Hybrid Action Space") and MP-DQN (Bester, James & Konidaris 2019,
// "Multi-Pass Q-Networks for Deep Reinforcement Learning with Parameterised Action Spaces")
// behind the algorithm seam (learner/algorithm.hpp), registered as "pdqn" and "mpdqn".
//
// Networks: a parameter network x(s; θ) giving every action's parameters, and a Q-network
// Q(s, x; ω) giving one value per discrete action, each with a soft-updated target copy.
// MP-DQN differs only in how Q reads x: pass k sees action k's parameters alone
// (core/pdqn_output.hpp).
//
// One update on a batch of B transitions (s, a, r, s'), a = (scores, parameters) as stored, the
// taken action k the arg-max of the stored scores over the unmasked actions:
//   1. y = r + γ max_k' Q'(s', k', x'(s')) (0 after a terminal), the max over unmasked actions,
//      mixed with the Monte-Carlo return as DDPG does (ddpg.mc_mix);
//   2. Q step on (1 / 2B) Σ (Q(s, k, x_a) - y)², x_a the stored parameters (for MP-DQN, only
//      action k's, the others zero);
//   3. parameter step on L = -(1 / B) Σ_batch Σ_k Q(s, k, x(s)) over the unmasked k, through the
//      updated Q-network (its parameter gradients discarded), the gradient on x kept in bounds by
//      ddpg.bound (inverting by default, as cycraig/MP-DQN; squashing squashes x); with
//      pdqn.indexed_loss over the taken k alone, with pdqn.zero_index_gradients only the taken
//      action's parameters stepped, with pdqn.own_action_gradients each action's parameters on
//      its own Q alone;
//   4. soft target updates at rate ddpg.tau (pdqn.q_tau, pdqn.param_tau when set).
// Its own keys (declared at registration, the [pdqn] section, shared by both): separate target
// rates for the two networks, a reward scale, and MP-DQN's pass-through layer (PdqnSettings).
// It reads the ddpg.* settings (hidden widths for both networks, learning rates: actor for the
// parameter network, critic for the Q-network, Adam, γ, τ, batch, clipping, bound, Monte-Carlo
// mix, learning-rate decay, initialisation, and ddpg.actor_average_tau: a Polyak average of both
// networks the actors act with, which evaluations then play). It does not clone demonstrations,
// and runs on the CPU: a config that asks for those is refused.
//
// State names: networks "param", "q", "target_param", "target_q"; Adam moments "param_adam.m",
// "param_adam.v", "q_adam.m", "q_adam.v"; counters "updates", "param_adam.steps",
// "q_adam.steps"; with the pass-through layer, "param_passthrough" too; with an evaluation average,
// the optional "param_average" and "q_average" and the counter "average_updates". The actors get
// "param" and "q", and "param_passthrough" with the layer. update() allocates nothing.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/bounds.hpp"
#include "core/mlp.hpp"
#include "core/optim.hpp"
#include "core/pdqn_output.hpp"
#include "learner/algorithm.hpp"
#include "learner/ddpg.hpp"

namespace pamdp {

// The [pdqn] keys (pdqn_keys() declares them for the config file).
struct PdqnSettings {
  double q_tau = 0.0;      // the Q-network's target rate; 0: ddpg.tau
  double param_tau = 0.0;  // the parameter network's; 0: ddpg.tau
  // Rewards, and Monte-Carlo returns, are multiplied by this where they enter the Q target
  // (MP-DQN scales Goal's by 1/50). Returns and evaluations report the env's own rewards.
  double reward_scale = 1.0;
  // MP-DQN's pass-through layer (cycraig/MP-DQN agents/pdqn.py, action_parameters_passthrough_layer):
  // x(s) = net(s) + W s + b, with W and b the env's hand-made parameter policy
  // (AlgorithmArgs::prior), fixed for the whole run. The net's output layer then starts small
  // (param_output_init_std), so that x(s) starts at the hand-made policy.
  bool passthrough = false;
  double param_output_init_std = 0.0;  // the parameter network's output-layer weights; 0: ddpg.init_std
  // Two options of MP-DQN's code (cycraig/MP-DQN agents/pdqn.py, `indexed` and
  // `zero_index_gradients`; its run scripts leave both off). indexed_loss: the parameter loss takes
  // only each sample's taken action, L = -(1 / B) Σ_j Q(s_j, a_j, x(s_j)), instead of the sum over
  // the actions. zero_index_gradients: the gradient on x(s_j) keeps only the taken action's own
  // parameters (the others' are zeroed after the bound), so action k's parameters learn only from
  // samples that took k.
  bool indexed_loss = false;
  bool zero_index_gradients = false;
  // P-DQN only (MP-DQN's passes give it already): each action's parameters step on that action's
  // own Q alone, the gradient of Σ_k Q(s, k, x_k(s), x_-k(s) held fixed), so that no action's
  // value moves another's parameters. One input back-propagation per action with parameters.
  bool own_action_gradients = false;

  static PdqnSettings from(const AlgorithmParams& params);
};

// The keys above, as the registration declares them.
std::vector<AlgorithmKey> pdqn_keys();

class Pdqn final : public Algorithm {
 public:
  // `masked_actions` are never taken (HFO's Tackle): left out of the max and of the parameter loss.
  // `prior` is read when settings.passthrough (std::invalid_argument when it is null).
  Pdqn(int obs_dim, const ActionSpace& space, const DdpgConfig& config, uint64_t seed, bool multipass,
       std::vector<int> masked_actions = {}, const PdqnSettings& settings = {}, const ParameterPrior* prior = nullptr);

  // Actions that act only where their feature is on (core/action_space.hpp): where shut in a
  // state, left out of the max over its successor's actions, of the arg-max that recovers the
  // action a stored sample took, and of the parameter loss. std::invalid_argument for an action
  // or feature out of range, a masked action, or every unmasked action gated.
  void set_gates(std::vector<ActionGate> gates);

  [[nodiscard]] std::string_view name() const override { return multipass_ ? "mpdqn" : "pdqn"; }
  [[nodiscard]] int obs_dim() const override { return obs_dim_; }
  [[nodiscard]] int output_width() const override { return num_actions_ + num_params_; }
  [[nodiscard]] int batch_size() const override { return config_.batch_size; }
  [[nodiscard]] int64_t updates() const override { return updates_; }
  [[nodiscard]] const char* device() const override { return "cpu"; }

  UpdateStats update(const BatchView& batch, const BatchView* demos = nullptr) override;
  UpdateStats finish() override { return last_; }

  // Moves the evaluation average (ddpg.actor_average_tau > 0) toward the online networks as far as
  // the updates since the last call would have moved it one update at a time: by
  // 1 - (1 - tau)^k, as Ddpg::track_actor_average does for its actor.
  void sync_acting() override;
  // kAverage plays the average of both networks (std::logic_error without one).
  void act(std::span<const float> obs, std::span<float> out, ActorCopy copy = ActorCopy::kOnline) override;
  [[nodiscard]] ActorCopy evaluated_copy() const override {
    return averages() ? ActorCopy::kAverage : ActorCopy::kOnline;
  }
  [[nodiscard]] std::string evaluated_copy_note() const override;
  ActingWeights acting_weights() override;

  void sync_to_host() override {}
  std::vector<StateTensor> state_tensors() override;
  std::vector<StateCounter> state_counters() override;
  void restored(const std::vector<std::string>& missing) override;
  void warm_started() override { reset_average(); }  // this run's average starts at its start weights

  // The gradients of one update's two losses at the current weights, left in q_net().grads() and
  // param_net().grads() (the parameter loss through the current Q-network), with the losses'
  // values; nothing is stepped. For gradient checks; update() computes the same on the way.
  struct Losses {
    double q_loss = 0.0;
    double param_loss = 0.0;
  };
  Losses gradients(const BatchView& batch);
  // The two losses alone (no gradients), for finite differences.
  Losses losses(const BatchView& batch);

  Mlp<float>& param_net() { return param_; }
  Mlp<float>& q_net() { return q_; }
  Mlp<float>& target_param_net() { return target_param_; }
  Mlp<float>& target_q_net() { return target_q_; }
  // The fixed pass-through layer (widths {obs, P}); all zeros without settings.passthrough.
  Mlp<float>& passthrough_net() { return passthrough_; }
  // The evaluation average (kept when ddpg.actor_average_tau > 0), and the updates() it last absorbed.
  [[nodiscard]] bool averages() const { return config_.actor_average_tau > 0.0; }
  Mlp<float>& param_average() { return param_average_; }
  Mlp<float>& q_average() { return q_average_; }
  [[nodiscard]] int64_t average_updates() const { return average_at_; }

 private:
  // x(s) for the batch's states into x_ (and the raw outputs in the network).
  void parameters_of(Mlp<float>& net, const Eigen::Ref<const Eigen::MatrixXf>& states, int B);
  // Q-network inputs for B states and the parameters in `x` (P x B): one pass, or one pass per
  // unmasked action (action k's pass, pass_[k], in columns pass_[k]*B .. pass_[k]*B + B - 1,
  // holds only its parameters; a masked action, never in the max nor the loss, gets none).
  // Returns the columns.
  int fill_q_input(const Eigen::Ref<const Eigen::MatrixXf>& states, const Eigen::Ref<const Eigen::MatrixXf>& x, int B);
  // The same for each sample's own action `taken_`: one column per sample.
  void fill_taken_input(const Eigen::Ref<const Eigen::MatrixXf>& states, const Eigen::Ref<const Eigen::MatrixXf>& x,
                        int B);
  // Q(s, k, ·) of sample j from a forward over fill_q_input's columns.
  // Whether action k is open in column j of `states` (no gate of k is shut there).
  [[nodiscard]] bool open(int k, const Eigen::Ref<const Eigen::MatrixXf>& states, int j) const {
    for (const ActionGate& g : gates_) {
      if (g.action == k && !(states(g.feature, j) > 0.0F)) {
        return false;
      }
    }
    return true;
  }
  // Whether Q(s_j, k, x(s_j)) is in the parameter loss: k unmasked and open, and with
  // pdqn.indexed_loss the action sample j took (targets() sets taken_).
  [[nodiscard]] bool in_param_loss(int k, const Eigen::Ref<const Eigen::MatrixXf>& states, int j) const {
    if (settings_.indexed_loss) {
      return k == taken_[static_cast<size_t>(j)];
    }
    return !masked_[static_cast<size_t>(k)] && open(k, states, j);
  }
  [[nodiscard]] float q_of(const Mlp<float>::ConstBlock& q, int k, int j, int B) const {
    return multipass_ ? q(k, pass_[static_cast<size_t>(k)] * B + j) : q(k, j);
  }
  void targets(const BatchView& batch, int B);
  double q_step_gradient(const BatchView& batch, int B, UpdateStats& stats);
  double param_step_gradient(const BatchView& batch, int B, UpdateStats& stats);
  // pdqn.own_action_gradients: d_x_ from one input back-propagation per action, of that action's
  // Q over the samples whose loss holds it, kept on that action's parameters alone.
  void own_action_gradients(const Eigen::Ref<const Eigen::MatrixXf>& states, int B, float per_sample);
  void schedule_learning_rates();
  // Restarts the average at the online networks, as of updates_.
  void reset_average();

  int obs_dim_;
  int num_actions_;
  int num_params_;
  bool multipass_;
  DdpgConfig config_;
  PdqnSettings settings_;
  OutputBounds param_bounds_;
  std::vector<bool> masked_;
  std::vector<ActionGate> gates_;
  std::vector<int> owner_;  // per parameter: the action that owns it
  std::vector<std::vector<int>> owned_;
  std::vector<int> pass_;  // per action: its pass in a multi-pass batch, -1 when masked
  int num_passes_ = 0;
  Mlp<float> param_;
  Mlp<float> q_;
  Mlp<float> target_param_;
  Mlp<float> target_q_;
  Mlp<float> passthrough_;    // shared by the parameter network, its target and its average
  Mlp<float> param_average_;  // followed only when averages()
  Mlp<float> q_average_;
  int64_t average_at_ = 0;
  Adam<float> param_adam_;
  Adam<float> q_adam_;
  int64_t updates_ = 0;
  UpdateStats last_;
  PdqnForward forward_;
  std::array<int64_t, 4> counters_{};

  // Scratch, sized in the constructor for batch_size.
  Eigen::MatrixXf x_;       // P x B: parameters fed to the Q-network
  Eigen::MatrixXf pre_;     // P x B: net(s) + passthrough(s), before a squash (with the layer)
  Eigen::MatrixXf q_in_;    // (obs + P) x (K * B)
  Eigen::MatrixXf d_q_;     // K x (K * B)
  Eigen::MatrixXf d_x_;     // P x B
  Eigen::VectorXf y_;       // B
  std::vector<int> taken_;  // B
};

void register_pdqn_algorithms(AlgorithmRegistry& registry);

}  // namespace pamdp
