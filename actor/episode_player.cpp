#include "actor/episode_player.hpp"

#include <stdexcept>
#include <utility>

namespace pamdp {

EpisodePlayer::EpisodePlayer(Env& env, Policy* teacher, bool labels)
    : env_(env),
      teacher_(teacher),
      space_(env.action_space()),
      episode_(env.max_episode_steps(), env.observation_size(), space_.output_width()),
      obs_(static_cast<size_t>(env.observation_size())),
      next_obs_(obs_.size()),
      net_out_(static_cast<size_t>(space_.output_width())),
      stored_(net_out_.size()) {
  if (labels) {
    if (teacher == nullptr) {
      throw std::invalid_argument("EpisodePlayer: labels need a teacher");
    }
    labels_.emplace(env.max_episode_steps(), env.observation_size(), space_.output_width());
    label_out_.resize(net_out_.size());
  }
}

void EpisodePlayer::begin(uint64_t env_seed, double demo_share, Rng& rng) {
  env_.reset(env_seed, obs_);
  episode_.clear();
  return_ = 0.0F;
  steps_ = 0;
  ended_ = false;
  demo_ = demo_share > 0.0 && rng.uniform() < demo_share;
  if (demo_ && teacher_ == nullptr) {
    throw std::logic_error("EpisodePlayer: a demonstration share > 0 without a teacher");
  }
  label_ = labels_.has_value() && !demo_;
  if (label_) {
    labels_->clear();
  }
  if (demo_ || label_) {
    teacher_->begin_episode();
  }
}

StepResult EpisodePlayer::step(const Act& act, EpsilonGreedy& explore, double epsilon) {
  // The network's output is computed only where it is used: by a greedy step, as a random step's
  // parameters (exploration.uniform_random_params off), or as the parameters of the actions a
  // teacher did not take.
  if (act && (demo_ || label_ || explore.uses_output(epsilon))) {
    act(obs_, net_out_);
  }
  const int id = demo_ ? write_teacher_output(space_, teacher_->act(obs_), net_out_, stored_)
                       : explore.select(obs_, net_out_, epsilon, stored_);
  if (label_) {  // before the step: the label is for the state the agent acted in
    write_teacher_output(space_, teacher_->act(obs_), net_out_, label_out_);
  }
  const size_t num_actions = static_cast<size_t>(space_.num_actions());
  const StepResult sr = env_.step({id, std::span<const float>(stored_).subspan(num_actions)}, next_obs_);
  episode_.push(obs_, stored_, sr.reward, next_obs_);
  if (label_) {
    labels_->push(obs_, label_out_, sr.reward, next_obs_);
  }
  return_ += sr.reward;
  ++steps_;
  std::swap(obs_, next_obs_);
  ended_ = sr.terminal() || episode_.size() >= episode_.capacity();
  return sr;
}

}  // namespace pamdp
