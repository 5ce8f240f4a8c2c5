#include "core/optim.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace pamdp {
namespace {

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "optim: %s\n", what);
  std::abort();
}

template <typename Scalar>
using ArrayMap = Eigen::Map<Eigen::Array<Scalar, Eigen::Dynamic, 1>>;
template <typename Scalar>
using ConstArrayMap = Eigen::Map<const Eigen::Array<Scalar, Eigen::Dynamic, 1>>;

}  // namespace

double adam_step_size(const AdamConfig& config, int64_t t) {
  const auto tt = static_cast<double>(t);
  return config.learning_rate * std::sqrt(1.0 - std::pow(config.beta2, tt)) / (1.0 - std::pow(config.beta1, tt));
}

template <typename Scalar>
Adam<Scalar>::Adam(int64_t num_params, const AdamConfig& config)
    : config_(config), m_(static_cast<size_t>(num_params), Scalar(0)), v_(static_cast<size_t>(num_params), Scalar(0)) {
  if (num_params < 0) {
    throw std::invalid_argument("Adam: num_params must be >= 0");
  }
}

template <typename Scalar>
void Adam<Scalar>::step(std::span<Scalar> params, std::span<const Scalar> grads) {
  if (params.size() != m_.size() || grads.size() != m_.size()) {
    misuse("Adam::step: params and grads must have num_params elements");
  }
  ++t_;
  // Caffe folds both bias corrections into the step size and adds eps to sqrt(v) uncorrected,
  // which differs slightly from Kingma & Ba's eps placement; the paper's code used Caffe.
  const auto step_size = static_cast<Scalar>(adam_step_size(config_, t_));
  const auto b1 = static_cast<Scalar>(config_.beta1);
  const auto b2 = static_cast<Scalar>(config_.beta2);
  const auto eps = static_cast<Scalar>(config_.epsilon);
  // Three Eigen statements over the whole vectors would be three passes over ~3 MB arrays
  // each; chunks small enough for L1 make it one pass.
  constexpr size_t kChunk = 1024;
  for (size_t start = 0; start < m_.size(); start += kChunk) {
    const auto len = static_cast<Eigen::Index>(std::min(kChunk, m_.size() - start));
    ArrayMap<Scalar> m(m_.data() + start, len);
    ArrayMap<Scalar> v(v_.data() + start, len);
    ArrayMap<Scalar> p(params.data() + start, len);
    const ConstArrayMap<Scalar> g(grads.data() + start, len);
    m = b1 * m + (Scalar(1) - b1) * g;
    v = b2 * v + (Scalar(1) - b2) * g.square();
    p -= step_size * m / (v.sqrt() + eps);
  }
}

template <typename Scalar>
double global_norm(std::span<const Scalar> v) {
  // Independent double accumulators: the compiler vectorizes them without reassociating a
  // single sum (which it must not do without -ffast-math), and 32 lanes are eight 4-wide FMA
  // chains, enough to hide the FMA latency (8 lanes ran 4x slower).
  constexpr size_t kLanes = 32;
  std::array<double, kLanes> acc{};
  const size_t n = v.size();
  const size_t full = n - n % kLanes;
  for (size_t i = 0; i < full; i += kLanes) {
    for (size_t j = 0; j < kLanes; ++j) {
      const auto x = static_cast<double>(v[i + j]);
      acc[j] += x * x;
    }
  }
  double sum = 0.0;
  for (size_t i = full; i < n; ++i) {
    const auto x = static_cast<double>(v[i]);
    sum += x * x;
  }
  for (double a : acc) {
    sum += a;
  }
  return std::sqrt(sum);
}

template <typename Scalar>
double clip_global_norm(std::span<Scalar> grads, double max_norm) {
  const double norm = global_norm<Scalar>(grads);
  // Caffe's ClipGradients: scale only when the norm exceeds the threshold.
  if (max_norm > 0.0 && norm > max_norm) {
    ArrayMap<Scalar>(grads.data(), static_cast<Eigen::Index>(grads.size())) *= static_cast<Scalar>(max_norm / norm);
  }
  return norm;
}

template <typename Scalar>
void soft_update(std::span<Scalar> target, std::type_identity_t<std::span<const Scalar>> source, double tau) {
  if (target.size() != source.size()) {
    misuse("soft_update: target and source sizes differ");
  }
  const auto n = static_cast<Eigen::Index>(target.size());
  ArrayMap<Scalar> t(target.data(), n);
  t = static_cast<Scalar>(tau) * ConstArrayMap<Scalar>(source.data(), n) + static_cast<Scalar>(1.0 - tau) * t;
}

template class Adam<float>;
template class Adam<double>;
template double global_norm<float>(std::span<const float>);
template double global_norm<double>(std::span<const double>);
template double clip_global_norm<float>(std::span<float>, double);
template double clip_global_norm<double>(std::span<double>, double);
template void soft_update<float>(std::span<float>, std::span<const float>, double);
template void soft_update<double>(std::span<double>, std::span<const double>, double);

}  // namespace pamdp
