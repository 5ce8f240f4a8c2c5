#include <memory>

#include "envs/goal/goal_env.hpp"
#include "envs/registry.hpp"
#include "envs/scaled_parameters.hpp"

namespace pamdp {
namespace {

// MP-DQN's hand-made starting parameters for Goal (cycraig/MP-DQN run_goal_pdqn.py,
// --initialise-params with --scale-actions: kickto_weights, shoot_goal_left/right_weights), in
// [-1, 1] parameter units over the 17 scaled features: kick towards a point ahead of the ball
// and away from the keeper (features 10, 11: ball position; 14, 15: keeper-to-ball unit vector);
// shoot at a fixed point inside each post.
ParameterPrior goal_prior_scaled() {
  constexpr int kObs = goal::GoalEnv::kObservationSize;
  ParameterPrior p{
      kObs, std::vector<float>(4 * kObs, 0.0F), {-0.375F, 0.0F, 0.857346647646219686F, -0.857346647646219686F}};
  const auto w = [&](int param, int feature, float value) {
    p.weights[static_cast<size_t>(param * kObs + feature)] = value;
  };
  w(0, 10, 0.5F);                 // kick_to_x
  w(0, 14, 0.0625F);              //
  w(1, 11, 0.8333333333333333F);  // kick_to_y
  w(1, 15, 0.1111111111111111F);  //
  return p;
}

}  // namespace

void register_goal_env(EnvRegistry& registry) {
  EnvRegistration r;
  r.name = "goal";
  r.description = "Robot Soccer Goal (Masson et al. 2016, gym-goal): kick past a keeper (17 features)";
  // Declared as the hfo env declares it (EnvRegistry::add checks): acceleration noise on or off.
  // env.scaled_parameters, as platform declares it: every parameter over [-1, 1], as MP-DQN plays it.
  r.keys = {EnvKey::boolean("noise", true), EnvKey::boolean("scaled_parameters", false)};
  r.make = [](const EnvParams& p) {
    return scaled_if(p.boolean("scaled_parameters"),
                     std::make_unique<goal::GoalEnv>(goal::GoalConfig{.noise = p.boolean("noise")}));
  };
  r.observation_size = [](const EnvParams&) { return goal::GoalEnv::kObservationSize; };
  r.observation_bound = goal::GoalEnv::kObservationBound;
  r.parameter_prior = [](const EnvParams& p) -> std::optional<ParameterPrior> {
    if (p.boolean("scaled_parameters")) {
      return goal_prior_scaled();
    }
    return prior_in_units_of(goal_prior_scaled(), goal::GoalEnv(goal::GoalConfig{}).action_space());
  };
  registry.add(std::move(r));
}

}  // namespace pamdp
