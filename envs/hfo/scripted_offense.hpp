// A hand-coded offense policy that reads only the HFO features, standing in for the paper's
// Helios baseline.
//
// 1v0 (58 features, no opponent): go to the ball, turn toward it, and once it is kickable
// shoot at full power at the goal centre from wherever the agent is (unchanged since 1v0).
// With a goalie in the opponent block (features 58-65, reference §3.3) it plays like a
// striker: at every touch it rates nine shot courses across the goal mouth (1.6 m inside the
// posts) by how many cycles the goalie would need to reach the course against how many the
// ball needs to pass it, and shoots at full power along the best one if that is good enough
// or the goal is within 10 m; otherwise it dribbles toward the goal centre with a controlled
// kick (ball rolling at 0.9 m/cycle). Every kick direction corrects for the ball's current
// velocity, so the ball leaves along the aimed line.
// act() allocates nothing; the policy keeps no state between steps.
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
  ParamAction kick_against_goalie(std::span<const float> obs);

  std::array<float, 6> params_{};
};

}  // namespace pamdp::hfo
