#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "app/role_metrics.hpp"
#include "app/run_options.hpp"
#include "app/run_support.hpp"
#include "app/trainer.hpp"
#include "core/log.hpp"

namespace pamdp::app {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_signal(int /*sig*/) {
  g_stop.store(true);
}

struct TrainCliOptions : RunCliOptions {
  bool json = false;
};

void run_train(const TrainCliOptions& o) {
  namespace fs = std::filesystem;
  if (o.quiet) {
    log::quiet();
  }
  ResolvedRun run = resolve_run(o, "train", "");
  ExperimentConfig& config = run.config;
  TrainOptions opts;
  opts.run_dir = run.run_dir;
  opts.resume = run.resume;
  opts.quiet = o.quiet;
  opts.stop = &g_stop;
  o.apply_metrics_overrides(config);
  MetricsEndpoint endpoint("train", opts.run_dir, config.metrics.bind, config.metrics.port, "");
  TrainMetrics train_metrics(endpoint.registry(), *make_env(config.env), config.replay.capacity);
  opts.metrics = &train_metrics;
  fs::create_directories(opts.run_dir);
  write_metrics_urls((fs::path(opts.run_dir) / "metrics_urls.txt").string(), {endpoint.url()});
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (!o.quiet) {
    std::printf("pamdp train: env %s, bound %s, seed %llu, run directory %s%s\n", config.env.name.c_str(),
                bound_method_name(config.ddpg.bound), static_cast<unsigned long long>(config.seed),
                opts.run_dir.c_str(), opts.resume ? " (resumed)" : "");
    std::fflush(stdout);
  }
  const TrainSummary s = train(config, opts);
  // Steps to success only when some episode succeeded: an average over none is not 0.
  char to_success[64] = "";
  if (s.final_eval.goal_rate > 0.0) {
    std::snprintf(to_success, sizeof(to_success), ", avg steps to success %.1f", s.final_eval.avg_steps_to_goal);
  }
  std::printf(
      "done: %lld updates, %lld episodes, %lld env steps in %.1f s; greedy eval %d episodes: success %.3f%s, "
      "return %.3f; checkpoint %s/checkpoint.ckpt\n",
      static_cast<long long>(s.updates), static_cast<long long>(s.episodes), static_cast<long long>(s.env_steps),
      s.seconds, s.final_eval.episodes, s.final_eval.goal_rate, to_success, s.final_eval.avg_return,
      opts.run_dir.c_str());
  if (o.json) {
    std::printf(
        "{\"run_dir\":\"%s\",\"updates\":%lld,\"episodes\":%lld,\"env_steps\":%lld,\"seconds\":%.3f,\"eval\":%s}\n",
        opts.run_dir.c_str(), static_cast<long long>(s.updates), static_cast<long long>(s.episodes),
        static_cast<long long>(s.env_steps), s.seconds, to_json(s.final_eval).c_str());
  }
}

}  // namespace

void register_train(CLI::App& app) {
  auto o = std::make_shared<TrainCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "train",
      "train a learner (train.algorithm, DDPG by default) in one process (env, replay and learner in one thread)");
  add_run_options(*cmd, *o,
                  {"TOML config (presets: deploy/configs/paper.toml, fast.toml, reach_stop.toml); default: built-in "
                   "paper settings",
                   "override one config key, e.g. --set ddpg.gamma=0.95 (repeatable)",
                   "where config, metrics and checkpoints go (default runs/<time>-seed<S>)"});
  cmd->add_flag("--json", o->json, "print one JSON summary object as the last line");
  cmd->footer(env_help_footer() + "\n\n" + algorithm_help_footer());
  cmd->callback([o] { run_train(*o); });
}

}  // namespace pamdp::app
