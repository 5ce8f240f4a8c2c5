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
// policy squashes; `passthrough`, when given, is a fixed layer {obs_dim, P} added to the last P
// outputs (the parameters) before a squash (core/passthrough.hpp). `out` has the network's
// output width.
inline void actor_output(Mlp<float>& net, Eigen::MatrixXf& input, std::span<const float> obs,
                         const OutputBounds* squash_into, std::span<float> out, Mlp<float>* passthrough = nullptr) {
  assert(input.cols() == 1 && static_cast<size_t>(input.rows()) == obs.size());
  input.col(0) = Eigen::Map<const Eigen::VectorXf>(obs.data(), input.rows());
  const auto raw = net.forward(input);
  assert(out.size() == static_cast<size_t>(raw.rows()));
  std::copy(raw.data(), raw.data() + raw.rows(), out.begin());
  if (passthrough != nullptr) {
    const auto extra = passthrough->forward(input);
    assert(static_cast<size_t>(extra.rows()) <= out.size());
    const size_t first = out.size() - static_cast<size_t>(extra.rows());
    for (Eigen::Index p = 0; p < extra.rows(); ++p) {
      out[first + static_cast<size_t>(p)] += extra(p, 0);
    }
  }
  if (squash_into != nullptr) {
    squash(out, *squash_into, out);  // element by element, so in place is safe
  }
}

}  // namespace pamdp
