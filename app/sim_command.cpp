#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "app/commands.hpp"
#include "app/sim_options.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/state_io.hpp"

namespace pamdp::app {
namespace {

struct TraceOptions {
  std::string init;
  std::string actions;
  uint64_t seed = 1;
  SimOptions sim;
};

void print_row(int step, int status, float reward, std::span<const float> obs) {
  std::printf("%d,%s,%.9g", step, hfo::status_name(status), static_cast<double>(reward));
  for (float v : obs) {
    std::printf(",%.9g", static_cast<double>(v));
  }
  std::printf("\n");
}

void run_trace(const TraceOptions& o) {
  const hfo::InitialState init = hfo::load_state_json(o.init);
  const std::vector<hfo::ScriptedAction> actions = hfo::load_actions_csv(o.actions);
  hfo::HfoEnv env(o.sim.resolved());
  std::vector<float> obs(static_cast<size_t>(env.observation_size()));
  std::vector<float> discard(obs.size());
  env.reset(o.seed, discard);  // seeds the noise stream
  env.set_state(init.agent, init.ball, obs);

  std::printf("step,status,reward");
  for (size_t i = 0; i < obs.size(); ++i) {
    std::printf(",f%zu", i);
  }
  std::printf("\n");
  print_row(0, hfo::kInGame, 0.0F, obs);
  int step = 0;
  for (const auto& a : actions) {
    const StepResult r = env.step({a.id, a.params}, obs);
    print_row(++step, r.status, r.reward, obs);
    if (r.terminal()) {
      if (static_cast<size_t>(step) < actions.size()) {
        std::fprintf(stderr, "pamdp sim trace: episode ended (%s) after %d of %zu actions; the rest were not run\n",
                     hfo::status_name(r.status), step, actions.size());
      }
      break;
    }
  }
}

}  // namespace

void register_sim(CLI::App& app) {
  CLI::App* sim = app.add_subcommand("sim", "the embedded HFO simulator");
  sim->require_subcommand(1);
  auto opts = std::make_shared<TraceOptions>();
  CLI::App* trace = sim->add_subcommand(
      "trace",
      "replay an action script from a given state and print step,status,reward,f0..f57 (f0..f65 with --goalie) as CSV");
  trace
      ->add_option("--init", opts->init, "STATE.json: {agent: {x, y, vx, vy, body_deg, stamina}, ball: {x, y, vx, vy}}")
      ->required()
      ->check(CLI::ExistingFile);
  trace
      ->add_option("--actions", opts->actions,
                   "ACTIONS.csv: rows DASH,power,dir | TURN,dir | TACKLE,dir | KICK,power,dir")
      ->required()
      ->check(CLI::ExistingFile);
  trace->add_option("--seed", opts->seed, "seed of the noise stream")->capture_default_str();
  opts->sim.add_to(*trace);
  trace->callback([opts] { run_trace(*opts); });
}

}  // namespace pamdp::app
