// Evaluation with the paper's protocol: play N episodes with a fixed policy and report the
// scoring rate and the average number of steps to goal (the paper's table), plus outcome
// counts and the mean return. Allocates only at construction of its buffers.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <span>
#include <string>

#include "core/policy.hpp"
#include "envs/env.hpp"

namespace pamdp {

struct EvalResult {
  int episodes = 0;
  double goal_rate = 0.0;          // fraction of episodes ending with env.success_status()
  double avg_steps_to_goal = 0.0;  // over successful episodes only; 0 if none
  double avg_return = 0.0;
  double avg_steps = 0.0;               // over all episodes
  std::map<std::string, int> outcomes;  // status name -> count (every outcome listed)
};

// One decision of an evaluation, as `on_step` sees it: the observation the policy read, the
// action it chose and what the env answered. Views are valid only during the call.
struct EvalStep {
  int episode = 0;  // 0-based
  int step = 0;     // 1-based within the episode
  std::span<const float> obs;
  ParamAction action;
  StepResult result;
};

// Plays `episodes` episodes; the first reset uses `seed`, later ones continue the env's stream.
// `on_episode`, when given, is called with the number of episodes done after each one;
// `on_step`, when given, after every step (the results do not depend on either).
EvalResult evaluate(Env& env, Policy& policy, int episodes, uint64_t seed,
                    const std::function<void(int)>& on_episode = {},
                    const std::function<void(const EvalStep&)>& on_step = {});

// The starts of a run's greedy evaluation after `updates` updates (train.eval_episodes), and the
// other starts its confirmation plays (train.confirm_episodes). `pamdp train` and `pamdp learner`
// both use these, so a run's seed picks the same starts whichever of them trains it.
uint64_t screening_seed(uint64_t run_seed, int64_t updates);
uint64_t confirmation_seed(uint64_t run_seed, int64_t updates);

// One JSON object (no newline) with keys episodes, goal_rate, avg_steps_to_goal, avg_return,
// avg_steps, outcomes.
std::string to_json(const EvalResult& r);

}  // namespace pamdp
