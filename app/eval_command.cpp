#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "app/commands.hpp"
#include "app/sim_options.hpp"
#include "core/policy.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "learner/evaluation.hpp"

namespace pamdp::app {
namespace {

struct EvalOptions {
  std::string policy = "scripted";
  int episodes = 100;
  uint64_t seed = 1;
  bool json = false;
  SimOptions sim;
};

void run_eval(const EvalOptions& o) {
  hfo::HfoEnv env(o.sim.resolved());
  std::unique_ptr<Policy> policy;
  if (o.policy == "scripted") {
    policy = std::make_unique<hfo::ScriptedOffense>();
  } else {
    // The paper's exploration draw: Tackle masked, dash power U[-100, 100] (reference §7.3).
    auto random = std::make_unique<RandomPolicy>(env.action_space(), o.seed ^ 0x5eedULL,
                                                 std::vector<int>{hfo::kDash, hfo::kTurn, hfo::kKick});
    random->set_param_range(hfo::param::kDashPower, -100.0F, 100.0F);
    policy = std::move(random);
  }
  const EvalResult r = evaluate(env, *policy, o.episodes, o.seed);

  std::printf("%-10s %9s %9s %18s %12s %10s\n", "policy", "episodes", "scoring", "avg steps to goal", "mean return",
              "avg steps");
  std::printf("%-10s %9d %9.3f %18.1f %12.3f %10.1f\n", o.policy.c_str(), r.episodes, r.goal_rate, r.avg_steps_to_goal,
              r.avg_return, r.avg_steps);
  std::printf("outcomes:");
  for (const auto& [name, count] : r.outcomes) {
    std::printf(" %s=%d", name.c_str(), count);
  }
  std::printf("\n");
  if (o.json) {
    std::printf("%s\n", to_json(r).c_str());
  }
}

}  // namespace

void register_eval(CLI::App& app) {
  auto opts = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand("eval", "play N episodes with a policy and print the paper's table row");
  cmd->add_option("--policy", opts->policy, "scripted (hand-coded offense) or random")
      ->check(CLI::IsMember({"scripted", "random"}))
      ->capture_default_str();
  cmd->add_option("--episodes", opts->episodes, "number of episodes (the paper used 100)")
      ->check(CLI::Range(1, 100000000))
      ->capture_default_str();
  cmd->add_option("--seed", opts->seed, "random seed of the evaluation")->capture_default_str();
  cmd->add_flag("--json", opts->json, "print one JSON object as the last line");
  opts->sim.add_to(*cmd);
  cmd->callback([opts] { run_eval(*opts); });
}

}  // namespace pamdp::app
