// The bounded outputs of a PAMDP actor: one score per discrete action in [-1, 1] and every
// parameter in its ActionSpace range (reference §7.4 step 5), plus the tanh squashing map used
// by the "squashing gradients" method (paper §5). Shared by the learner (gradient bounds) and
// the actors (which must squash exactly as the learner does).
#pragma once

#include <cmath>
#include <span>
#include <vector>

#include "core/action_space.hpp"

namespace pamdp {

struct OutputBounds {
  std::vector<float> lo;
  std::vector<float> hi;

  // Scores [-1, 1] then the parameters' bounds, in the actor's output order.
  static OutputBounds for_actor(const ActionSpace& space) {
    OutputBounds b;
    for (int i = 0; i < space.num_actions(); ++i) {
      b.lo.push_back(-1.0F);
      b.hi.push_back(1.0F);
    }
    for (const ParamSpec& p : space.params) {
      b.lo.push_back(p.lo);
      b.hi.push_back(p.hi);
    }
    return b;
  }
  [[nodiscard]] int width() const { return static_cast<int>(lo.size()); }
};

// p = lo + (hi - lo) * (tanh(u) + 1) / 2, element-wise over one output vector.
inline void squash(std::span<const float> raw, const OutputBounds& b, std::span<float> out) {
  for (size_t i = 0; i < raw.size(); ++i) {
    out[i] = b.lo[i] + (b.hi[i] - b.lo[i]) * 0.5F * (std::tanh(raw[i]) + 1.0F);
  }
}

}  // namespace pamdp
