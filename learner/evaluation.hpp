// Evaluation with the paper's protocol: play N episodes with a fixed policy and report the
// scoring rate and the average number of steps to goal (the paper's table), plus outcome
// counts and the mean return. Allocates only at construction of its buffers.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

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
  // The env's counters (Env::counters()) over these episodes; empty for envs that keep none.
  std::map<std::string, int64_t> env_counters;
};

// One decision of an evaluation, as `on_step` sees it: the observation the policy read, the
// action it chose and what the env answered. Views are valid only during the call.
struct EvalStep {
  int episode = 0;  // 0-based
  int step = 0;     // 1-based within the episode
  std::span<const float> obs;
  ParamAction action;
  StepResult result;  // a team's: the game's status and this player's reward
  int player = 0;     // in a team game (Env::agents() > 1), whose step this is; each player's in turn
};

// Plays `episodes` episodes (every player of a team game with `policy`); the first reset uses `seed`, later ones
// continue the env's stream. `on_episode`, when given, is called with the number of episodes done after each one;
// `on_step`, when given, after every step (the results do not depend on either).
EvalResult evaluate(Env& env, Policy& policy, int episodes, uint64_t seed,
                    const std::function<void(int)>& on_episode = {},
                    const std::function<void(const EvalStep&)>& on_step = {});
// A team game (Env::agents() > 1): `players` holds one policy for every player (parameter
// sharing: each acts on its own observation), or one per player. The return is the players' mean.
EvalResult evaluate(Env& env, std::span<Policy* const> players, int episodes, uint64_t seed,
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

// How closely a student policy follows its teacher in the teacher's own states (`pamdp eval
// --checkpoint C --agreement`: the scripted offense plays, the checkpoint's greedy actor is asked
// at every step). For each action the teacher took: how often the student took the same one, and
// how far the student's parameters of that action were from the teacher's, in the parameter's
// units, the student's clamped to the bounds first (the env clamps them so); an angle's
// difference (a parameter whose range is 360) goes the short way round, so it is at most 180.
class PolicyAgreement {
 public:
  explicit PolicyAgreement(const ActionSpace& space);

  void add(const ParamAction& teacher, const ParamAction& student);

  struct ParamError {
    std::string name;
    double median = 0.0;
    double p90 = 0.0;  // the 90th percentile
  };
  struct ActionRow {
    std::string name;
    int64_t steps = 0;  // steps in which the teacher took this action
    int64_t same = 0;   // ... and the student took it too
    std::vector<ParamError> params;
  };
  // The actions the teacher took at least once, in the action space's order.
  [[nodiscard]] std::vector<ActionRow> rows() const;
  [[nodiscard]] int64_t steps() const { return steps_; }
  // One JSON object (no newline): {"steps": N, "actions": {"DASH": {"steps", "same_action",
  // "params": {"dash_power": {"median", "p90"}, ...}}, ...}}; same_action is a fraction.
  [[nodiscard]] std::string to_json() const;

 private:
  ActionSpace space_;  // a copy: the env may be gone when the rows are read
  int64_t steps_ = 0;
  std::vector<int64_t> taken_;                           // per action
  std::vector<int64_t> same_;                            // per action
  std::vector<std::vector<std::vector<float>>> errors_;  // per action, per owned parameter
};

}  // namespace pamdp
