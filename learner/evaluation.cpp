#include "learner/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
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
  Policy* one = &policy;
  return evaluate(env, std::span<Policy* const>(&one, 1), episodes, seed, on_episode, on_step);
}

EvalResult evaluate(Env& env, std::span<Policy* const> players, int episodes, uint64_t seed,
                    const std::function<void(int)>& on_episode, const std::function<void(const EvalStep&)>& on_step) {
  const auto n = static_cast<size_t>(env.agents());
  if (players.size() != 1 && players.size() != n) {
    throw std::invalid_argument("evaluate: " + std::to_string(players.size()) + " policies for a game of " +
                                std::to_string(n) + " players; give one, or one per player");
  }
  const auto obs_dim = static_cast<size_t>(env.observation_size());
  const auto width = static_cast<size_t>(env.action_space().output_width());
  std::vector<float> obs(n * obs_dim);
  std::vector<float> seen(on_step ? obs.size() : 0);  // the observations the policies acted on
  // A policy's action views its own buffer until its next act(): each player's parameters are
  // copied out before the next player acts.
  std::vector<float> params(n * width);
  std::vector<ParamAction> actions(n);
  std::vector<float> rewards(n);
  std::vector<int> counts(8, 0);
  EvalResult res;
  res.episodes = episodes;
  double total_return = 0.0;
  int64_t total_steps = 0;
  int64_t goal_steps = 0;
  int goals = 0;
  std::vector<int64_t> counters_before;
  for (const EnvCounter& c : env.counters()) {
    counters_before.push_back(c.value);
  }
  const auto policy_of = [&](size_t i) -> Policy& { return *players[players.size() == 1 ? 0 : i]; };
  for (int ep = 0; ep < episodes; ++ep) {
    if (ep == 0) {
      env.reset(seed, obs);
    } else {
      env.reset(obs);
    }
    for (Policy* p : players) {
      p->begin_episode();
    }
    int steps = 0;
    StepResult sr;
    do {
      for (size_t i = 0; i < n; ++i) {
        const ParamAction a = policy_of(i).act(std::span<const float>(obs).subspan(i * obs_dim, obs_dim));
        const std::span<float> mine = std::span<float>(params).subspan(i * width, a.params.size());
        std::copy(a.params.begin(), a.params.end(), mine.begin());
        actions[i] = {a.id, mine};
      }
      if (on_step) {
        std::copy(obs.begin(), obs.end(), seen.begin());
      }
      if (n == 1) {
        sr = env.step(actions[0], obs);
        rewards[0] = sr.reward;
      } else {
        sr = env.step_team(actions, obs, rewards);
      }
      total_return += sr.reward;
      ++steps;
      if (on_step) {
        for (size_t i = 0; i < n; ++i) {
          on_step(EvalStep{ep,
                           steps,
                           std::span<const float>(seen).subspan(i * obs_dim, obs_dim),
                           actions[i],
                           {rewards[i], sr.status},
                           static_cast<int>(i)});
        }
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
  const std::span<const EnvCounter> counters = env.counters();
  for (size_t i = 0; i < counters.size(); ++i) {
    res.env_counters[std::string(counters[i].name)] =
        counters[i].value - (i < counters_before.size() ? counters_before[i] : 0);
  }
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
  if (!r.env_counters.empty()) {
    j["env_counters"] = r.env_counters;
  }
  return j.dump();
}

PolicyAgreement::PolicyAgreement(const ActionSpace& space)
    : space_(space),
      taken_(static_cast<size_t>(space.num_actions()), 0),
      same_(static_cast<size_t>(space.num_actions()), 0),
      errors_(static_cast<size_t>(space.num_actions())) {
  for (size_t a = 0; a < errors_.size(); ++a) {
    errors_[a].resize(space.actions[a].param_indices.size());
  }
}

void PolicyAgreement::add(const ParamAction& teacher, const ParamAction& student) {
  if (teacher.id < 0 || teacher.id >= space_.num_actions() || student.id < 0 || student.id >= space_.num_actions()) {
    throw std::logic_error("PolicyAgreement::add: an action id outside the action space");
  }
  const auto a = static_cast<size_t>(teacher.id);
  ++steps_;
  ++taken_[a];
  same_[a] += student.id == teacher.id ? 1 : 0;
  const std::vector<int>& owned = space_.actions[a].param_indices;
  for (size_t k = 0; k < owned.size(); ++k) {
    const auto i = static_cast<size_t>(owned[k]);
    const ParamSpec& p = space_.params[i];
    const double t =
        std::clamp(static_cast<double>(teacher.params[i]), static_cast<double>(p.lo), static_cast<double>(p.hi));
    const double s =
        std::clamp(static_cast<double>(student.params[i]), static_cast<double>(p.lo), static_cast<double>(p.hi));
    double d = std::abs(s - t);
    const double range = static_cast<double>(p.hi) - static_cast<double>(p.lo);
    if (range == 360.0) {
      d = std::min(d, 360.0 - d);
    }
    errors_[a][k].push_back(static_cast<float>(d));
  }
}

namespace {

// The q-quantile of `v` (nearest rank); v is reordered.
double quantile(std::vector<float>& v, double q) {
  if (v.empty()) {
    return 0.0;
  }
  const auto rank = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size()))) - (q > 0.0 ? 1 : 0);
  const auto at = v.begin() + static_cast<std::ptrdiff_t>(std::min(rank, v.size() - 1));
  std::nth_element(v.begin(), at, v.end());
  return static_cast<double>(*at);
}

}  // namespace

std::vector<PolicyAgreement::ActionRow> PolicyAgreement::rows() const {
  std::vector<ActionRow> out;
  for (size_t a = 0; a < taken_.size(); ++a) {
    if (taken_[a] == 0) {
      continue;
    }
    ActionRow row;
    row.name = space_.actions[a].name;
    row.steps = taken_[a];
    row.same = same_[a];
    const std::vector<int>& owned = space_.actions[a].param_indices;
    for (size_t k = 0; k < owned.size(); ++k) {
      std::vector<float> e = errors_[a][k];
      ParamError pe;
      pe.name = space_.params[static_cast<size_t>(owned[k])].name;
      pe.median = quantile(e, 0.5);
      pe.p90 = quantile(e, 0.9);
      row.params.push_back(std::move(pe));
    }
    out.push_back(std::move(row));
  }
  return out;
}

std::string PolicyAgreement::to_json() const {
  nlohmann::json j;
  j["steps"] = steps_;
  nlohmann::json actions = nlohmann::json::object();
  for (const ActionRow& r : rows()) {
    nlohmann::json a;
    a["steps"] = r.steps;
    a["same_action"] = static_cast<double>(r.same) / static_cast<double>(r.steps);
    nlohmann::json params = nlohmann::json::object();
    for (const ParamError& p : r.params) {
      params[p.name] = {{"median", p.median}, {"p90", p.p90}};
    }
    a["params"] = std::move(params);
    actions[r.name] = std::move(a);
  }
  j["actions"] = std::move(actions);
  return j.dump();
}

}  // namespace pamdp
