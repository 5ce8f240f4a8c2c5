// Command-line options shared by every subcommand that builds an embedded HFO simulator.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>

#include "app/experiment_config.hpp"
#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::app {

struct SimOptions {
  pamdp::hfo::SoccerSimConfig config;
  bool no_noise = false;

  void add_to(CLI::App& cmd) {
    cmd.add_flag("--no-noise", no_noise, "switch off movement, turn, kick and tackle noise");
    cmd.add_flag("--goalie", config.goalie, "an NPC goalie defends the goal (1v1; 66 features instead of 58)");
    const std::map<std::string, pamdp::hfo::StartDistribution> starts(start_choices().begin(), start_choices().end());
    cmd.add_option("--start", config.start, "start distribution: paper (E1), dec2015 (E2), hfo (E3)")
        ->transform(CLI::CheckedTransformer(starts, CLI::ignore_case))
        ->default_str("paper");
    const std::map<std::string, pamdp::hfo::Referee> referees(referee_choices().begin(), referee_choices().end());
    cmd.add_option("--referee", config.referee, "episode rules: server (HFORef, default) or trainer (paper era)")
        ->transform(CLI::CheckedTransformer(referees, CLI::ignore_case))
        ->default_str("server");
    const std::map<std::string, pamdp::hfo::BodyAtReset> bodies(body_at_reset_choices().begin(),
                                                                body_at_reset_choices().end());
    cmd.add_option("--body-reset", config.body_at_reset, "body angle at episode start: carry, zero, uniform")
        ->transform(CLI::CheckedTransformer(bodies, CLI::ignore_case))
        ->default_str("carry");
    cmd.add_option("--max-steps", config.max_steps, "episode time limit in steps")
        ->check(CLI::Range(1, 1000000))
        ->capture_default_str();
    cmd.add_option("--untouched-limit", config.untouched_limit, "cycles the ball may stay untouched")
        ->check(CLI::Range(1, 1000000))
        ->capture_default_str();
  }

  [[nodiscard]] pamdp::hfo::SoccerSimConfig resolved() const {
    auto c = config;
    c.noise = !no_noise;
    return c;
  }
};

}  // namespace pamdp::app
