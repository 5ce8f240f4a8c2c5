// A multi-layer perceptron on Eigen: Linear layers with leaky ReLU between them and a linear
// output layer, batched forward and backward, gradients with respect to the parameters and
// to the inputs. Templated on the scalar so that gradient checks can run in double; the
// learner uses float.
//
// Data layout: one sample per column (features x batch, column-major). All parameters live in
// one contiguous vector (for each layer: W as out x in column-major, then b), so Adam,
// gradient clipping, soft target updates, checkpoints and weight broadcasts each work on one
// flat span.
//
// The paper's actor has two linear heads (4 action scores, 6 parameters) on the last hidden
// layer. Two linear heads on the same input are exactly one linear layer whose output rows are
// the two heads stacked, so the actor is an Mlp with output width 4 + 6 and the heads are
// row ranges of its output (see ActorHeads below).
//
// Cost: forward ~ 2 * sum(in*out) * batch FLOP; backward ~ twice that. Buffers for up to
// max_batch samples are allocated in the constructor; forward() and backward() allocate
// nothing. Batched products go through core/gemm.hpp (OpenBLAS, or Eigen without it); on Eigen
// their workspaces live on the stack: up to ~1.5 MB at the paper's widths (core/CMakeLists.txt),
// so run them on threads with default-sized (8 MiB) stacks.
// Not thread-safe: one Mlp per thread (copies are cheap to make for actors).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "core/rng.hpp"

namespace pamdp {

template <typename Scalar>
class Mlp {
 public:
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using MatrixMap = Eigen::Map<Matrix>;
  using ConstMatrixMap = Eigen::Map<const Matrix>;
  using ConstBlock = Eigen::Block<const Matrix>;

  // widths = {input, hidden..., output}; at least {input, output}.
  Mlp(std::vector<int> widths, int max_batch, Scalar leaky_slope = Scalar(0.01));

  [[nodiscard]] const std::vector<int>& widths() const { return widths_; }
  [[nodiscard]] int input_width() const { return widths_.front(); }
  [[nodiscard]] int output_width() const { return widths_.back(); }
  [[nodiscard]] int num_layers() const { return static_cast<int>(widths_.size()) - 1; }
  [[nodiscard]] int max_batch() const { return max_batch_; }
  [[nodiscard]] Scalar leaky_slope() const { return slope_; }
  [[nodiscard]] int64_t num_params() const { return static_cast<int64_t>(params_.size()); }

  // Flat parameter and gradient vectors (same layout).
  std::span<Scalar> params() { return params_; }
  [[nodiscard]] std::span<const Scalar> params() const { return params_; }
  std::span<Scalar> grads() { return grads_; }
  [[nodiscard]] std::span<const Scalar> grads() const { return grads_; }

  // Views of layer l's weights (out x in) and biases (out) inside params().
  MatrixMap weight(int layer);
  Eigen::Map<Eigen::Matrix<Scalar, Eigen::Dynamic, 1>> bias(int layer);

  // Weights ~ N(0, weight_std^2), biases 0 (Caffe's gaussian filler, reference §7.2).
  // If output_weight_std > 0 the output layer's weights use it instead; the output layer's
  // biases are output_bias (default 0) either way. Draws weights layer by layer in params()
  // order, so one seed gives one network.
  void init_gaussian(Rng& rng, Scalar weight_std, Scalar output_weight_std = Scalar(0), Scalar output_bias = Scalar(0));

  // Forward pass of `input` (input_width x B, B <= max_batch). Keeps the activations for
  // backward(). Returns a view of the output (output_width x B) valid until the next forward.
  // Pass column-major storage with contiguous columns (a Matrix, a block of one, a Map) so that
  // the Ref binds without a temporary copy; the same holds for d_output below.
  ConstBlock forward(const Eigen::Ref<const Matrix>& input);

  // Back-propagates d_output (output_width x B, same B as the last forward). Overwrites
  // grads() with dLoss/dparams (not accumulated). If want_input_grad, input_grad() then holds
  // dLoss/dinput (input_width x B).
  void backward(const Eigen::Ref<const Matrix>& d_output, bool want_input_grad);
  // Back-propagates to the input only: input_grad() as backward(d_output, true) would leave it,
  // grads() untouched. Skips the parameter-gradient products, about half of backward's work,
  // for when only dLoss/dinput is needed (the actor step's pass through the critic).
  void backward_input(const Eigen::Ref<const Matrix>& d_output);
  [[nodiscard]] ConstBlock input_grad() const;

  // The last forward's output (output_width x B).
  [[nodiscard]] ConstBlock output() const;

 private:
  std::vector<int> widths_;
  int max_batch_;
  Scalar slope_;
  int batch_ = 0;
  std::vector<int64_t> offsets_;  // start of layer l's W in params_; b follows W
  // Aligned so that every layer's view has the same alignment in every process: Eigen's
  // vectorized reductions peel unaligned heads, so a different heap address could change the
  // order of a sum and break bit-for-bit resume across processes.
  std::vector<Scalar, Eigen::aligned_allocator<Scalar>> params_;
  std::vector<Scalar, Eigen::aligned_allocator<Scalar>> grads_;
  std::vector<Matrix> pre_;    // pre-activations z_l (out_l x max_batch)
  std::vector<Matrix> act_;    // act_[0] = input copy, act_[l+1] = activation of layer l
  std::vector<Matrix> delta_;  // scratch dLoss/dz per layer
  Matrix input_grad_;

  void backprop(const Eigen::Ref<const Matrix>& d_output, bool want_param_grads, bool want_input_grad);
};

// Row ranges of the actor's output: the first num_actions rows are the action scores, the rest
// the parameters.
struct ActorHeads {
  int num_actions = 4;
  int num_params = 6;
  [[nodiscard]] int width() const { return num_actions + num_params; }
};

extern template class Mlp<float>;
extern template class Mlp<double>;

}  // namespace pamdp
