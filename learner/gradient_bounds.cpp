#include "learner/gradient_bounds.hpp"

#include <cmath>

namespace pamdp {

bool parse_bound_method(std::string_view name, BoundMethod* out) {
  if (name == "inverting") {
    *out = BoundMethod::kInverting;
  } else if (name == "zeroing") {
    *out = BoundMethod::kZeroing;
  } else if (name == "squashing") {
    *out = BoundMethod::kSquashing;
  } else {
    return false;
  }
  return true;
}

const char* bound_method_name(BoundMethod m) {
  switch (m) {
    case BoundMethod::kInverting: return "inverting";
    case BoundMethod::kZeroing: return "zeroing";
    case BoundMethod::kSquashing: return "squashing";
  }
  return "?";
}

void apply_gradient_bounds(BoundMethod method, const OutputBounds& bounds, const Eigen::Ref<const Eigen::MatrixXf>& p,
                           const Eigen::Ref<const Eigen::MatrixXf>& raw, Eigen::Ref<Eigen::MatrixXf> grad) {
  const Eigen::Index rows = grad.rows();
  const Eigen::Index cols = grad.cols();
  for (Eigen::Index j = 0; j < cols; ++j) {
    for (Eigen::Index i = 0; i < rows; ++i) {
      const float lo = bounds.lo[static_cast<size_t>(i)];
      const float hi = bounds.hi[static_cast<size_t>(i)];
      float& g = grad(i, j);
      switch (method) {
        case BoundMethod::kInverting: {
          // g < 0 suggests increasing p: scale by the room left below the upper bound, which
          // turns negative (pushing back) once p is above it; symmetric for g > 0.
          const float v = p(i, j);
          g *= g < 0.0F ? (hi - v) / (hi - lo) : (v - lo) / (hi - lo);
          break;
        }
        case BoundMethod::kZeroing: {
          // Paper §5's text: zero the gradients that suggest increasing (decreasing) a
          // parameter already at or above its upper (at or below its lower) limit. A gradient
          // that points back into the range is kept, so an out-of-range output can return.
          const float v = p(i, j);
          if ((g < 0.0F && v >= hi) || (g > 0.0F && v <= lo)) {
            g = 0.0F;
          }
          break;
        }
        case BoundMethod::kSquashing: {
          // p = lo + (hi - lo)(tanh(u) + 1)/2  =>  dp/du = (hi - lo)/2 * (1 - tanh(u)^2).
          const float t = std::tanh(raw(i, j));
          g *= 0.5F * (hi - lo) * (1.0F - t * t);
          break;
        }
      }
    }
  }
}

}  // namespace pamdp
