// Subcommand registration. Each register_* adds one subcommand whose callback runs the
// command; errors a user can cause are thrown as std::runtime_error with a message that
// names the problem and the fix, and main() prints them and exits with status 2.
#pragma once

#include <CLI/CLI.hpp>

namespace pamdp::app {

void register_actor(CLI::App& app);
void register_eval(CLI::App& app);
void register_sim(CLI::App& app);
void register_train(CLI::App& app);
void register_replay(CLI::App& app);
void register_learner(CLI::App& app);
void register_keygen(CLI::App& app);
void register_monitor(CLI::App& app);
void register_plot(CLI::App& app);

}  // namespace pamdp::app
