#include "core/mlp.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/gemm.hpp"

namespace pamdp {
namespace {

// A batch wider than the buffers or a matrix of the wrong height is a bug in the caller; an
// Eigen assertion would vanish under NDEBUG and write out of bounds, so stop here instead.
[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "Mlp: %s\n", what);
  std::abort();
}

// a * b + c. std::fma is one instruction where the target has FMA (-march=native here) but a
// slow, exactly rounded library call where it does not.
template <typename Scalar>
inline Scalar multiply_add(Scalar a, Scalar b, Scalar c) {
#ifdef __FMA__
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// y += W x for a column-major rows x cols W: the batch-1 forward, which streams every weight
// once and is bound by cache bandwidth (the paper's actor is 3 MB of float weights, more than
// L2). Eight columns per sweep over y keep eight sequential weight streams in flight and touch
// y once per eight columns; on Zen 3 this reads the 512 x 1024 layer at ~65 GB/s where Eigen's
// GEMV reaches ~50 GB/s.
template <typename Scalar>
void gemv_accumulate(const Scalar* __restrict w, Eigen::Index rows, Eigen::Index cols, const Scalar* __restrict x,
                     Scalar* __restrict y) {
  constexpr Eigen::Index kCols = 8;
  Eigen::Index j = 0;
  for (; j + kCols <= cols; j += kCols) {
    const Scalar* c = w + j * rows;
    std::array<Scalar, kCols> xs{};
    std::copy(x + j, x + j + kCols, xs.begin());
    for (Eigen::Index i = 0; i < rows; ++i) {
      Scalar acc = y[i];
      for (Eigen::Index t = 0; t < kCols; ++t) {
        acc = multiply_add(c[i + t * rows], xs[t], acc);
      }
      y[i] = acc;
    }
  }
  for (; j < cols; ++j) {
    const Scalar* c = w + j * rows;
    const Scalar xj = x[j];
    for (Eigen::Index i = 0; i < rows; ++i) {
      y[i] = multiply_add(c[i], xj, y[i]);
    }
  }
}

}  // namespace

template <typename Scalar>
Mlp<Scalar>::Mlp(std::vector<int> widths, int max_batch, Scalar leaky_slope)
    : widths_(std::move(widths)), max_batch_(max_batch), slope_(leaky_slope) {
  if (widths_.size() < 2) {
    throw std::invalid_argument("Mlp: widths needs at least {input, output}, got " + std::to_string(widths_.size()));
  }
  for (int w : widths_) {
    if (w < 1) {
      throw std::invalid_argument("Mlp: every width must be >= 1, got " + std::to_string(w));
    }
  }
  if (max_batch_ < 1) {
    throw std::invalid_argument("Mlp: max_batch must be >= 1, got " + std::to_string(max_batch_));
  }
  // The activation is computed as max(z, slope * z), which is the leaky ReLU only for slopes
  // in [0, 1].
  if (!(leaky_slope >= Scalar(0) && leaky_slope <= Scalar(1))) {
    throw std::invalid_argument("Mlp: leaky_slope must be in [0, 1]");
  }

  const int layers = num_layers();
  int64_t total = 0;
  for (int l = 0; l < layers; ++l) {
    offsets_.push_back(total);
    total += static_cast<int64_t>(widths_[l + 1]) * (widths_[l] + 1);
  }
  params_.assign(static_cast<size_t>(total), Scalar(0));
  grads_.assign(static_cast<size_t>(total), Scalar(0));

  act_.emplace_back(Matrix::Zero(widths_[0], max_batch_));
  for (int l = 0; l < layers; ++l) {
    const bool hidden = l + 1 < layers;
    // The output layer is linear: its z is written straight into act_.back(), and the
    // gradient arriving at it is the caller's d_output, so it needs neither pre_ nor delta_.
    pre_.emplace_back(hidden ? Matrix::Zero(widths_[l + 1], max_batch_) : Matrix());
    delta_.emplace_back(hidden ? Matrix::Zero(widths_[l + 1], max_batch_) : Matrix());
    act_.emplace_back(Matrix::Zero(widths_[l + 1], max_batch_));
  }
  input_grad_ = Matrix::Zero(widths_[0], max_batch_);
}

template <typename Scalar>
typename Mlp<Scalar>::MatrixMap Mlp<Scalar>::weight(int layer) {
  if (layer < 0 || layer >= num_layers()) {
    misuse("weight(): layer out of range");
  }
  return MatrixMap(params_.data() + offsets_[layer], widths_[layer + 1], widths_[layer]);
}

template <typename Scalar>
Eigen::Map<Eigen::Matrix<Scalar, Eigen::Dynamic, 1>> Mlp<Scalar>::bias(int layer) {
  if (layer < 0 || layer >= num_layers()) {
    misuse("bias(): layer out of range");
  }
  const int64_t weights = static_cast<int64_t>(widths_[layer + 1]) * widths_[layer];
  return Eigen::Map<Eigen::Matrix<Scalar, Eigen::Dynamic, 1>>(params_.data() + offsets_[layer] + weights,
                                                              widths_[layer + 1]);
}

template <typename Scalar>
void Mlp<Scalar>::init_gaussian(Rng& rng, Scalar weight_std, Scalar output_weight_std, Scalar output_bias) {
  const int layers = num_layers();
  for (int l = 0; l < layers; ++l) {
    const bool output_layer = l + 1 == layers;
    const double std = output_layer && output_weight_std > Scalar(0) ? output_weight_std : weight_std;
    MatrixMap w = weight(l);
    for (Eigen::Index i = 0; i < w.size(); ++i) {
      w.data()[i] = static_cast<Scalar>(std * rng.normal());
    }
    bias(l).setConstant(output_layer ? output_bias : Scalar(0));
  }
}

template <typename Scalar>
typename Mlp<Scalar>::ConstBlock Mlp<Scalar>::forward(const Eigen::Ref<const Matrix>& input) {
  const auto batch = input.cols();
  if (input.rows() != input_width() || batch < 1 || batch > max_batch_) {
    misuse("forward(): input must be input_width x B with 1 <= B <= max_batch");
  }
  batch_ = static_cast<int>(batch);
  // Kept for backward(): dW of the first layer needs the input.
  act_[0].leftCols(batch) = input;

  const int layers = num_layers();
  for (int l = 0; l < layers; ++l) {
    const bool hidden = l + 1 < layers;
    auto z = (hidden ? pre_[l] : act_[l + 1]).leftCols(batch);
    // Starting from the bias and accumulating the product saves a pass over z.
    z.colwise() = bias(l);
    if (batch == 1) {
      gemv_accumulate(params_.data() + offsets_[l], widths_[l + 1], widths_[l], act_[l].data(), z.data());
    } else {
      gemm<Scalar>(Op::kNone, weight(l), Op::kNone, act_[l].leftCols(batch), z, /*accumulate=*/true);
    }
    if (hidden) {
      act_[l + 1].leftCols(batch) = z.cwiseMax(slope_ * z);
    }
  }
  return output();
}

template <typename Scalar>
void Mlp<Scalar>::backward(const Eigen::Ref<const Matrix>& d_output, bool want_input_grad) {
  backprop(d_output, /*want_param_grads=*/true, want_input_grad);
}

template <typename Scalar>
void Mlp<Scalar>::backward_input(const Eigen::Ref<const Matrix>& d_output) {
  backprop(d_output, /*want_param_grads=*/false, /*want_input_grad=*/true);
}

template <typename Scalar>
void Mlp<Scalar>::backprop(const Eigen::Ref<const Matrix>& d_output, bool want_param_grads, bool want_input_grad) {
  const auto batch = static_cast<Eigen::Index>(batch_);
  if (batch_ == 0) {
    misuse("backward() before forward()");
  }
  if (d_output.rows() != output_width() || d_output.cols() != batch) {
    misuse("backward(): d_output must be output_width x B with B of the last forward()");
  }

  for (int l = num_layers() - 1; l >= 0; --l) {
    const bool output_layer = l + 1 == num_layers();
    // Ref to a leftCols block of a column-major matrix binds without a copy.
    const Eigen::Ref<const Matrix> dz = output_layer ? d_output : Eigen::Ref<const Matrix>(delta_[l].leftCols(batch));
    if (want_param_grads) {
      const int64_t weights = static_cast<int64_t>(widths_[l + 1]) * widths_[l];
      MatrixMap dw(grads_.data() + offsets_[l], widths_[l + 1], widths_[l]);
      Eigen::Map<Eigen::Matrix<Scalar, Eigen::Dynamic, 1>> db(grads_.data() + offsets_[l] + weights, widths_[l + 1]);
      gemm<Scalar>(Op::kNone, dz, Op::kTranspose, act_[l].leftCols(batch), dw, /*accumulate=*/false);
      // Row sums of dz, a column at a time: contiguous, vectorized adds.
      db = dz.col(0);
      for (Eigen::Index c = 1; c < batch; ++c) {
        db += dz.col(c);
      }
    }
    if (l > 0) {
      auto d_prev = delta_[l - 1].leftCols(batch);
      gemm<Scalar>(Op::kTranspose, weight(l), Op::kNone, dz, d_prev, /*accumulate=*/false);
      // Through layer l-1's leaky ReLU: the gradient passes where z > 0 and is scaled by the
      // slope elsewhere. Written as a multiply by max(slope, [z > 0]) (equal for slopes in
      // [0, 1]) over the contiguous block because GCC vectorizes that, but neither a ternary
      // (no if-conversion of float compares under -ftrapping-math) nor Eigen 3.4's select().
      // The slope is a local: a store through d could alias the member and force reloads.
      Scalar* d = d_prev.data();
      const Scalar* z = pre_[l - 1].data();
      const Scalar slope = slope_;
      const Eigen::Index n = d_prev.size();
      for (Eigen::Index i = 0; i < n; ++i) {
        d[i] *= std::max(slope, static_cast<Scalar>(z[i] > Scalar(0)));
      }
    } else if (want_input_grad) {
      gemm<Scalar>(Op::kTranspose, weight(0), Op::kNone, dz, input_grad_.leftCols(batch), /*accumulate=*/false);
    }
  }
}

template <typename Scalar>
typename Mlp<Scalar>::ConstBlock Mlp<Scalar>::input_grad() const {
  return ConstBlock(input_grad_, 0, 0, input_width(), batch_);
}

template <typename Scalar>
typename Mlp<Scalar>::ConstBlock Mlp<Scalar>::output() const {
  return ConstBlock(act_.back(), 0, 0, output_width(), batch_);
}

template class Mlp<float>;
template class Mlp<double>;

}  // namespace pamdp
