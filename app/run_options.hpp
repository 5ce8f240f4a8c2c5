// The command-line options `pamdp train` and `pamdp learner` share: which config, overrides,
// seed, run directory or run to resume, quiet, and where to serve /metrics.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "app/experiment_config.hpp"

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
  cmd.add_flag("--quiet", o.quiet, "no progress lines");
  cmd.add_option("--metrics-bind", o.metrics_bind, "address to serve /metrics on (overrides metrics.bind)");
  cmd.add_option("--metrics-port", o.metrics_port, "port of /metrics, 0 = any free port (overrides metrics.port)")
      ->check(CLI::Range(0, 65535));
}

}  // namespace pamdp::app
