// Optimizer pieces that work on flat parameter/gradient spans (see Mlp): Adam with Caffe's
// semantics, global-norm gradient clipping and the soft target update. None allocates after
// construction. Not thread-safe. Spans must have matching sizes; a mismatch is a bug and aborts.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

namespace pamdp {

struct AdamConfig {
  double learning_rate = 1e-3;
  double beta1 = 0.95;  // the paper's code (Caffe solver), reference §7.1
  double beta2 = 0.999;
  double epsilon = 1e-8;
};

// Caffe Adam (reference §7.4): with t = number of steps taken including this one,
//   m <- b1 m + (1 - b1) g;  v <- b2 v + (1 - b2) g^2;
//   theta <- theta - lr * sqrt(1 - b2^t) / (1 - b1^t) * m / (sqrt(v) + eps).
// adam_step_size is lr * sqrt(1 - b2^t) / (1 - b1^t), in double: step t casts it to Scalar
// (shared with the CUDA learner, which computes it on the host the same way).
double adam_step_size(const AdamConfig& config, int64_t t);

template <typename Scalar>
class Adam {
 public:
  Adam(int64_t num_params, const AdamConfig& config);
  void step(std::span<Scalar> params, std::span<const Scalar> grads);

  [[nodiscard]] const AdamConfig& config() const { return config_; }
  void set_learning_rate(double lr) { config_.learning_rate = lr; }
  [[nodiscard]] int64_t steps() const { return t_; }
  // State for checkpoints.
  std::span<Scalar> first_moment() { return m_; }
  std::span<Scalar> second_moment() { return v_; }
  void set_steps(int64_t t) { t_ = t; }

 private:
  AdamConfig config_;
  int64_t t_ = 0;
  std::vector<Scalar> m_;
  std::vector<Scalar> v_;
};

// L2 norm of a flat vector (accumulated in double).
template <typename Scalar>
double global_norm(std::span<const Scalar> v);
// Lets global_norm(mlp.grads()) deduce Scalar from a mutable span.
template <typename Scalar>
requires(!std::is_const_v<Scalar>) double global_norm(std::span<Scalar> v) {
  return global_norm<Scalar>(std::span<const Scalar>(v));
}

// Scales grads so that their global L2 norm is at most max_norm (no-op if max_norm <= 0).
// Returns the norm before clipping.
template <typename Scalar>
double clip_global_norm(std::span<Scalar> grads, double max_norm);

// target <- tau * source + (1 - tau) * target, element-wise. Scalar is deduced from target
// only, so a mutable source span (online.params()) binds too.
template <typename Scalar>
void soft_update(std::span<Scalar> target, std::type_identity_t<std::span<const Scalar>> source, double tau);

// The rate one soft_update must take to move as far as `steps` soft updates at `tau` would
// with the source held still: 1 - (1 - tau)^steps (evaluation averages absorb several updates
// at once).
inline double soft_update_rate(double tau, int64_t steps) {
  return -std::expm1(static_cast<double>(steps) * std::log1p(-tau));
}

extern template class Adam<float>;
extern template class Adam<double>;

}  // namespace pamdp
