#include "actor/episode_player.hpp"

#include <stdexcept>
#include <string>
#include <utility>

namespace pamdp {
namespace {

std::vector<Policy*> raw_pointers(std::span<const std::unique_ptr<Policy>> owned) {
  std::vector<Policy*> out;
  out.reserve(owned.size());
  for (const auto& p : owned) {
    out.push_back(p.get());
  }
  return out;
}

}  // namespace

EpisodePlayer::EpisodePlayer(Env& env, Policy* teacher, bool labels)
    : EpisodePlayer(env, teacher == nullptr ? std::span<Policy* const>{} : std::span<Policy* const>(&teacher, 1),
                    labels) {}

EpisodePlayer::EpisodePlayer(Env& env, std::span<const std::unique_ptr<Policy>> teachers, bool labels)
    : EpisodePlayer(env, std::span<Policy* const>(raw_pointers(teachers)), labels) {}

EpisodePlayer::EpisodePlayer(Env& env, std::span<Policy* const> teachers, bool labels)
    : env_(env), teachers_(teachers.begin(), teachers.end()), space_(env.action_space()) {
  const auto n = static_cast<size_t>(env.agents());
  if (n < 1) {
    throw std::invalid_argument("EpisodePlayer: an env with no players");
  }
  if (!teachers_.empty() && teachers_.size() != n) {
    throw std::invalid_argument("EpisodePlayer: " + std::to_string(teachers_.size()) + " teachers for " +
                                std::to_string(n) + " players; give one per player");
  }
  for (size_t i = 0; i < n; ++i) {
    episodes_.emplace_back(env.max_episode_steps(), env.observation_size(), space_.output_width());
  }
  const auto obs = static_cast<size_t>(env.observation_size());
  const auto width = static_cast<size_t>(space_.output_width());
  obs_.resize(n * obs);
  next_obs_.resize(obs_.size());
  net_out_.resize(n * width);
  stored_.resize(net_out_.size());
  actions_.resize(n);
  rewards_.resize(n);
  if (labels) {
    if (teachers_.empty()) {
      throw std::invalid_argument("EpisodePlayer: labels need a teacher");
    }
    for (size_t i = 0; i < n; ++i) {
      labels_.emplace_back(env.max_episode_steps(), env.observation_size(), space_.output_width());
    }
    label_out_.resize(net_out_.size());
  }
}

void EpisodePlayer::begin(uint64_t env_seed, double demo_share, Rng& rng) {
  env_.reset(env_seed, obs_);
  for (EpisodeBuffer& e : episodes_) {
    e.clear();
  }
  return_ = 0.0F;
  steps_ = 0;
  ended_ = false;
  demo_ = demo_share > 0.0 && rng.uniform() < demo_share;
  if (demo_ && teachers_.empty()) {
    throw std::logic_error("EpisodePlayer: a demonstration share > 0 without a teacher");
  }
  label_ = !labels_.empty() && !demo_;
  if (label_) {
    for (EpisodeBuffer& l : labels_) {
      l.clear();
    }
  }
  if (demo_ || label_) {
    for (Policy* t : teachers_) {
      t->begin_episode();
    }
  }
}

StepResult EpisodePlayer::step(const Act& act, EpsilonGreedy& explore, double epsilon) {
  const auto n = episodes_.size();
  const auto obs_dim = obs_.size() / n;
  const auto width = net_out_.size() / n;
  const auto num_actions = static_cast<size_t>(space_.num_actions());
  const std::span<const float> obs_all(obs_);
  const std::span<float> out_all(net_out_);
  const std::span<float> stored_all(stored_);
  for (size_t i = 0; i < n; ++i) {
    const auto obs = obs_all.subspan(i * obs_dim, obs_dim);
    const auto out = out_all.subspan(i * width, width);
    const auto stored = stored_all.subspan(i * width, width);
    // The network's output is computed only where it is used: by a greedy step, as a random
    // step's parameters (exploration.uniform_random_params off), or as the parameters of the
    // actions a teacher did not take.
    if (act && (demo_ || label_ || explore.uses_output(epsilon))) {
      act(obs, out);
    }
    const int id = demo_ ? write_teacher_output(space_, teachers_[i]->act(obs), out, stored)
                         : explore.select(obs, out, epsilon, stored);
    if (label_) {  // before the step: the label is for the state the agent acted in
      write_teacher_output(space_, teachers_[i]->act(obs), out, std::span<float>(label_out_).subspan(i * width, width));
    }
    actions_[i] = {id, std::span<const float>(stored).subspan(num_actions)};
  }
  const StepResult sr = n == 1 ? env_.step(actions_[0], next_obs_) : env_.step_team(actions_, next_obs_, rewards_);
  if (n == 1) {
    rewards_[0] = sr.reward;
  }
  const std::span<const float> next_all(next_obs_);
  for (size_t i = 0; i < n; ++i) {
    const auto obs = obs_all.subspan(i * obs_dim, obs_dim);
    const auto next = next_all.subspan(i * obs_dim, obs_dim);
    episodes_[i].push(obs, stored_all.subspan(i * width, width), rewards_[i], next);
    if (label_) {
      labels_[i].push(obs, std::span<const float>(label_out_).subspan(i * width, width), rewards_[i], next);
    }
  }
  return_ += sr.reward;
  ++steps_;
  std::swap(obs_, next_obs_);
  ended_ = sr.terminal() || episodes_[0].size() >= episodes_[0].capacity();
  return sr;
}

}  // namespace pamdp
