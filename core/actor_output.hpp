// The actor's output for one observation, as every player of a DDPG policy computes it: the
// network's forward pass on one column, then, when the learner bounds the parameters by
// squashing (paper §5), the tanh map into the output bounds; with inverting or zeroing
// gradients the output is used raw (the bound acts on the update, not on the output).
//
// One function for the learner's act() (`pamdp train`'s exploration, evaluation, `pamdp eval`)
// and the actors (actor/actor_loop.cpp), so that they play the same policy. Allocates nothing.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cassert>
#include <span>

#include "core/bounds.hpp"
#include "core/mlp.hpp"

namespace pamdp {

// `input` is the caller's obs_dim x 1 scratch column; `squash_into` is null unless the
// policy squashes. `out` has the network's output width.
inline void actor_output(Mlp<float>& net, Eigen::MatrixXf& input, std::span<const float> obs,
                         const OutputBounds* squash_into, std::span<float> out) {
  assert(input.cols() == 1 && static_cast<size_t>(input.rows()) == obs.size());
  input.col(0) = Eigen::Map<const Eigen::VectorXf>(obs.data(), input.rows());
  const auto raw = net.forward(input);
  const std::span<const float> raw_span(raw.data(), static_cast<size_t>(raw.rows()));
  assert(out.size() == raw_span.size());
  if (squash_into != nullptr) {
    squash(raw_span, *squash_into, out);
  } else {
    std::copy(raw_span.begin(), raw_span.end(), out.begin());
  }
}

}  // namespace pamdp
