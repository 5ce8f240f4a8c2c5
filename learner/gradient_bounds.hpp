// The three ways of keeping a PAMDP actor's bounded outputs in range (paper §5), applied to the
// gradient the critic hands back for the actor's outputs.
//
// Convention: `grad` is dLoss/dp with Loss = -Q (so grad < 0 means "increasing p increases Q"),
// one column per sample, one row per actor output; `p` is the output the critic saw, `raw` the
// actor's pre-squash output (only used by kSquashing). Both are width x batch, column-major.
#pragma once

#include <Eigen/Core>
#include <string_view>

#include "core/bounds.hpp"

namespace pamdp {

enum class BoundMethod {
  kInverting,  // scale by the distance to the bound the gradient heads for; invert outside
  kZeroing,    // drop gradients that push a parameter further beyond a bound it has reached
  kSquashing,  // outputs go through tanh and are rescaled; chain rule through the squash
};

// Parses "inverting", "zeroing" or "squashing"; returns false on anything else.
bool parse_bound_method(std::string_view name, BoundMethod* out);
const char* bound_method_name(BoundMethod m);

// Rewrites grad in place. For kSquashing, grad on p becomes the gradient on raw.
void apply_gradient_bounds(BoundMethod method, const OutputBounds& bounds, const Eigen::Ref<const Eigen::MatrixXf>& p,
                           const Eigen::Ref<const Eigen::MatrixXf>& raw, Eigen::Ref<Eigen::MatrixXf> grad);

}  // namespace pamdp
