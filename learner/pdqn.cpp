#include "learner/pdqn.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/passthrough.hpp"
#include "learner/gradient_bounds.hpp"

namespace pamdp {
namespace {

std::vector<int> widths(int in, const std::vector<int>& hidden, int out) {
  std::vector<int> w{in};
  w.insert(w.end(), hidden.begin(), hidden.end());
  w.push_back(out);
  return w;
}

AdamConfig adam(const DdpgConfig& c, double lr) {
  return {lr, c.adam_beta1, c.adam_beta2, c.adam_epsilon};
}

const DdpgConfig& checked(const DdpgConfig& c, bool multipass) {
  const std::string name = multipass ? "mpdqn" : "pdqn";
  if (c.batch_size < 1) {
    throw std::invalid_argument("ddpg.batch_size must be >= 1");
  }
  if (c.demo_bc_weight > 0.0) {
    throw std::invalid_argument("ddpg.demo_bc_weight: " + name +
                                " does not clone demonstrations; set it to 0 (or train.algorithm = \"ddpg\")");
  }
  if (!(c.actor_average_tau >= 0.0 && c.actor_average_tau <= 1.0)) {
    throw std::invalid_argument("ddpg.actor_average_tau must be in [0, 1]");
  }
  // PA-DDPG's own forms of P-DQN's keys: these learners read pdqn.* instead.
  const auto not_here = [&](bool set, const std::string& key, const std::string& theirs, const char* unset) {
    if (set) {
      throw std::invalid_argument(key + " is PA-DDPG's (train.algorithm = \"ddpg\"); " + name + " takes " + theirs +
                                  ": set that instead, and " + key + " = " + unset);
    }
  };
  not_here(c.passthrough, "ddpg.passthrough", "pdqn.passthrough", "false");
  not_here(c.actor_output_init_std != 0.0, "ddpg.actor_output_init_std", "pdqn.param_output_init_std", "0");
  not_here(c.reward_scale != 1.0, "ddpg.reward_scale", "pdqn.reward_scale", "1");
  if (c.device == UpdateDevice::kCuda) {
    throw std::invalid_argument("ddpg.device = cuda: " + name +
                                " updates on the CPU only; set ddpg.device = \"cpu\" or \"auto\"");
  }
  return c;
}

constexpr const char* kQTau = "pdqn.q_tau";
constexpr const char* kParamTau = "pdqn.param_tau";
constexpr const char* kRewardScale = "pdqn.reward_scale";
constexpr const char* kPassthrough = "pdqn.passthrough";
constexpr const char* kParamOutputInitStd = "pdqn.param_output_init_std";
constexpr const char* kIndexedLoss = "pdqn.indexed_loss";
constexpr const char* kZeroIndexGradients = "pdqn.zero_index_gradients";
constexpr const char* kOwnActionGradients = "pdqn.own_action_gradients";
constexpr const char* kParamAverage = "param_average";
constexpr const char* kQAverage = "q_average";

}  // namespace

std::vector<AlgorithmKey> pdqn_keys() {
  return {
      AlgorithmKey::real(kQTau, 0.0, 0.0, 1.0, "the Q-network's target rate; 0: ddpg.tau"),
      AlgorithmKey::real(kParamTau, 0.0, 0.0, 1.0, "the parameter network's target rate; 0: ddpg.tau"),
      AlgorithmKey::real(kRewardScale, 1.0, 1e-9, 1e9,
                         "rewards (and Monte-Carlo returns) are multiplied by this in the Q target"),
      AlgorithmKey::boolean(kPassthrough, false,
                            "add the env's hand-made parameter policy to the parameter network as a fixed layer"),
      AlgorithmKey::real(kParamOutputInitStd, 0.0, 0.0, 10.0,
                         "the parameter network's output-layer initial weight scale; 0: ddpg.init_std"),
      AlgorithmKey::boolean(kIndexedLoss, false,
                            "the parameter loss takes each sample's taken action alone, not the sum over actions"),
      AlgorithmKey::boolean(kZeroIndexGradients, false,
                            "the parameter step moves only the taken action's parameters of each sample"),
      AlgorithmKey::boolean(
          kOwnActionGradients, false,
          "P-DQN: each action's parameters step on that action's own Q alone (MP-DQN has it already)"),
  };
}

PdqnSettings PdqnSettings::from(const AlgorithmParams& params) {
  PdqnSettings s;
  s.q_tau = params.real(kQTau);
  s.param_tau = params.real(kParamTau);
  s.reward_scale = params.real(kRewardScale);
  s.passthrough = params.boolean(kPassthrough);
  s.param_output_init_std = params.real(kParamOutputInitStd);
  s.indexed_loss = params.boolean(kIndexedLoss);
  s.zero_index_gradients = params.boolean(kZeroIndexGradients);
  s.own_action_gradients = params.boolean(kOwnActionGradients);
  return s;
}

Pdqn::Pdqn(int obs_dim, const ActionSpace& space, const DdpgConfig& config, uint64_t seed, bool multipass,
           std::vector<int> masked_actions, const PdqnSettings& settings, const ParameterPrior* prior)
    : obs_dim_(obs_dim),
      num_actions_(space.num_actions()),
      num_params_(space.num_params()),
      multipass_(multipass),
      config_(checked(config, multipass)),
      settings_(settings),
      param_bounds_(parameter_bounds(space)),
      masked_(static_cast<size_t>(space.num_actions()), false),
      owner_(static_cast<size_t>(space.num_params()), 0),
      param_(widths(obs_dim, config.hidden, space.num_params()), config.batch_size),
      q_(widths(obs_dim + space.num_params(), config.hidden, space.num_actions()),
         (multipass ? space.num_actions() : 1) * config.batch_size),
      target_param_(param_.widths(), config.batch_size),
      target_q_(q_.widths(), (multipass ? space.num_actions() : 1) * config.batch_size),
      passthrough_({obs_dim, space.num_params()}, config.batch_size),
      param_average_(param_.widths(), 1),
      q_average_(q_.widths(), multipass ? space.num_actions() : 1),
      param_adam_(param_.num_params(), adam(config, config.actor_learning_rate)),
      q_adam_(q_.num_params(), adam(config, config.critic_learning_rate)),
      forward_(obs_dim, space, multipass),
      x_(space.num_params(), config.batch_size),
      pre_(space.num_params(), config.batch_size),
      q_in_(obs_dim + space.num_params(), (multipass ? space.num_actions() : 1) * config.batch_size),
      d_q_(space.num_actions(), (multipass ? space.num_actions() : 1) * config.batch_size),
      d_x_(space.num_params(), config.batch_size),
      y_(config.batch_size),
      taken_(static_cast<size_t>(config.batch_size), 0) {
  if (space.num_params() < 1) {
    throw std::invalid_argument("P-DQN needs an action space with continuous parameters");
  }
  for (const int k : masked_actions) {
    if (k >= 0 && k < num_actions_) {
      masked_[static_cast<size_t>(k)] = true;
    }
  }
  if (std::all_of(masked_.begin(), masked_.end(), [](bool m) { return m; })) {
    throw std::invalid_argument("every action is masked: unmask at least one (exploration.masked_actions)");
  }
  for (int k = 0; k < num_actions_; ++k) {
    pass_.push_back(masked_[static_cast<size_t>(k)] ? -1 : num_passes_++);
    owned_.push_back(space.actions[static_cast<size_t>(k)].param_indices);
    for (const int p : owned_.back()) {
      owner_[static_cast<size_t>(p)] = k;
    }
  }
  Rng rng(seed);
  const auto s = static_cast<float>(config.init_std);
  param_.init_gaussian(rng, s, static_cast<float>(settings_.param_output_init_std));
  q_.init_gaussian(rng, s, static_cast<float>(config.critic_output_init_std),
                   static_cast<float>(config.critic_output_init_bias));
  std::copy(param_.params().begin(), param_.params().end(), target_param_.params().begin());
  std::copy(q_.params().begin(), q_.params().end(), target_q_.params().begin());
  if (settings_.passthrough) {  // else the layer keeps the zeros it was made with
    load_passthrough(passthrough_, prior, kPassthrough);
  }
  reset_average();
}

void Pdqn::reset_average() {
  std::copy(param_.params().begin(), param_.params().end(), param_average_.params().begin());
  std::copy(q_.params().begin(), q_.params().end(), q_average_.params().begin());
  average_at_ = updates_;
}

void Pdqn::sync_acting() {
  const int64_t k = updates_ - average_at_;
  if (!averages() || k <= 0) {
    return;
  }
  const double rate = soft_update_rate(config_.actor_average_tau, k);
  soft_update<float>(param_average_.params(), param_.params(), rate);
  soft_update<float>(q_average_.params(), q_.params(), rate);
  average_at_ = updates_;
}

std::string Pdqn::evaluated_copy_note() const {
  if (!averages()) {
    return {};
  }
  std::ostringstream s;
  s << "evaluations and best.ckpt play the average of the parameter and Q-networks (ddpg.actor_average_tau = "
    << config_.actor_average_tau << ")";
  return s.str();
}

void Pdqn::set_gates(std::vector<ActionGate> gates) {
  for (const ActionGate& g : gates) {
    if (g.action < 0 || g.action >= num_actions_ || g.feature < 0 || g.feature >= obs_dim_) {
      throw std::invalid_argument("P-DQN: a gated action or its feature is out of range");
    }
    if (masked_[static_cast<size_t>(g.action)]) {
      throw std::invalid_argument("P-DQN: action " + std::to_string(g.action) +
                                  " is both masked and gated; list it in one of exploration.masked_actions and "
                                  "exploration.gated_actions");
    }
  }
  if (!some_action_always_open(masked_, gates)) {
    throw std::invalid_argument("P-DQN: every unmasked action is gated; leave one ungated");
  }
  gates_ = std::move(gates);
}

void Pdqn::act(std::span<const float> obs, std::span<float> out, ActorCopy copy) {
  if (copy == ActorCopy::kAverage && !averages()) {
    throw std::logic_error("P-DQN: no evaluation average is kept (ddpg.actor_average_tau = 0)");
  }
  Mlp<float>* param = &param_;
  Mlp<float>* q = &q_;
  if (copy == ActorCopy::kTarget) {
    param = &target_param_;
    q = &target_q_;
  } else if (copy == ActorCopy::kAverage) {
    param = &param_average_;
    q = &q_average_;
  }
  forward_(*param, *q, config_.bound == BoundMethod::kSquashing ? &param_bounds_ : nullptr, obs, out,
           settings_.passthrough ? &passthrough_ : nullptr);
}

ActingWeights Pdqn::acting_weights() {
  ActingWeights w{name(),
                  static_cast<uint8_t>(config_.bound),
                  {{"param", param_.widths(), param_.params()}, {"q", q_.widths(), q_.params()}}};
  if (settings_.passthrough) {
    w.networks.push_back({"param_passthrough", passthrough_.widths(), passthrough_.params()});
  }
  return w;
}

void Pdqn::parameters_of(Mlp<float>& net, const Eigen::Ref<const Eigen::MatrixXf>& states, int B) {
  const auto net_out = net.forward(states.leftCols(B));
  if (settings_.passthrough) {
    pre_.leftCols(B) = net_out;
    pre_.leftCols(B) += passthrough_.forward(states.leftCols(B));
  }
  const Eigen::Ref<const Eigen::MatrixXf> raw = settings_.passthrough
                                                    ? Eigen::Ref<const Eigen::MatrixXf>(pre_.leftCols(B))
                                                    : Eigen::Ref<const Eigen::MatrixXf>(net_out);
  if (config_.bound == BoundMethod::kSquashing) {
    for (int j = 0; j < B; ++j) {
      squash({raw.col(j).data(), static_cast<size_t>(num_params_)}, param_bounds_,
             {x_.col(j).data(), static_cast<size_t>(num_params_)});
    }
  } else {
    x_.leftCols(B) = raw;
  }
}

int Pdqn::fill_q_input(const Eigen::Ref<const Eigen::MatrixXf>& states, const Eigen::Ref<const Eigen::MatrixXf>& x,
                       int B) {
  if (!multipass_) {
    q_in_.topLeftCorner(obs_dim_, B) = states.leftCols(B);
    q_in_.bottomLeftCorner(num_params_, B) = x.leftCols(B);
    return B;
  }
  for (int k = 0; k < num_actions_; ++k) {
    const int pass = pass_[static_cast<size_t>(k)];
    if (pass < 0) {
      continue;  // a masked action's Q is never read
    }
    q_in_.block(0, pass * B, obs_dim_, B) = states.leftCols(B);
    q_in_.block(obs_dim_, pass * B, num_params_, B).setZero();
    for (const int p : owned_[static_cast<size_t>(k)]) {
      q_in_.block(obs_dim_ + p, pass * B, 1, B) = x.block(p, 0, 1, B);
    }
  }
  return num_passes_ * B;
}

void Pdqn::fill_taken_input(const Eigen::Ref<const Eigen::MatrixXf>& states, const Eigen::Ref<const Eigen::MatrixXf>& x,
                            int B) {
  q_in_.topLeftCorner(obs_dim_, B) = states.leftCols(B);
  q_in_.bottomLeftCorner(num_params_, B) = x.leftCols(B);
  if (multipass_) {
    for (int j = 0; j < B; ++j) {
      for (int p = 0; p < num_params_; ++p) {
        if (owner_[static_cast<size_t>(p)] != taken_[static_cast<size_t>(j)]) {
          q_in_(obs_dim_ + p, j) = 0.0F;
        }
      }
    }
  }
}

void Pdqn::targets(const BatchView& batch, int B) {
  parameters_of(target_param_, batch.next_states, B);
  const int cols = fill_q_input(batch.next_states, x_, B);
  const auto q_next = target_q_.forward(q_in_.leftCols(cols));
  const auto g = static_cast<float>(config_.gamma);
  const auto beta = static_cast<float>(config_.mc_mix);
  const auto scale = static_cast<float>(settings_.reward_scale);
  const auto clip = static_cast<float>(config_.bootstrap_clip);
  for (int j = 0; j < B; ++j) {
    float best = -std::numeric_limits<float>::infinity();
    for (int k = 0; k < num_actions_; ++k) {
      if (!masked_[static_cast<size_t>(k)] && open(k, batch.next_states, j)) {
        best = std::max(best, q_of(q_next, k, j, B));
      }
    }
    if (clip > 0.0F) {
      best = std::clamp(best, -clip, clip);
    }
    float y = scale * batch.rewards(j) + (batch.terminal(j) > 0.5F ? 0.0F : g * best);
    if (beta > 0.0F) {
      y = beta * scale * batch.mc_returns(j) + (1.0F - beta) * y;
    }
    y_(j) = y;
  }
  // The action each sample took: the arg-max of its stored scores over the unmasked actions open
  // in its state (as the actor chose it: actor/exploration.cpp).
  for (int j = 0; j < B; ++j) {
    int k_best = -1;
    for (int k = 0; k < num_actions_; ++k) {
      if (!masked_[static_cast<size_t>(k)] && open(k, batch.states, j) &&
          (k_best < 0 || batch.actions(k, j) > batch.actions(k_best, j))) {
        k_best = k;
      }
    }
    taken_[static_cast<size_t>(j)] = k_best;
  }
}

double Pdqn::q_step_gradient(const BatchView& batch, int B, UpdateStats& stats) {
  fill_taken_input(batch.states, batch.actions.bottomRows(num_params_), B);
  const auto q = q_.forward(q_in_.leftCols(B));
  d_q_.leftCols(B).setZero();
  double loss = 0.0;
  for (int j = 0; j < B; ++j) {
    const int k = taken_[static_cast<size_t>(j)];
    const float diff = q(k, j) - y_(j);
    loss += 0.5 * static_cast<double>(diff) * diff;
    d_q_(k, j) = diff / static_cast<float>(B);
    stats.q_mean += q(k, j);
    stats.target_mean += y_(j);
  }
  stats.q_mean /= static_cast<float>(B);
  stats.target_mean /= static_cast<float>(B);
  q_.backward(d_q_.leftCols(B), false);
  return loss / B;
}

double Pdqn::param_step_gradient(const BatchView& batch, int B, UpdateStats& stats) {
  parameters_of(param_, batch.states, B);
  int at_bound = 0;
  for (int j = 0; j < B; ++j) {
    for (int p = 0; p < num_params_; ++p) {
      const float v = x_(p, j);
      at_bound +=
          (v <= param_bounds_.lo[static_cast<size_t>(p)] || v >= param_bounds_.hi[static_cast<size_t>(p)]) ? 1 : 0;
    }
  }
  stats.params_at_bound_fraction = static_cast<float>(at_bound) / static_cast<float>(num_params_ * B);
  const int cols = fill_q_input(batch.states, x_, B);
  const auto q = q_.forward(q_in_.leftCols(cols));
  d_q_.leftCols(cols).setZero();
  double loss = 0.0;
  const float per_sample = -1.0F / static_cast<float>(B);
  for (int j = 0; j < B; ++j) {
    for (int k = 0; k < num_actions_; ++k) {
      if (in_param_loss(k, batch.states, j)) {
        loss -= q_of(q, k, j, B);
        d_q_(k, multipass_ ? pass_[static_cast<size_t>(k)] * B + j : j) = per_sample;
      }
    }
  }
  if (settings_.own_action_gradients && !multipass_) {
    own_action_gradients(batch.states, B, per_sample);
  } else {
    q_.backward_input(d_q_.leftCols(cols));  // only dL/dx: the Q-network's parameter gradients are not needed
    const auto in_grad = q_.input_grad();
    for (int j = 0; j < B; ++j) {
      for (int p = 0; p < num_params_; ++p) {
        // In a multi-pass batch x_p reaches Q only through the pass of the action that owns it (a
        // masked action has none: its parameters get no gradient, as its Q is not in the loss).
        const int pass = multipass_ ? pass_[static_cast<size_t>(owner_[static_cast<size_t>(p)])] : 0;
        d_x_(p, j) = pass < 0 ? 0.0F : in_grad(obs_dim_ + p, pass * B + j);
      }
    }
  }
  if (settings_.passthrough) {
    apply_gradient_bounds(config_.bound, param_bounds_, x_.leftCols(B), pre_.leftCols(B), d_x_.leftCols(B));
  } else {
    apply_gradient_bounds(config_.bound, param_bounds_, x_.leftCols(B), param_.output(), d_x_.leftCols(B));
  }
  if (settings_.zero_index_gradients) {
    for (int j = 0; j < B; ++j) {
      for (int p = 0; p < num_params_; ++p) {
        if (owner_[static_cast<size_t>(p)] != taken_[static_cast<size_t>(j)]) {
          d_x_(p, j) = 0.0F;
        }
      }
    }
  }
  param_.backward(d_x_.leftCols(B), false);
  return loss / B;
}

void Pdqn::own_action_gradients(const Eigen::Ref<const Eigen::MatrixXf>& states, int B, float per_sample) {
  d_x_.leftCols(B).setZero();  // a parameter no action owns gets none
  for (int k = 0; k < num_actions_; ++k) {
    const std::vector<int>& owned = owned_[static_cast<size_t>(k)];
    if (owned.empty()) {
      continue;
    }
    d_q_.leftCols(B).setZero();
    bool any = false;
    for (int j = 0; j < B; ++j) {
      if (in_param_loss(k, states, j)) {
        d_q_(k, j) = per_sample;
        any = true;
      }
    }
    if (!any) {
      continue;
    }
    q_.backward_input(d_q_.leftCols(B));  // the forward of param_step_gradient is still in place
    const auto in_grad = q_.input_grad();
    for (int j = 0; j < B; ++j) {
      for (const int p : owned) {
        d_x_(p, j) = in_grad(obs_dim_ + p, j);
      }
    }
  }
}

Pdqn::Losses Pdqn::gradients(const BatchView& batch) {
  const int B = static_cast<int>(batch.states.cols());
  UpdateStats stats;
  Losses l;
  targets(batch, B);
  l.q_loss = q_step_gradient(batch, B, stats);
  l.param_loss = param_step_gradient(batch, B, stats);
  return l;
}

Pdqn::Losses Pdqn::losses(const BatchView& batch) {
  const int B = static_cast<int>(batch.states.cols());
  Losses l;
  targets(batch, B);
  fill_taken_input(batch.states, batch.actions.bottomRows(num_params_), B);
  const auto q = q_.forward(q_in_.leftCols(B));
  for (int j = 0; j < B; ++j) {
    const float diff = q(taken_[static_cast<size_t>(j)], j) - y_(j);
    l.q_loss += 0.5 * static_cast<double>(diff) * diff / B;
  }
  parameters_of(param_, batch.states, B);
  const int cols = fill_q_input(batch.states, x_, B);
  const auto qx = q_.forward(q_in_.leftCols(cols));
  for (int j = 0; j < B; ++j) {
    for (int k = 0; k < num_actions_; ++k) {
      if (in_param_loss(k, batch.states, j)) {
        l.param_loss -= static_cast<double>(q_of(qx, k, j, B)) / B;
      }
    }
  }
  return l;
}

void Pdqn::schedule_learning_rates() {
  if (config_.lr_decay_updates <= 0) {
    return;
  }
  const double done = std::min(1.0, static_cast<double>(updates_) / static_cast<double>(config_.lr_decay_updates));
  const double scale = 1.0 - (1.0 - config_.lr_final_fraction) * done;
  param_adam_.set_learning_rate(config_.actor_learning_rate * scale);
  q_adam_.set_learning_rate(config_.critic_learning_rate * scale);
}

UpdateStats Pdqn::update(const BatchView& batch, const BatchView* /*demos*/) {
  const int B = static_cast<int>(batch.states.cols());
  assert(B <= config_.batch_size && batch.states.rows() == obs_dim_);
  schedule_learning_rates();
  UpdateStats stats;
  targets(batch, B);
  stats.critic_loss = static_cast<float>(q_step_gradient(batch, B, stats));
  stats.critic_grad_norm = static_cast<float>(clip_global_norm(q_.grads(), config_.clip_grad_norm));
  q_adam_.step(q_.params(), q_.grads());
  param_step_gradient(batch, B, stats);  // through the just-updated Q-network
  stats.actor_grad_norm = static_cast<float>(clip_global_norm(param_.grads(), config_.clip_grad_norm));
  param_adam_.step(param_.params(), param_.grads());
  soft_update<float>(target_param_.params(), param_.params(),
                     settings_.param_tau > 0.0 ? settings_.param_tau : config_.tau);
  soft_update<float>(target_q_.params(), q_.params(), settings_.q_tau > 0.0 ? settings_.q_tau : config_.tau);
  ++updates_;
  last_ = stats;
  return stats;
}

std::vector<StateTensor> Pdqn::state_tensors() {
  std::vector<StateTensor> t;
  const auto net = [&](const char* n, Mlp<float>& m) { t.push_back({n, m.params(), m.widths(), false}); };
  const auto moments = [&](const std::string& n, Adam<float>& a) {
    t.push_back({n + ".m", a.first_moment(), {}, false});
    t.push_back({n + ".v", a.second_moment(), {}, false});
  };
  net("param", param_);
  net("q", q_);
  net("target_param", target_param_);
  net("target_q", target_q_);
  moments("param_adam", param_adam_);
  moments("q_adam", q_adam_);
  if (settings_.passthrough) {
    t.push_back({"param_passthrough", passthrough_.params(), {}, false});
  }
  if (averages()) {
    t.push_back({kParamAverage, param_average_.params(), param_average_.widths(), true});
    t.push_back({kQAverage, q_average_.params(), q_average_.widths(), true});
  }
  return t;
}

std::vector<StateCounter> Pdqn::state_counters() {
  counters_ = {updates_, param_adam_.steps(), q_adam_.steps(), average_at_};
  std::vector<StateCounter> c = {
      {"updates", &counters_[0]}, {"param_adam.steps", &counters_[1]}, {"q_adam.steps", &counters_[2]}};
  if (averages()) {
    c.push_back({"average_updates", &counters_[3]});
  }
  return c;
}

void Pdqn::restored(const std::vector<std::string>& missing) {
  updates_ = counters_[0];
  param_adam_.set_steps(counters_[1]);
  q_adam_.set_steps(counters_[2]);
  const auto lacks = [&](const char* n) { return std::find(missing.begin(), missing.end(), n) != missing.end(); };
  if (lacks(kParamAverage) || lacks(kQAverage)) {
    reset_average();  // written without one (ddpg.actor_average_tau was 0, or an older build)
  } else {
    average_at_ = counters_[3];
  }
}

void register_pdqn_algorithms(AlgorithmRegistry& registry) {
  for (const bool multipass : {false, true}) {
    registry.add({multipass ? "mpdqn" : "pdqn",
                  multipass ? "MP-DQN: P-DQN with one Q pass per action (Bester, James & Konidaris 2019)"
                            : "P-DQN: a Q-network over all parameters and a parameter network (Xiong et al. 2018)",
                  [multipass](const AlgorithmArgs& a) {
                    const PdqnSettings settings =
                        PdqnSettings::from(a.params != nullptr ? *a.params : algorithm_registry().defaults());
                    auto pdqn = std::make_unique<Pdqn>(a.obs_dim, *a.space, *a.ddpg, a.seed, multipass,
                                                       a.masked_actions, settings, a.prior);
                    pdqn->set_gates(a.gates);
                    return pdqn;
                  },
                  pdqn_keys()});
  }
}

}  // namespace pamdp
