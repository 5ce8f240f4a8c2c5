// A hand-coded player for a team of offense agents (2v0, 2v1, ...; issue 79), reading only its
// own features: its 58, then 8 per teammate and 8 per opponent (features.hpp). Each player
// decides alone, as HFO's agents do, so one policy plays every slot, in the embedded simulator
// (HfoTeamEnv) or on the real server (one agent per process).
//
// - The player nearest the ball goes for it (its distance against each teammate's, both from
//   its own features); the others move to a support spot 6 m from the ball toward the goal and
//   8 m to their own side of the ball's line to the goal, and face the ball there.
// - With the ball it plays the close-in offense (scripted_offense.hpp, ShotAim::kCloseIn:
//   dribble slowly at the goal, shoot within 8 m) against the nearest opponent, or shoots at
//   the goal centre with no opponent; but when an opponent comes within kPassWhenOpponentWithin
//   of the ball and a teammate stands open (the opponent at least kOpenMargin farther from it
//   than from the ball, and no nearer than kLaneClearance to the passing line), it passes: the
//   ball rolls to the teammate at a pace that would stop it kPassOverrun past him. The chaser
//   is whoever is nearest to where the ball will be kChaseLookahead cycles on, so a passer
//   leaves its pass to the receiver.
// - Against agent2d's goalie (1,000 embedded episodes, HFO's starts): .933 with about one pass
//   an episode. Never passing scores .991 (the close-in dribble alone); slower passes (overrun
//   1.5 m) .65, since the goalie intercepts them; passing only within 4 m .990 with a pass in
//   one episode of twenty. The team is a yardstick for two-player play (passes, receptions,
//   collisions, the goalie choosing between attackers), not the strongest team.
// act() allocates nothing; the player keeps no state between steps.
#pragma once

#include <array>
#include <span>

#include "core/policy.hpp"
#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/scripted_offense.hpp"

namespace pamdp::hfo {

class ScriptedTeamPlayer final : public Policy {
 public:
  static constexpr double kPassWhenOpponentWithin = 6.0;
  static constexpr double kOpenMargin = 3.0;
  static constexpr double kLaneClearance = 2.0;
  static constexpr double kPassOverrun = 10.0;
  static constexpr double kSupportAhead = 6.0;
  static constexpr double kSupportAside = 8.0;
  static constexpr int kChaseLookahead = 5;

  // `teammates` and `opponents` give the observation's layout: 58 + 8 * (teammates + opponents).
  // pass_within: kPassWhenOpponentWithin (0 never passes).
  ScriptedTeamPlayer(int teammates, int opponents, bool shoot_action = false,
                     double pass_within = kPassWhenOpponentWithin, double pass_overrun = kPassOverrun);
  ParamAction act(std::span<const float> obs) override;
  void begin_episode() override { offense_.begin_episode(); }

  // How many passes act() has chosen since construction (tests, evaluation reports).
  [[nodiscard]] long passes() const { return passes_; }

 private:
  ParamAction go_to(Vec2 target_body, Vec2 face_body);
  [[nodiscard]] std::span<const float> view() const {
    return {params_.data(), static_cast<size_t>(shoot_action_ ? param::kCountWithShoot : param::kCount)};
  }

  int teammates_;
  int opponents_;
  bool shoot_action_;
  ScriptedOffense offense_;
  // The close-in offense's input: this player's 58 features and the nearest opponent's block.
  std::array<float, kNumAgentFeatures + kFeaturesPerPlayer> offense_view_{};
  std::array<float, param::kCountWithShoot> params_{};
  double pass_within_;
  double pass_overrun_;
  long passes_ = 0;
};

}  // namespace pamdp::hfo
