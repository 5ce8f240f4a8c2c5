#include "learner/evaluation.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/rng.hpp"

namespace pamdp {

uint64_t screening_seed(uint64_t run_seed, int64_t updates) {
  return mix_seeds(run_seed, 1000 + static_cast<uint64_t>(updates));
}

uint64_t confirmation_seed(uint64_t run_seed, int64_t updates) {
  return mix_seeds(screening_seed(run_seed, updates), 1);
}

EvalResult evaluate(Env& env, Policy& policy, int episodes, uint64_t seed, const std::function<void(int)>& on_episode,
                    const std::function<void(const EvalStep&)>& on_step) {
  std::vector<float> obs(static_cast<size_t>(env.observation_size()));
  std::vector<float> seen(on_step ? obs.size() : 0);  // the observation the policy acted on
  std::vector<int> counts(8, 0);
  EvalResult res;
  res.episodes = episodes;
  double total_return = 0.0;
  int64_t total_steps = 0;
  int64_t goal_steps = 0;
  int goals = 0;
  for (int ep = 0; ep < episodes; ++ep) {
    if (ep == 0) {
      env.reset(seed, obs);
    } else {
      env.reset(obs);
    }
    policy.begin_episode();
    int steps = 0;
    StepResult sr;
    do {
      const ParamAction action = policy.act(obs);
      if (on_step) {
        std::copy(obs.begin(), obs.end(), seen.begin());
      }
      sr = env.step(action, obs);
      total_return += sr.reward;
      ++steps;
      if (on_step) {
        on_step(EvalStep{ep, steps, seen, action, sr});
      }
    } while (!sr.terminal() && steps <= env.max_episode_steps());
    if (!sr.terminal()) {
      throw std::runtime_error("evaluate: env '" + std::string(env.name()) + "' ran past its max_episode_steps()");
    }
    total_steps += steps;
    if (sr.status < 0) {
      throw std::runtime_error("evaluate: env '" + std::string(env.name()) + "' returned a negative status");
    }
    if (static_cast<size_t>(sr.status) >= counts.size()) {
      counts.resize(static_cast<size_t>(sr.status) + 1, 0);
    }
    ++counts[static_cast<size_t>(sr.status)];
    if (sr.status == env.success_status()) {
      ++goals;
      goal_steps += steps;
    }
    if (on_episode) {
      on_episode(ep + 1);
    }
  }
  for (int s : env.outcomes()) {
    if (s != 0) {
      res.outcomes[std::string(env.status_name(s))] =
          static_cast<size_t>(s) < counts.size() ? counts[static_cast<size_t>(s)] : 0;
    }
  }
  if (episodes > 0) {
    res.goal_rate = static_cast<double>(goals) / episodes;
    res.avg_return = total_return / episodes;
    res.avg_steps = static_cast<double>(total_steps) / episodes;
  }
  res.avg_steps_to_goal = goals > 0 ? static_cast<double>(goal_steps) / goals : 0.0;
  return res;
}

std::string to_json(const EvalResult& r) {
  nlohmann::json j;
  j["episodes"] = r.episodes;
  j["goal_rate"] = r.goal_rate;
  j["avg_steps_to_goal"] = r.avg_steps_to_goal;
  j["avg_return"] = r.avg_return;
  j["avg_steps"] = r.avg_steps;
  j["outcomes"] = r.outcomes;
  return j.dump();
}

}  // namespace pamdp
