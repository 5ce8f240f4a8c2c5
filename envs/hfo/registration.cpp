#include <algorithm>
#include <memory>
#include <stdexcept>

#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/settings.hpp"
#include "envs/registry.hpp"

namespace pamdp {
namespace hfo {
namespace {

template <typename E>
std::vector<std::string> names_of(const Names<E>& names) {
  std::vector<std::string> out;
  for (const auto& [name, value] : names) {
    out.push_back(name);
  }
  return out;
}

template <typename E>
E value_of(const Names<E>& names, const std::string& name) {
  for (const auto& [n, value] : names) {
    if (n == name) {
      return value;
    }
  }
  throw std::logic_error("env setting value '" + name + "' is not a valid choice");  // the config reader checks first
}

template <typename E>
std::string name_of(const Names<E>& names, E value) {
  for (const auto& [name, v] : names) {
    if (v == value) {
      return name;
    }
  }
  throw std::logic_error("an hfo setting has a value without a name");
}

}  // namespace

const Names<StartDistribution>& start_names() {
  static const Names<StartDistribution> kNames{
      {"paper", StartDistribution::kPaper}, {"dec2015", StartDistribution::kDec2015}, {"hfo", StartDistribution::kHfo}};
  return kNames;
}

const Names<Referee>& referee_names() {
  static const Names<Referee> kNames{{"server", Referee::kServer}, {"trainer", Referee::kTrainer}};
  return kNames;
}

const Names<BodyAtReset>& body_at_reset_names() {
  static const Names<BodyAtReset> kNames{
      {"carry", BodyAtReset::kCarry}, {"zero", BodyAtReset::kZero}, {"uniform", BodyAtReset::kUniform}};
  return kNames;
}

EnvKey goalie_key() {
  return EnvKey::boolean("goalie", SoccerSimConfig{}.goalie);
}

EnvKey defense_npcs_key() {
  return EnvKey::integer("defense_npcs", 0, 0, 1 + kMaxFieldDefenders);
}

int defense_players(const EnvParams& params) {
  const int goalie = params.contains("goalie") && params.boolean("goalie") ? 1 : 0;
  const int npcs = params.contains("defense_npcs") ? static_cast<int>(params.integer("defense_npcs")) : 0;
  return std::max(goalie, npcs);
}

EnvKey shoot_action_key() {
  return EnvKey::boolean("shoot_action", false);
}

bool shoot_action(const EnvParams& params) {
  return params.contains("shoot_action") && params.boolean("shoot_action");
}

EnvKey offense_agents_key() {
  return EnvKey::integer("offense_agents", SoccerSimConfig{}.offense_agents, 1, kMaxOffenseAgents);
}

EnvKey max_steps_key() {
  return EnvKey::integer("max_steps", SoccerSimConfig{}.max_steps, 1, 1000000);
}

std::vector<EnvKey> sim_keys() {
  const SoccerSimConfig d;
  return {
      EnvKey::boolean("noise", d.noise),
      EnvKey::choice("start", name_of(start_names(), d.start), names_of(start_names())),
      EnvKey::choice("referee", name_of(referee_names(), d.referee), names_of(referee_names())),
      EnvKey::choice("body_at_reset", name_of(body_at_reset_names(), d.body_at_reset), names_of(body_at_reset_names())),
      max_steps_key(),
      EnvKey::integer("untouched_limit", d.untouched_limit, 1, 1000000),
      goalie_key(),
      offense_agents_key(),
      defense_npcs_key()};
}

SoccerSimConfig sim_config(const EnvParams& params) {
  SoccerSimConfig c;
  c.noise = params.boolean("noise");
  c.start = value_of(start_names(), params.text("start"));
  c.referee = value_of(referee_names(), params.text("referee"));
  c.body_at_reset = value_of(body_at_reset_names(), params.text("body_at_reset"));
  c.max_steps = static_cast<int>(params.integer("max_steps"));
  c.untouched_limit = static_cast<int>(params.integer("untouched_limit"));
  c.goalie = params.boolean("goalie");
  const int64_t defense_npcs = params.contains("defense_npcs") ? params.integer("defense_npcs") : 0;
  c.goalie = c.goalie || defense_npcs >= 1;
  c.field_defenders = static_cast<int>(std::max<int64_t>(0, defense_npcs - 1));
  c.offense_agents = static_cast<int>(params.integer("offense_agents"));
  return c;
}

void set_sim_config(EnvParams& params, const SoccerSimConfig& config) {
  params.set("noise", config.noise);
  params.set("start", name_of(start_names(), config.start));
  params.set("referee", name_of(referee_names(), config.referee));
  params.set("body_at_reset", name_of(body_at_reset_names(), config.body_at_reset));
  params.set("max_steps", int64_t{config.max_steps});
  params.set("untouched_limit", int64_t{config.untouched_limit});
  params.set("goalie", config.goalie);
  params.set("defense_npcs", int64_t{config.field_defenders > 0 ? 1 + config.field_defenders : 0});
  params.set("offense_agents", int64_t{config.offense_agents});
}

}  // namespace hfo

void register_hfo_env(EnvRegistry& registry) {
  EnvRegistration r;
  r.name = "hfo";
  r.description =
      "embedded Half Field Offense simulator (58 features; 66 with env.goalie = true; 8 more per teammate with "
      "env.offense_agents = N, a team of N learned players, and per field defender with env.defense_npcs = K)";
  r.keys = hfo::sim_keys();
  r.keys.push_back(hfo::shoot_action_key());
  // Subtracted from the reward when the ball goes out of bounds (hfo::ShapedReward); 0 keeps
  // dqn-hfo's reward. In the reward's units: a goal is 5.
  r.keys.push_back(EnvKey::integer("out_of_bounds_penalty", 0, 0, 100));
  // With env.offense_agents > 1: every player earns the team's mean shaped reward, not its own.
  r.keys.push_back(EnvKey::boolean("team_reward", false));
  // The start curriculum (hfo::SoccerSimConfig::start_curriculum_*): over this many learner
  // updates the starts move out from start_curriculum_percent of their distance to the goal to
  // the whole of it. 0 = off. Training only: evaluations play the full starts.
  r.keys.push_back(EnvKey::integer("start_curriculum_updates", 0, 0, int64_t{1} << 40));
  r.keys.push_back(EnvKey::integer("start_curriculum_percent", 25, 1, 100));
  r.make = [](const EnvParams& p) -> std::unique_ptr<Env> {
    hfo::SoccerSimConfig c = hfo::sim_config(p);
    c.start_curriculum_updates = p.integer("start_curriculum_updates");
    c.start_curriculum_from = static_cast<double>(p.integer("start_curriculum_percent")) / 100.0;
    const int penalty = static_cast<int>(p.integer("out_of_bounds_penalty"));
    if (c.offense_agents > 1) {
      return std::make_unique<hfo::HfoTeamEnv>(c, p.boolean("shoot_action"), penalty, p.boolean("team_reward"));
    }
    return std::make_unique<hfo::HfoEnv>(c, p.boolean("shoot_action"), penalty);
  };
  r.observation_size = [](const EnvParams& p) { return hfo::HfoTeamEnv(hfo::sim_config(p)).observation_size(); };
  r.gives_embedded_hfo_features = [](const EnvParams&) { return true; };
  r.hfo_actions = true;
  r.action_gates = {{"KICK", hfo::feat::kKickable}};  // the client sends no kick without it
  registry.add(std::move(r));
}

}  // namespace pamdp
