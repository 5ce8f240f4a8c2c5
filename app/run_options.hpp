// The command-line options `pamdp train` and `pamdp learner` share: which config, overrides,
// seed, run directory or run to resume, quiet, and where to serve /metrics.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/experiment_config.hpp"
#include "app/run_support.hpp"

namespace pamdp::app {

struct RunCliOptions {
  std::string config;
  std::vector<std::string> sets;
  int64_t seed = -1;
  std::string run_dir;
  std::string resume;
  bool quiet = false;
  std::string metrics_bind;  // overrides metrics.bind when set
  int metrics_port = -1;     // overrides metrics.port when >= 0

  // --metrics-bind / --metrics-port over the config's [metrics].
  void apply_metrics_overrides(ExperimentConfig& c) const {
    if (!metrics_bind.empty()) {
      c.metrics.bind = metrics_bind;
    }
    if (metrics_port >= 0) {
      c.metrics.port = metrics_port;
    }
  }
};

// What a run starts from: a new run's config (--config, --set, --seed) and directory (--run-dir,
// or runs/<time>-<label_prefix>seed<N>), or the run in --resume DIR (its config.toml, with --set
// on top). Throws naming the fix when the options clash or the directories do not fit.
struct ResolvedRun {
  ExperimentConfig config;
  std::string run_dir;
  bool resume = false;
};

inline ResolvedRun resolve_run(const RunCliOptions& o, const std::string& command, const std::string& label_prefix) {
  namespace fs = std::filesystem;
  ResolvedRun r;
  if (!o.resume.empty()) {
    if (!o.config.empty()) {
      throw std::runtime_error(
          "--resume uses the config saved in the run directory; drop --config (use --set to change limits)");
    }
    const fs::path dir(o.resume);
    if (!fs::exists(dir / "config.toml") || !fs::exists(dir / "checkpoint.ckpt")) {
      throw std::runtime_error(
          "--resume " + o.resume +
          ": no config.toml and checkpoint.ckpt there; pass the run directory of an earlier pamdp " + command);
    }
    r.config = load_experiment_config((dir / "config.toml").string(), o.sets);
    r.run_dir = o.resume;
    r.resume = true;
    return r;
  }
  r.config = load_experiment_config(o.config, o.sets);
  if (o.seed >= 0) {
    r.config.seed = static_cast<uint64_t>(o.seed);
  }
  r.run_dir =
      o.run_dir.empty() ? timestamped_run_dir(label_prefix + "seed" + std::to_string(r.config.seed)) : o.run_dir;
  if (fs::exists(fs::path(r.run_dir) / "checkpoint.ckpt")) {
    throw std::runtime_error("run directory '" + r.run_dir + "' already holds a run; continue it with --resume " +
                             r.run_dir + " or choose another --run-dir");
  }
  return r;
}

// The help texts that differ between the two commands.
struct RunOptionHelp {
  std::string config;
  std::string set;
  std::string run_dir;
};

inline void add_run_options(CLI::App& cmd, RunCliOptions& o, const RunOptionHelp& help) {
  cmd.add_option("--config", o.config, help.config);
  cmd.add_option("--set", o.sets, help.set);
  cmd.add_option("--seed", o.seed, "random seed (overrides the config's seed)")->check(CLI::NonNegativeNumber);
  cmd.add_option("--run-dir", o.run_dir, help.run_dir);
  cmd.add_option("--resume", o.resume, "continue the run in this directory from its checkpoint");
  cmd.add_flag("--quiet", o.quiet,
               "no progress lines and no [info] log lines (warnings and errors still print; an explicit --log-level "
               "wins)");
  cmd.add_option("--metrics-bind", o.metrics_bind, "address to serve /metrics on (overrides metrics.bind)");
  cmd.add_option("--metrics-port", o.metrics_port, "port of /metrics, 0 = any free port (overrides metrics.port)")
      ->check(CLI::Range(0, 65535));
}

}  // namespace pamdp::app
