// A hand-coded 1v0 offense policy that reads only the 58 features, standing in for the
// paper's Helios baseline: go to the ball, turn toward the goal, dribble, then shoot at a
// spot of the goal mouth away from the posts.
#pragma once

#include <array>
#include <span>

#include "core/policy.hpp"

namespace pamdp::hfo {

class ScriptedOffense final : public Policy {
 public:
  ScriptedOffense() = default;
  ParamAction act(std::span<const float> obs) override;

 private:
  std::array<float, 6> params_{};
};

}  // namespace pamdp::hfo
