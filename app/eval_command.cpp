#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/cli_checks.hpp"
#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "app/progress.hpp"
#include "app/sim_options.hpp"
#include "core/policy.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/scripted_offense.hpp"
#include "envs/hfo/scripted_team.hpp"
#include "envs/hfo/settings.hpp"
#include "envs/registry.hpp"
#include "learner/checkpoint.hpp"
#include "learner/evaluation.hpp"
#include "learner/greedy_policy.hpp"

namespace pamdp::app {
namespace {

struct EvalOptions {
  std::string policy = "scripted";
  int episodes = 100;
  uint64_t seed = 1;
  bool json = false;
  std::string checkpoint;
  std::string env;                // overrides env.name
  std::vector<std::string> sets;  // env.* overrides
  std::string trace;              // CSV of every step, when set
  ActorCopy actor =
      ActorCopy::kOnline;  // which actor of a checkpoint plays (--actor; unset: the one its run evaluated)
  bool agreement = false;  // the scripted offense plays, the checkpoint's actor is asked
  hfo::ShotAim shot = hfo::ShotAim::kBestCourse;  // the scripted offense's (--shot)
  int offense_agents = 1;                         // --offense-agents: a team in the embedded simulator
  SimOptions sim;
};

// `--trace FILE`: one CSV row per step with the observation the policy read, the action and
// parameters it chose, and the env's reward and status, so that a user can see what a policy
// does (how often it kicks, from where it shoots) without a debugger.
class TraceCsv {
 public:
  TraceCsv(const std::string& path, const Env& env)
      : file_(std::fopen(path.c_str(), "w")), env_(env), team_(env.agents() > 1) {
    if (file_ == nullptr) {
      throw std::runtime_error("--trace " + path + ": cannot create the file (" + std::strerror(errno) +
                               "); give a path in a writable directory");
    }
    // A team game's rows say whose step each is, each player's in turn.
    std::fprintf(file_, team_ ? "episode,step,player,action" : "episode,step,action");
    for (const ParamSpec& p : env.action_space().params) {
      std::fprintf(file_, ",%s", p.name.c_str());
    }
    std::fprintf(file_, ",reward,status");
    for (int i = 0; i < env.observation_size(); ++i) {
      std::fprintf(file_, ",obs_%d", i);
    }
    std::fprintf(file_, "\n");
  }
  TraceCsv(const TraceCsv&) = delete;
  TraceCsv& operator=(const TraceCsv&) = delete;
  ~TraceCsv() { std::fclose(file_); }

  void write(const EvalStep& s) {
    const std::string& action = env_.action_space().actions[static_cast<size_t>(s.action.id)].name;
    if (team_) {
      std::fprintf(file_, "%d,%d,%d,%s", s.episode, s.step, s.player, action.c_str());
    } else {
      std::fprintf(file_, "%d,%d,%s", s.episode, s.step, action.c_str());
    }
    for (float p : s.action.params) {
      std::fprintf(file_, ",%.6g", p);
    }
    const std::string_view status = env_.status_name(s.result.status);
    std::fprintf(file_, ",%.6g,%.*s", s.result.reward, static_cast<int>(status.size()), status.data());
    for (float x : s.obs) {
      std::fprintf(file_, ",%.6g", x);
    }
    std::fprintf(file_, "\n");
  }

 private:
  std::FILE* file_;
  const Env& env_;
  bool team_;
};

// `--agreement`: the teacher plays; the student is asked the same question at every step, and
// the tally records how its answer differs.
class Shadowed final : public Policy {
 public:
  Shadowed(Policy& teacher, Policy& student, PolicyAgreement& tally)
      : teacher_(teacher), student_(student), tally_(tally) {}

  void begin_episode() override {
    teacher_.begin_episode();
    student_.begin_episode();
  }
  ParamAction act(std::span<const float> obs) override {
    const ParamAction t = teacher_.act(obs);
    tally_.add(t, student_.act(obs));
    return t;
  }

 private:
  Policy& teacher_;
  Policy& student_;
  PolicyAgreement& tally_;
};

void print_agreement(const PolicyAgreement& a, const std::string& checkpoint) {
  std::printf("\nagreement of %s's greedy actor with the scripted offense, in the offense's states (%lld steps)\n",
              checkpoint.c_str(), static_cast<long long>(a.steps()));
  std::printf("%-8s %8s %12s  %s\n", "offense", "steps", "same action", "|parameter difference|: median / 90th pct");
  for (const PolicyAgreement::ActionRow& r : a.rows()) {
    std::printf("%-8s %8lld %12.3f ", r.name.c_str(), static_cast<long long>(r.steps),
                static_cast<double>(r.same) / static_cast<double>(r.steps));
    for (const PolicyAgreement::ParamError& p : r.params) {
      std::printf(" %s %.1f / %.1f", p.name.c_str(), p.median, p.p90);
    }
    std::printf("\n");
  }
}

void print_result(const std::string& name, const EvalResult& r, bool json, const PolicyAgreement* agreement = nullptr,
                  const std::string& checkpoint = {}) {
  std::printf("%-10s %9s %9s %18s %12s %10s\n", "policy", "episodes", "scoring", "avg steps to goal", "mean return",
              "avg steps");
  // Steps to goal only when some episode scored: an average over none is not 0 (--json keeps its 0).
  char to_goal[32] = "-";
  if (r.goal_rate > 0.0) {
    std::snprintf(to_goal, sizeof(to_goal), "%.1f", r.avg_steps_to_goal);
  }
  std::printf("%-10s %9d %9.3f %18s %12.3f %10.1f\n", name.c_str(), r.episodes, r.goal_rate, to_goal, r.avg_return,
              r.avg_steps);
  std::printf("outcomes:");
  for (const auto& [status, count] : r.outcomes) {
    std::printf(" %s=%d", status.c_str(), count);
  }
  std::printf("\n");
  if (!r.env_counters.empty()) {
    std::printf("env counters:");
    for (const auto& [counter, value] : r.env_counters) {
      std::printf(" %s=%lld", counter.c_str(), static_cast<long long>(value));
    }
    std::printf("\n");
  }
  if (agreement != nullptr) {
    print_agreement(*agreement, checkpoint);
  }
  if (json) {
    std::string line = to_json(r);
    if (agreement != nullptr) {
      line.pop_back();  // the closing brace
      line += ",\"agreement\":" + agreement->to_json() + "}";
    }
    std::printf("%s\n", line.c_str());
  }
}

// Plays the episodes (a team game: `players` holds one policy for all, or one per player) with a
// progress bar on stderr (only on a terminal), then gives the env back
// (a real server's client prints as it leaves, which must come before the table) and reports
// the pace on stderr (stdout stays the same for the same seed).
EvalResult evaluate_with_progress(std::unique_ptr<Env> env, std::span<Policy* const> players, const EvalOptions& o) {
  ProgressBar bar("episodes", o.episodes);
  std::optional<TraceCsv> trace;
  std::function<void(const EvalStep&)> on_step;
  if (!o.trace.empty()) {
    trace.emplace(o.trace, *env);
    on_step = [&trace](const EvalStep& s) { trace->write(s); };
  }
  const auto start = std::chrono::steady_clock::now();
  EvalResult r = evaluate(
      *env, players, o.episodes, o.seed, [&bar](int done) { bar.update(done); }, on_step);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  bar.finish();
  const std::string env_name(env->name());
  env.reset();
  const double steps = r.avg_steps * r.episodes;
  std::fprintf(stderr, "eval: env %s, %.0f steps in %.1f s (%.0f steps/s)\n", env_name.c_str(), steps, seconds,
               seconds > 0.0 ? steps / seconds : 0.0);
  return r;
}

EvalResult evaluate_with_progress(std::unique_ptr<Env> env, Policy& policy, const EvalOptions& o) {
  Policy* one = &policy;
  return evaluate_with_progress(std::move(env), std::span<Policy* const>(&one, 1), o);
}

// The simulator flags and the env.* keys they set. An env that does not read one (hfo-server: the
// server's own flags set up its game) refuses the flag rather than ignoring it.
constexpr std::pair<const char*, const char*> kSimFlags[] = {
    {"--no-noise", "noise"},           {"--start", "start"},         {"--referee", "referee"},
    {"--body-reset", "body_at_reset"}, {"--max-steps", "max_steps"}, {"--untouched-limit", "untouched_limit"}};

void refuse_unread_sim_options(const CLI::App& cmd, const std::string& env) {
  for (const auto& [flag, key] : kSimFlags) {
    if (cmd.count(flag) > 0 && !env_registry().reads(env, key)) {
      throw std::runtime_error(std::string(flag) + " sets env." + key + ", which env '" + env +
                               "' does not read: " + env_registry().find(env).description);
    }
  }
}

// A checkpoint is played on its run's env settings, except those a simulator flag given on the
// command line changes (--start hfo: the real server's start distribution).
void apply_given_sim_options(const CLI::App& cmd, const SimOptions& sim, EnvConfig& env) {
  refuse_unread_sim_options(cmd, env.name);
  EnvParams given;
  hfo::set_sim_config(given, sim.resolved());
  for (const auto& [flag, key] : kSimFlags) {
    if (cmd.count(flag) > 0) {
      env.params.set(key, given.at(key));
    }
  }
}

// `sets` applied to `c` with the config file's validation; only env.* keys.
ExperimentConfig with_env_overrides(const ExperimentConfig& c, const std::vector<std::string>& sets) {
  for (const std::string& s : sets) {
    if (s.rfind("env.", 0) != 0) {
      throw std::runtime_error("--set '" + s + "': eval takes env.* settings only, e.g. --set env.server_port=7000");
    }
  }
  return sets.empty() ? c : parse_experiment_config(to_toml(c), "eval --set", sets);
}

// A trained actor, with the env and bounds of the run that wrote the checkpoint; `--env
// hfo-server` plays it on the real server, in the embedded encoding when it was trained in-process.
void run_checkpoint_eval(const EvalOptions& o, const CLI::App& cmd) {
  const bool shot_given = cmd.count("--shot") > 0;
  if (shot_given && !o.agreement) {  // before the checkpoint is read
    throw std::runtime_error(
        "--shot aims the scripted offense's shots; with --checkpoint the offense plays only with "
        "--agreement: add --agreement, or leave out --shot");
  }
  ExperimentConfig c = parse_experiment_config(read_checkpoint_config(o.checkpoint), o.checkpoint + " (config)", {});
  const int trained_width = observation_size(c.env);
  const std::string trained_env = c.env.name;
  const bool trained_embedded = gives_embedded_features(c.env);
  if (!o.env.empty() && o.env != c.env.name) {
    c.env.name = o.env;
    const auto& use_embedded = env_registry().find(o.env).use_embedded_hfo_features;
    if (trained_embedded && !gives_embedded_features(c.env) && use_embedded) {
      const std::string changed = use_embedded(c.env.params);
      std::fprintf(stderr,
                   "eval: %s was trained on the embedded simulator's features; env '%s' gives them to it (%s)\n",
                   o.checkpoint.c_str(), o.env.c_str(), changed.c_str());
    }
  }
  c = with_env_overrides(c, o.sets);
  apply_given_sim_options(cmd, o.sim, c.env);
  if (o.sim.config.goalie && !c.env.params.boolean("goalie")) {
    throw std::runtime_error("--goalie: " + o.checkpoint +
                             " was trained without a goalie (env.goalie = false, 58 features); a checkpoint is "
                             "evaluated on its own env");
  }
  auto env = make_env(c.env);
  if (env->observation_size() != trained_width) {
    const auto& use_embedded = env_registry().find(c.env.name).use_embedded_hfo_features;
    EnvParams embedded = c.env.params;
    throw std::runtime_error(
        "--env " + c.env.name + ": " + o.checkpoint + " reads " + std::to_string(trained_width) +
        " features (trained on env '" + trained_env + "'), env '" + c.env.name + "' gives " +
        std::to_string(env->observation_size()) +
        (use_embedded ? " (" + use_embedded(embedded) + " gives the embedded width)" : std::string()));
  }
  const std::unique_ptr<Algorithm> algorithm =
      make_learner(c, env->observation_size(), env->action_space(), c.seed, UpdateDevice::kCpu);
  load_checkpoint(o.checkpoint, *algorithm);
  const bool actor_given = cmd.count("--actor") > 0;
  if (actor_given && o.actor == ActorCopy::kAverage && algorithm->evaluated_copy() != ActorCopy::kAverage) {
    throw std::runtime_error("--actor average: " + o.checkpoint +
                             " keeps no actor average (its run had ddpg.actor_average_tau = 0); use --actor online "
                             "or target");
  }
  // By default the copy its run's evaluations judged (and best.ckpt was chosen by).
  const ActorCopy copy = actor_given ? o.actor : algorithm->evaluated_copy();
  if (!actor_given && copy == ActorCopy::kAverage) {
    std::fprintf(stderr,
                 "eval: %s plays its actor average (ddpg.actor_average_tau = %g; --actor online for the other)\n",
                 o.checkpoint.c_str(), c.ddpg.actor_average_tau);
  }
  GreedyActorPolicy policy(*algorithm, env->action_space(), resolve_exploration(c, env->action_space()), copy);
  if (o.agreement && env->agents() > 1) {
    throw std::runtime_error("--agreement compares one striker with the scripted offense; " + o.checkpoint +
                             " plays a team (env.offense_agents = " + std::to_string(env->agents()) +
                             "): leave out --agreement");
  }
  if (o.agreement) {
    if (!gives_embedded_features(c.env)) {
      throw std::runtime_error("--agreement: the scripted offense plays and reads the embedded simulator's features; " +
                               o.checkpoint + " plays env '" + c.env.name +
                               "' (use a checkpoint trained on hfo, or leave out --agreement)");
    }
    hfo::ScriptedOffense offense(shot_given ? o.shot : c.demo_shot,
                                 hfo::shoot_action(c.env.params));  // by default the teacher it learned from
    PolicyAgreement tally(env->action_space());
    Shadowed shadowed(offense, policy, tally);
    print_result("scripted", evaluate_with_progress(std::move(env), shadowed, o), o.json, &tally, o.checkpoint);
    return;
  }
  print_result(std::string(algorithm->name()), evaluate_with_progress(std::move(env), policy, o), o.json);
}

// --offense-agents N: N players in one embedded game (env.offense_agents = N), the scripted team
// player or the paper's random draw in every slot. The row is the team's: its scoring rate and
// steps to goal; the return is the mean of the players' returns.
void run_team_eval(const EvalOptions& o, const CLI::App& cmd) {
  if (!o.checkpoint.empty()) {
    throw std::runtime_error(
        "--offense-agents: a checkpoint plays the team it was trained in (env.offense_agents in "
        "its config); leave out --offense-agents");
  }
  if (!o.trace.empty() || o.agreement || cmd.count("--shot") > 0 || cmd.count("--actor") > 0) {
    throw std::runtime_error(
        "--offense-agents plays a team of scripted or random players; --trace, --agreement, --shot and --actor are "
        "for one agent: leave them out, or leave out --offense-agents");
  }
  const bool server = o.env == "hfo-server";
  if (!o.env.empty() && o.env != "hfo" && !server) {
    throw std::runtime_error(
        "--offense-agents plays a team of HFO: --env hfo (the embedded simulator) or --env "
        "hfo-server (all N agents of one real server, env.server_agents = N)");
  }
  ExperimentConfig c;
  c.env.name = server ? "hfo-server" : "hfo";
  hfo::SoccerSimConfig cfg = o.sim.resolved();
  cfg.offense_agents = o.offense_agents;
  hfo::set_sim_config(c.env.params, cfg);
  if (server) {
    // One process plays every agent of the server, each reading the embedded features.
    refuse_unread_sim_options(cmd, c.env.name);
    c.env.params.set("server_agents", int64_t{o.offense_agents});
    (void)env_registry().find(c.env.name).use_embedded_hfo_features(c.env.params);
  }
  c = with_env_overrides(c, o.sets);
  if (c.env.params.integer("offense_agents") != o.offense_agents) {
    throw std::runtime_error("--set env.offense_agents and --offense-agents disagree: give one of them");
  }
  auto env = make_env(c.env);
  const int n = env->agents();
  std::vector<std::unique_ptr<Policy>> players;
  std::vector<Policy*> slots;
  for (int i = 0; i < n; ++i) {
    if (o.policy == "scripted") {
      players.push_back(std::make_unique<hfo::ScriptedTeamPlayer>(n - 1, hfo::defense_players(c.env.params),
                                                                  hfo::shoot_action(c.env.params)));
    } else {
      auto random = std::make_unique<RandomPolicy>(env->action_space(), (o.seed ^ 0x5eedULL) + static_cast<uint64_t>(i),
                                                   std::vector<int>{hfo::kDash, hfo::kTurn, hfo::kKick});
      random->set_param_range(hfo::param::kDashPower, -100.0F, 100.0F);
      players.push_back(std::move(random));
    }
    slots.push_back(players.back().get());
  }
  print_result(o.policy + " team of " + std::to_string(n), evaluate_with_progress(std::move(env), slots, o), o.json);
}

void run_eval(const EvalOptions& o, const CLI::App& cmd) {
  if (o.offense_agents > 1) {
    run_team_eval(o, cmd);
    return;
  }
  if (!o.checkpoint.empty()) {
    run_checkpoint_eval(o, cmd);
    return;
  }
  if (o.agreement) {
    throw std::runtime_error(
        "--agreement compares a checkpoint's greedy actor with the scripted offense: give "
        "--checkpoint FILE too");
  }
  if (cmd.count("--actor") > 0) {
    throw std::runtime_error("--actor picks a network of a checkpoint: give --checkpoint FILE too");
  }
  ExperimentConfig c;
  c.env.name = o.env.empty() ? "hfo" : o.env;
  hfo::set_sim_config(c.env.params, o.sim.resolved());
  const EnvRegistration& registration = env_registry().find(c.env.name);
  refuse_unread_sim_options(cmd, c.env.name);
  if (o.policy == "scripted" && registration.use_embedded_hfo_features) {
    (void)registration.use_embedded_hfo_features(c.env.params);  // the scripted offense reads the embedded features
  }
  c = with_env_overrides(c, o.sets);
  const bool hfo_actions = env_registry().find(c.env.name).hfo_actions;
  if (!hfo_actions && o.policy == "scripted") {
    throw std::runtime_error("--policy scripted plays HFO; env '" + c.env.name +
                             "' takes --checkpoint FILE, or --policy random (uniform over its actions and parameters)");
  }
  if (o.policy == "scripted" && !gives_embedded_features(c.env)) {
    const auto& use_embedded = env_registry().find(c.env.name).use_embedded_hfo_features;
    EnvParams embedded = c.env.params;
    throw std::runtime_error("--policy scripted reads the embedded encoding" +
                             (use_embedded ? ": leave " + use_embedded(embedded) : std::string()));
  }
  const bool shot_given = cmd.count("--shot") > 0;
  if (shot_given && o.policy != "scripted") {
    throw std::runtime_error("--shot aims the scripted offense's shots: use it with --policy scripted");
  }
  if (shot_given && !c.env.params.boolean("goalie")) {
    throw std::runtime_error(
        "--shot aims the scripted offense's shots past a goalie; on the empty goal it shoots at the centre: add "
        "--goalie, or leave out --shot");
  }
  auto env = make_env(c.env);
  std::unique_ptr<Policy> policy;
  const int teammates =
      c.env.params.contains("offense_agents") ? static_cast<int>(c.env.params.integer("offense_agents")) - 1 : 0;
  if (o.policy == "scripted" && teammates > 0) {
    // One player of a team (env.offense_agents on the real server): the scripted team player.
    if (shot_given) {
      throw std::runtime_error(
          "--shot aims the single striker's shots; a team player (env.offense_agents > 1) "
          "plays the close-in offense: leave out --shot");
    }
    policy = std::make_unique<hfo::ScriptedTeamPlayer>(teammates, hfo::defense_players(c.env.params),
                                                       hfo::shoot_action(c.env.params));
  } else if (o.policy == "scripted") {
    policy = std::make_unique<hfo::ScriptedOffense>(o.shot, hfo::shoot_action(c.env.params));
  } else if (hfo_actions) {
    // The paper's exploration draw: Tackle masked, dash power U[-100, 100] (reference §7.3).
    auto random = std::make_unique<RandomPolicy>(env->action_space(), o.seed ^ 0x5eedULL,
                                                 std::vector<int>{hfo::kDash, hfo::kTurn, hfo::kKick});
    random->set_param_range(hfo::param::kDashPower, -100.0F, 100.0F);
    policy = std::move(random);
  } else {
    // Any other env: every action, each parameter uniform over its range.
    policy = std::make_unique<RandomPolicy>(env->action_space(), o.seed ^ 0x5eedULL);
  }
  print_result(o.policy, evaluate_with_progress(std::move(env), *policy, o), o.json);
}

}  // namespace

void register_eval(CLI::App& app) {
  auto opts = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand("eval", "play N episodes with a policy and print the paper's table row");
  cmd->footer(env_help_footer());
  cmd->add_option("--policy", opts->policy, "scripted (hand-coded offense) or random")
      ->check(CLI::IsMember({"scripted", "random"}))
      ->capture_default_str();
  cmd->add_option("--episodes", opts->episodes, "number of episodes (the paper used 100)")
      ->check(CLI::Range(1, 100000000))
      ->capture_default_str();
  cmd->add_option("--seed", opts->seed, "random seed of the evaluation")->capture_default_str();
  cmd->add_flag("--json", opts->json, "print one JSON object as the last line");
  cmd->add_option("--checkpoint", opts->checkpoint,
                  "evaluate the greedy actor of a checkpoint written by pamdp train (its env settings are used, but "
                  "for those a simulator flag given here changes, e.g. --start hfo)")
      ->check(existing_file("give a checkpoint: models/*.ckpt (trained agents) or RUN_DIR/checkpoint.ckpt or "
                            "RUN_DIR/best.ckpt of a pamdp train run"));
  cmd->add_option("--env", opts->env,
                  "play on this env instead: " + env_registry().names_joined() +
                      " (--policy scripted plays envs with HFO's actions; others take --checkpoint or --policy "
                      "random); a checkpoint trained on "
                      "the embedded simulator gets the embedded features where the env can give them")
      ->check(CLI::IsMember(env_registry().names()));
  cmd->add_option("--set", opts->sets,
                  "override an env setting, e.g. --set env.server_port=7000 (repeatable; env.* keys of the config)");
  cmd->add_option("--offense-agents", opts->offense_agents,
                  "N learned-agent slots in one embedded game (HFO's --offense-agents), each played by the "
                  "scripted team player (--policy scripted: chase, support, dribble, pass, shoot) or the random "
                  "draw; the row is the team's")
      ->check(CLI::Range(1, hfo::kMaxOffenseAgents))
      ->capture_default_str();
  const std::map<std::string, ActorCopy> actors{
      {"online", ActorCopy::kOnline}, {"target", ActorCopy::kTarget}, {"average", ActorCopy::kAverage}};
  cmd->add_option("--actor", opts->actor,
                  "with --checkpoint: play the online actor, the target actor (the critic targets' soft-updated "
                  "copy) or the actor average (ddpg.actor_average_tau > 0); default: the one its run's "
                  "evaluations played (the average when it kept one)")
      ->transform(CLI::CheckedTransformer(actors, CLI::ignore_case));
  cmd->add_option("--trace", opts->trace,
                  "write every step to this CSV file: episode, step, action, its parameters, reward, status and "
                  "the observation the policy read");
  cmd->add_flag("--agreement", opts->agreement,
                "with --checkpoint: the scripted offense plays, and the checkpoint's greedy actor is asked in "
                "every state; prints how often it picks the offense's action and how far its parameters are "
                "(how well a cloned actor imitates its teacher)");
  const std::map<std::string, hfo::ShotAim> shots(shot_aim_choices().begin(), shot_aim_choices().end());
  cmd->add_option("--shot", opts->shot,
                  "the scripted offense's shot against a goalie: best-course (the best of nine courses), "
                  "bottom-post (always inside the bottom post) or bottom-side (inside the bottom post, dribbling "
                  "toward that side and waiting longer for the shot from far out), close-in (dribbling slowly to "
                  "within 8 m, then the best course: the one for agent2d's goalie) or close-in-post (the same, "
                  "shooting inside the bottom post); default best-course, and with "
                  "--agreement the checkpoint's exploration.demo_shot")
      ->transform(CLI::CheckedTransformer(shots, CLI::ignore_case));
  opts->sim.add_to(*cmd);
  cmd->callback([opts, cmd] { run_eval(*opts, *cmd); });
}

}  // namespace pamdp::app
