#include "learner/ddpg.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>

#include "core/actor_output.hpp"
#include "core/passthrough.hpp"

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

// Columns of the online networks' actor step: the batch, plus as many demonstrations.
int actor_batch(const DdpgConfig& c) {
  return c.demo_bc_weight > 0.0 ? 2 * c.batch_size : c.batch_size;
}

}  // namespace

Ddpg::Ddpg(int obs_dim, const ActionSpace& space, const DdpgConfig& config, uint64_t seed, const ParameterPrior* prior)
    : obs_dim_(obs_dim),
      config_(config),
      bounds_(OutputBounds::for_actor(space)),
      actor_(widths(obs_dim, config.hidden, space.output_width()), actor_batch(config)),
      critic_(widths(obs_dim + space.output_width(), config.hidden, 1), actor_batch(config)),
      target_actor_(actor_.widths(), config.batch_size),
      target_critic_(critic_.widths(), config.batch_size),
      actor_average_(actor_.widths(), 1),
      // One row at least, so that an env without parameters still builds its (unused) layer.
      passthrough_({obs_dim, std::max(space.num_params(), 1)}, actor_batch(config)),
      actor_adam_(actor_.num_params(), adam(config, config.actor_learning_rate)),
      critic_adam_(critic_.num_params(), adam(config, config.critic_learning_rate)),
      critic_in_(obs_dim + space.output_width(), actor_batch(config)),
      actions_(space.output_width(), actor_batch(config)),
      targets_(1, config.batch_size),
      d_q_(1, actor_batch(config)),
      d_action_(space.output_width(), actor_batch(config)),
      single_in_(obs_dim, 1) {
  if (config.batch_size < 1) {
    throw std::invalid_argument("ddpg.batch_size must be >= 1");
  }
  if (config.demo_bc_weight < 0.0) {
    throw std::invalid_argument("ddpg.demo_bc_weight must be >= 0");
  }
  if (!(config.actor_average_tau >= 0.0 && config.actor_average_tau <= 1.0)) {
    throw std::invalid_argument("ddpg.actor_average_tau must be in [0, 1]");
  }
  if (!(config.reward_scale > 0.0)) {
    throw std::invalid_argument("ddpg.reward_scale must be > 0");
  }
  num_actions_ = space.num_actions();
  if (config.demo_bc_weight > 0.0) {
    states_in_.resize(obs_dim, 2 * config.batch_size);
    demo_q_.resize(1, config.batch_size);
    for (int i = 0; i < bounds_.width(); ++i) {
      const float range = bounds_.hi[static_cast<size_t>(i)] - bounds_.lo[static_cast<size_t>(i)];
      bc_scale_.push_back(range > 0.0F ? 2.0F / range : 1.0F);
    }
    for (const DiscreteActionSpec& a : space.actions) {
      std::vector<int> rows;
      for (const int p : a.param_indices) {
        rows.push_back(num_actions_ + p);
      }
      owned_.push_back(std::move(rows));
    }
  }
  Rng rng(seed);
  const auto s = static_cast<float>(config.init_std);
  actor_.init_gaussian(rng, s, static_cast<float>(config.actor_output_init_std));
  critic_.init_gaussian(rng, s, static_cast<float>(config.critic_output_init_std),
                        static_cast<float>(config.critic_output_init_bias));
  if (config.passthrough) {  // else the layer keeps the zeros it was made with
    if (space.num_params() < 1) {
      throw std::invalid_argument("ddpg.passthrough: this env's actions have no continuous parameters");
    }
    load_passthrough(passthrough_, prior, "ddpg.passthrough");
    pre_.resize(space.output_width(), actor_batch(config));
  }
  // Targets start as exact copies (reference §7.2).
  std::copy(actor_.params().begin(), actor_.params().end(), target_actor_.params().begin());
  std::copy(critic_.params().begin(), critic_.params().end(), target_critic_.params().begin());
  reset_actor_average();
}

void Ddpg::reset_actor_average() {
  std::copy(actor_.params().begin(), actor_.params().end(), actor_average_.params().begin());
  actor_average_at_ = updates_;
}

void Ddpg::track_actor_average() {
  const int64_t k = updates_ - actor_average_at_;
  if (config_.actor_average_tau <= 0.0 || k <= 0) {
    return;
  }
  const auto rate = static_cast<float>(soft_update_rate(config_.actor_average_tau, k));
  const auto online = actor_.params();
  const auto avg = actor_average_.params();
  for (size_t i = 0; i < avg.size(); ++i) {
    avg[i] += rate * (online[i] - avg[i]);
  }
  actor_average_at_ = updates_;
}

void Ddpg::actor_outputs(Mlp<float>& net, const Eigen::Ref<const Eigen::MatrixXf>& states, int batch,
                         Eigen::MatrixXf& out) {
  const auto net_out = net.forward(states.leftCols(batch));
  if (config_.passthrough) {
    pre_.leftCols(batch) = net_out;
    pre_.bottomLeftCorner(passthrough_.output_width(), batch) += passthrough_.forward(states.leftCols(batch));
  }
  const Eigen::Ref<const Eigen::MatrixXf> raw = config_.passthrough
                                                    ? Eigen::Ref<const Eigen::MatrixXf>(pre_.leftCols(batch))
                                                    : Eigen::Ref<const Eigen::MatrixXf>(net_out);
  if (config_.bound == BoundMethod::kSquashing) {
    for (int j = 0; j < batch; ++j) {
      squash({raw.col(j).data(), static_cast<size_t>(raw.rows())}, bounds_,
             {out.col(j).data(), static_cast<size_t>(out.rows())});
    }
  } else {
    out.leftCols(batch) = raw;
  }
}

void Ddpg::act(std::span<const float> obs, std::span<float> out, ActorCopy copy) {
  assert(static_cast<int>(obs.size()) == obs_dim_ && static_cast<int>(out.size()) == output_width());
  Mlp<float>& net = copy == ActorCopy::kTarget ? target_actor_ : copy == ActorCopy::kAverage ? actor_average_ : actor_;
  actor_output(net, single_in_, obs, config_.bound == BoundMethod::kSquashing ? &bounds_ : nullptr, out,
               config_.passthrough ? &passthrough_ : nullptr);
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

UpdateStats Ddpg::update(const BatchView& batch, const BatchView* demos) {
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
  const auto clip = static_cast<float>(config_.bootstrap_clip);
  const auto scale = static_cast<float>(config_.reward_scale);
  for (int j = 0; j < B; ++j) {
    const float next = clip > 0.0F ? std::clamp(q_next(0, j), -clip, clip) : q_next(0, j);
    float y = scale * batch.rewards(j) + (batch.terminal(j) > 0.5F ? 0.0F : g * next);
    if (beta > 0.0F) {
      y = beta * scale * batch.mc_returns(j) + (1.0F - beta) * y;
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
  // Demonstrations, when given, ride along as D more columns whose only loss is the cloning.
  const bool clone = demos != nullptr && config_.demo_bc_weight > 0.0 && demos->states.cols() > 0;
  const int D = clone ? static_cast<int>(demos->states.cols()) : 0;
  assert(D <= config_.batch_size);
  if (clone) {
    // Q(s_d, a_d) before the pass below overwrites the critic's activations.
    critic_in_.topLeftCorner(obs_dim_, D) = demos->states;
    critic_in_.bottomLeftCorner(W, D) = demos->actions;
    demo_q_.leftCols(D) = critic_.forward(critic_in_.leftCols(D));
    states_in_.leftCols(B) = batch.states;
    states_in_.middleCols(B, D) = demos->states;
    actor_outputs(actor_, states_in_, B + D, actions_);
  } else {
    actor_outputs(actor_, batch.states, B, actions_);
  }
  const int N = B + D;
  int at_bound = 0;
  for (int j = 0; j < B; ++j) {
    for (int i = num_actions_; i < W; ++i) {
      const float a = actions_(i, j);
      at_bound += (a <= bounds_.lo[static_cast<size_t>(i)] || a >= bounds_.hi[static_cast<size_t>(i)]) ? 1 : 0;
    }
  }
  stats.params_at_bound_fraction =
      W > num_actions_ ? static_cast<float>(at_bound) / static_cast<float>((W - num_actions_) * B) : 0.0F;
  if (clone) {
    critic_in_.topLeftCorner(obs_dim_, N) = states_in_.leftCols(N);
  } else {
    critic_in_.topLeftCorner(obs_dim_, B) = batch.states;
  }
  critic_in_.bottomLeftCorner(W, N) = actions_.leftCols(N);
  const auto q_pi = critic_.forward(critic_in_.leftCols(N));
  int accepted = 0;
  double bc_loss = 0.0;
  d_q_.leftCols(B).setConstant(-1.0F);
  if (clone) {
    // Which demonstrations are cloned (targets_, free after the critic step, holds the marks),
    // decided before backward_input reuses the critic. Their columns take no Q gradient.
    Eigen::MatrixXf& marks = targets_;
    for (int j = 0; j < D; ++j) {
      marks(0, j) = !config_.demo_q_filter || demo_q_(0, j) > q_pi(0, B + j) ? 1.0F : 0.0F;
    }
    d_q_.middleCols(B, D).setZero();
    critic_.backward_input(d_q_.leftCols(N));
    d_action_.leftCols(N) = critic_.input_grad().bottomRows(W);
    const auto lambda = static_cast<float>(config_.demo_bc_weight);
    for (int j = 0; j < D; ++j) {
      if (marks(0, j) == 0.0F) {
        continue;
      }
      ++accepted;
      const auto a_d = demos->actions.col(j);
      int chosen = 0;
      for (int k = 1; k < num_actions_; ++k) {
        chosen = a_d(k) > a_d(chosen) ? k : chosen;
      }
      auto clone_row = [&](int i) {
        const float s2 = bc_scale_[static_cast<size_t>(i)] * bc_scale_[static_cast<size_t>(i)];
        const float diff = actions_(i, B + j) - a_d(i);
        bc_loss += 0.5 * static_cast<double>(lambda) * s2 * diff * diff;
        d_action_(i, B + j) += lambda * s2 * diff;
      };
      for (int k = 0; k < num_actions_; ++k) {
        clone_row(k);
      }
      for (const int i : owned_[static_cast<size_t>(chosen)]) {
        clone_row(i);
      }
    }
    stats.bc_accepted_fraction = static_cast<float>(accepted) / static_cast<float>(D);
    stats.bc_loss = static_cast<float>(bc_loss / D);
  } else {
    critic_.backward_input(d_q_.leftCols(B));  // only dQ/da: critic parameter gradients are not needed
    d_action_.leftCols(B) = critic_.input_grad().bottomRows(W);
  }
  // The bound reads the outputs before a squash: the actor's own, plus the layer when there is one.
  apply_gradient_bounds(config_.bound, bounds_, actions_.leftCols(N),
                        config_.passthrough ? Eigen::Ref<const Eigen::MatrixXf>(pre_.leftCols(N))
                                            : Eigen::Ref<const Eigen::MatrixXf>(actor_.output()),
                        d_action_.leftCols(N));
  actor_.backward(d_action_.leftCols(N), false);
  stats.actor_grad_norm = static_cast<float>(clip_global_norm(actor_.grads(), config_.clip_grad_norm));
  actor_adam_.step(actor_.params(), actor_.grads());
  // 4. Soft target updates.
  soft_update<float>(target_actor_.params(), actor_.params(), config_.tau);
  soft_update<float>(target_critic_.params(), critic_.params(), config_.tau);
  ++updates_;
  return stats;
}

}  // namespace pamdp
