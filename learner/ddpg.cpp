#include "learner/ddpg.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>

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

}  // namespace

Ddpg::Ddpg(int obs_dim, const ActionSpace& space, const DdpgConfig& config, uint64_t seed)
    : obs_dim_(obs_dim),
      config_(config),
      bounds_(OutputBounds::for_actor(space)),
      actor_(widths(obs_dim, config.hidden, space.output_width()), config.batch_size),
      critic_(widths(obs_dim + space.output_width(), config.hidden, 1), config.batch_size),
      target_actor_(actor_.widths(), config.batch_size),
      target_critic_(critic_.widths(), config.batch_size),
      actor_adam_(actor_.num_params(), adam(config, config.actor_learning_rate)),
      critic_adam_(critic_.num_params(), adam(config, config.critic_learning_rate)),
      critic_in_(obs_dim + space.output_width(), config.batch_size),
      actions_(space.output_width(), config.batch_size),
      targets_(1, config.batch_size),
      d_q_(1, config.batch_size),
      d_action_(space.output_width(), config.batch_size),
      single_in_(obs_dim, 1) {
  if (config.batch_size < 1) {
    throw std::invalid_argument("ddpg.batch_size must be >= 1");
  }
  num_actions_ = space.num_actions();
  Rng rng(seed);
  const auto s = static_cast<float>(config.init_std);
  actor_.init_gaussian(rng, s);
  critic_.init_gaussian(rng, s, static_cast<float>(config.critic_output_init_std),
                        static_cast<float>(config.critic_output_init_bias));
  // Targets start as exact copies (reference §7.2).
  std::copy(actor_.params().begin(), actor_.params().end(), target_actor_.params().begin());
  std::copy(critic_.params().begin(), critic_.params().end(), target_critic_.params().begin());
}

void Ddpg::actor_outputs(Mlp<float>& net, const Eigen::Ref<const Eigen::MatrixXf>& states, int batch,
                         Eigen::MatrixXf& out) {
  const auto raw = net.forward(states.leftCols(batch));
  if (config_.bound == BoundMethod::kSquashing) {
    for (int j = 0; j < batch; ++j) {
      squash({raw.col(j).data(), static_cast<size_t>(raw.rows())}, bounds_,
             {out.col(j).data(), static_cast<size_t>(out.rows())});
    }
  } else {
    out.leftCols(batch) = raw;
  }
}

void Ddpg::act(std::span<const float> obs, std::span<float> out) {
  assert(static_cast<int>(obs.size()) == obs_dim_ && static_cast<int>(out.size()) == output_width());
  single_in_.col(0) = Eigen::Map<const Eigen::VectorXf>(obs.data(), obs_dim_);
  const auto raw = actor_.forward(single_in_);
  if (config_.bound == BoundMethod::kSquashing) {
    squash({raw.data(), static_cast<size_t>(raw.rows())}, bounds_, out);
  } else {
    Eigen::Map<Eigen::VectorXf>(out.data(), output_width()) = raw.col(0);
  }
}

void Ddpg::schedule_learning_rates() {
  if (config_.lr_decay_updates <= 0) {
    return;
  }
  const double done = std::min(1.0, static_cast<double>(updates_) / static_cast<double>(config_.lr_decay_updates));
  const double scale = 1.0 - (1.0 - config_.lr_final_fraction) * done;
  actor_adam_.set_learning_rate(config_.actor_learning_rate * scale);
  critic_adam_.set_learning_rate(config_.critic_learning_rate * scale);
}

UpdateStats Ddpg::update(const BatchView& batch) {
  const int B = static_cast<int>(batch.states.cols());
  schedule_learning_rates();
  assert(B <= config_.batch_size && batch.states.rows() == obs_dim_);
  const int W = output_width();
  UpdateStats stats;

  // 1. Critic target y = r + gamma * Q'(s', mu'(s')) for non-terminal transitions.
  actor_outputs(target_actor_, batch.next_states, B, actions_);
  critic_in_.topLeftCorner(obs_dim_, B) = batch.next_states;
  critic_in_.bottomLeftCorner(W, B) = actions_.leftCols(B);
  const auto q_next = target_critic_.forward(critic_in_.leftCols(B));
  const auto g = static_cast<float>(config_.gamma);
  const auto beta = static_cast<float>(config_.mc_mix);
  for (int j = 0; j < B; ++j) {
    float y = batch.rewards(j) + (batch.terminal(j) > 0.5F ? 0.0F : g * q_next(0, j));
    if (beta > 0.0F) {
      y = beta * batch.mc_returns(j) + (1.0F - beta) * y;
    }
    targets_(0, j) = y;
  }

  // 2. Critic step on (1 / 2B) sum (Q(s, a) - y)^2.
  critic_in_.topLeftCorner(obs_dim_, B) = batch.states;
  critic_in_.bottomLeftCorner(W, B) = batch.actions;
  const auto q = critic_.forward(critic_in_.leftCols(B));
  double loss = 0.0;
  for (int j = 0; j < B; ++j) {
    const float diff = q(0, j) - targets_(0, j);
    loss += 0.5 * static_cast<double>(diff) * diff;
    d_q_(0, j) = diff / static_cast<float>(B);
    stats.q_mean += q(0, j);
    stats.target_mean += targets_(0, j);
  }
  stats.critic_loss = static_cast<float>(loss / B);
  stats.q_mean /= static_cast<float>(B);
  stats.target_mean /= static_cast<float>(B);
  critic_.backward(d_q_.leftCols(B), false);
  stats.critic_grad_norm = static_cast<float>(clip_global_norm(critic_.grads(), config_.clip_grad_norm));
  critic_adam_.step(critic_.params(), critic_.grads());

  // 3. Actor step through the updated critic: dLoss/dQ = -1 per sample (a sum, not a mean).
  actor_outputs(actor_, batch.states, B, actions_);
  int at_bound = 0;
  for (int j = 0; j < B; ++j) {
    for (int i = num_actions_; i < W; ++i) {
      const float a = actions_(i, j);
      at_bound += (a <= bounds_.lo[static_cast<size_t>(i)] || a >= bounds_.hi[static_cast<size_t>(i)]) ? 1 : 0;
    }
  }
  stats.params_at_bound_fraction =
      W > num_actions_ ? static_cast<float>(at_bound) / static_cast<float>((W - num_actions_) * B) : 0.0F;
  critic_in_.topLeftCorner(obs_dim_, B) = batch.states;
  critic_in_.bottomLeftCorner(W, B) = actions_.leftCols(B);
  critic_.forward(critic_in_.leftCols(B));
  d_q_.leftCols(B).setConstant(-1.0F);
  critic_.backward_input(d_q_.leftCols(B));  // only dQ/da: critic parameter gradients are not needed
  d_action_.leftCols(B) = critic_.input_grad().bottomRows(W);
  apply_gradient_bounds(config_.bound, bounds_, actions_.leftCols(B), actor_.output(), d_action_.leftCols(B));
  actor_.backward(d_action_.leftCols(B), false);
  stats.actor_grad_norm = static_cast<float>(clip_global_norm(actor_.grads(), config_.clip_grad_norm));
  actor_adam_.step(actor_.params(), actor_.grads());

  // 4. Soft target updates.
  soft_update<float>(target_actor_.params(), actor_.params(), config_.tau);
  soft_update<float>(target_critic_.params(), critic_.params(), config_.tau);
  ++updates_;
  return stats;
}

}  // namespace pamdp
