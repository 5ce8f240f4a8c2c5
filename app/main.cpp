// pamdp: one executable, one subcommand per role or tool.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "app/commands.hpp"
#include "core/log.hpp"

namespace {

int run(int argc, char** argv) {
  CLI::App app{"pamdp: DDPG in parameterized action spaces (Hausknecht & Stone, ICLR 2016) on Half Field Offense"};
  app.require_subcommand(1);
  // On a parse error also show the usage, so an unknown or missing subcommand lists the valid ones.
  app.failure_message(CLI::FailureMessage::help);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->each([](const std::string& level) { pamdp::log::set_level(level); })
      ->capture_default_str();

  pamdp::app::register_actor(app);
  pamdp::app::register_eval(app);
  pamdp::app::register_sim(app);
  pamdp::app::register_train(app);
  pamdp::app::register_replay(app);
  pamdp::app::register_learner(app);
  pamdp::app::register_keygen(app);
  pamdp::app::register_monitor(app);
  pamdp::app::register_plot(app);

  std::string valid;
  bool known = false;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    valid += (valid.empty() ? "" : ", ") + sub->get_name();
    known = known || (argc > 1 && sub->get_name() == argv[1]);
  }
  if (argc > 1 && argv[1][0] != '-' && !known) {
    std::fprintf(stderr, "pamdp: unknown subcommand '%s' (valid: %s); see pamdp --help\n", argv[1], valid.c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pamdp: error: %s\n", e.what());
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pamdp: fatal: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "pamdp: fatal: unknown exception\n");
  }
  return 3;
}
