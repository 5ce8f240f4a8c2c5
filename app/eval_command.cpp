#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "app/actor_policy.hpp"
#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "app/progress.hpp"
#include "app/sim_options.hpp"
#include "core/policy.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "learner/checkpoint.hpp"
#include "learner/evaluation.hpp"

namespace pamdp::app {
namespace {

struct EvalOptions {
  std::string policy = "scripted";
  int episodes = 100;
  uint64_t seed = 1;
  bool json = false;
  std::string checkpoint;
  SimOptions sim;
};

void print_result(const std::string& name, const EvalResult& r, bool json) {
  std::printf("%-10s %9s %9s %18s %12s %10s\n", "policy", "episodes", "scoring", "avg steps to goal", "mean return",
              "avg steps");
  std::printf("%-10s %9d %9.3f %18.1f %12.3f %10.1f\n", name.c_str(), r.episodes, r.goal_rate, r.avg_steps_to_goal,
              r.avg_return, r.avg_steps);
  std::printf("outcomes:");
  for (const auto& [status, count] : r.outcomes) {
    std::printf(" %s=%d", status.c_str(), count);
  }
  std::printf("\n");
  if (json) {
    std::printf("%s\n", to_json(r).c_str());
  }
}

// A progress bar on stderr while it plays (only on a terminal).
EvalResult evaluate_with_progress(Env& env, Policy& policy, const EvalOptions& o) {
  ProgressBar bar("episodes", o.episodes);
  EvalResult r = evaluate(env, policy, o.episodes, o.seed, [&bar](int done) { bar.update(done); });
  bar.finish();
  return r;
}

// A trained actor, with the env and bounds of the run that wrote the checkpoint.
void run_checkpoint_eval(const EvalOptions& o) {
  ExperimentConfig c = parse_experiment_config(read_checkpoint_config(o.checkpoint), o.checkpoint + " (config)", {});
  if (o.sim.no_noise) {
    c.env.hfo.noise = false;
  }
  if (o.sim.config.goalie && !c.env.hfo.goalie) {
    throw std::runtime_error("--goalie: " + o.checkpoint +
                             " was trained without a goalie (env.goalie = false, 58 features); a checkpoint is "
                             "evaluated on its own env");
  }
  auto env = make_env(c.env);
  Ddpg ddpg(env->observation_size(), env->action_space(), c.ddpg, c.seed);
  load_checkpoint(o.checkpoint, ddpg);
  GreedyActorPolicy policy(ddpg, env->action_space(), resolve_exploration(c, env->action_space()));
  print_result("ddpg", evaluate_with_progress(*env, policy, o), o.json);
}

void run_eval(const EvalOptions& o) {
  if (!o.checkpoint.empty()) {
    run_checkpoint_eval(o);
    return;
  }
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
  print_result(o.policy, evaluate_with_progress(env, *policy, o), o.json);
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
  cmd->add_option("--checkpoint", opts->checkpoint,
                  "evaluate the greedy actor of a checkpoint written by pamdp train (its env settings are used)")
      ->check(CLI::ExistingFile);
  opts->sim.add_to(*cmd);
  cmd->callback([opts] { run_eval(*opts); });
}

}  // namespace pamdp::app
