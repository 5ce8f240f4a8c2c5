// pamdp: one executable, one subcommand per role or tool.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <regex>
#include <string>

#include "app/commands.hpp"
#include "core/log.hpp"

namespace {

// The subcommand a failed parse reached (`pamdp sim trace`: trace), or the top level.
const CLI::App* deepest_parsed(const CLI::App& app) {
  const CLI::App* at = &app;
  for (bool deeper = true; deeper;) {
    deeper = false;
    for (const CLI::App* sub : at->get_subcommands()) {
      if (sub->parsed()) {
        at = sub;
        deeper = true;
        break;
      }
    }
  }
  return at;
}

// "pamdp sim trace" for the subcommand `at`.
std::string command_path(const CLI::App* at) {
  std::string path;
  for (; at != nullptr; at = at->get_parent()) {
    path = at->get_parent() == nullptr ? "pamdp" + path : " " + at->get_name() + path;
  }
  return path;
}

std::string subcommand_names(const CLI::App* at) {
  std::string names;
  for (const CLI::App* sub : at->get_subcommands([](const CLI::App*) { return true; })) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  return names;
}

// Every error a user can cause is one line, `pamdp: error: …`, that names the fix, and exit
// status 2: CLI11's parse errors (a value out of range, a missing file, an unknown flag) as
// well as the commands' own (std::runtime_error).
int parse_error(const CLI::App& app, const CLI::ParseError& e) {
  const CLI::App* at = deepest_parsed(app);
  const std::string where = command_path(at);
  std::string what = e.what();
  if (e.get_name() == "RequiredError" && what.find("subcommand") != std::string::npos) {
    what = where + " needs a subcommand (valid: " + subcommand_names(at) + ")";
  }
  // CLI11's "Value -1 not in range 1 to 100" in the words config errors use.
  static const std::regex kRange("Value (.*) not in range (.*) to (.*)");
  what = std::regex_replace(what, kRange, "must be within [$2, $3], got $1");
  std::fprintf(stderr, "pamdp: error: %s; see %s --help\n", what.c_str(), where.c_str());
  return 2;
}

int run(int argc, char** argv) {
  CLI::App app{"pamdp: DDPG in parameterized action spaces (Hausknecht & Stone, ICLR 2016) on Half Field Offense"};
  app.require_subcommand(1);
  app.footer(
      "Exit status: 0 done; 2 an error you can fix (one line 'pamdp: error: ...' on stderr naming the fix); 3 an "
      "internal failure.");
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off (before or after the subcommand)")
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

  // The global --log-level may come after any subcommand's name too: an option a subcommand does
  // not know falls through to its parent.
  const auto fall_through = [](CLI::App* sub, const auto& self) -> void {
    sub->fallthrough();
    for (CLI::App* s : sub->get_subcommands([](const CLI::App*) { return true; })) {
      self(s, self);
    }
  };
  for (CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    fall_through(sub, fall_through);
  }

  bool known = false;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    known = known || (argc > 1 && sub->get_name() == argv[1]);
  }
  if (argc > 1 && argv[1][0] != '-' && !known) {
    std::fprintf(stderr, "pamdp: error: unknown subcommand '%s' (valid: %s); see pamdp --help\n", argv[1],
                 subcommand_names(&app).c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) {
      return app.exit(e);  // --help
    }
    return parse_error(app, e);
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
