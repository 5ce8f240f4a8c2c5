#include "envs/hfo_server/lockstep_team.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace pamdp::hfo_server {
namespace {

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "LockstepTeamEnv: %s\n", what);
  std::abort();
}

}  // namespace

LockstepTeamEnv::LockstepTeamEnv(std::vector<std::unique_ptr<Env>> players, bool team_reward)
    : players_(std::move(players)), team_reward_(team_reward) {
  if (players_.empty()) {
    throw std::invalid_argument("LockstepTeamEnv: a team needs at least one player");
  }
  const Env& first = *players_.front();
  for (const auto& p : players_) {
    if (p == nullptr || p->agents() != 1) {
      throw std::invalid_argument("LockstepTeamEnv: every player must be a one-player env");
    }
    const bool same = p->observation_size() == first.observation_size() &&
                      p->action_space().num_actions() == first.action_space().num_actions() &&
                      p->action_space().num_params() == first.action_space().num_params() &&
                      std::ranges::equal(p->outcomes(), first.outcomes());
    if (!same) {
      throw std::invalid_argument("LockstepTeamEnv: the players' envs differ in observations, actions or outcomes");
    }
  }
  const size_t n = players_.size();
  width_ = static_cast<size_t>(first.observation_size());
  results_.resize(n);
  errors_.resize(n);
  threads_.reserve(n - 1);
  for (size_t i = 1; i < n; ++i) {
    threads_.emplace_back([this, i] { worker(static_cast<int>(i)); });
  }
}

LockstepTeamEnv::~LockstepTeamEnv() {
  // Every player leaves at once: one that says goodbye to a synchronous server may wait for the
  // others' last commands.
  try {
    run(Job::kDestroy);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "LockstepTeamEnv: a player failed while leaving its game: %s\n", e.what());
  }
  {
    const std::lock_guard lock(mutex_);
    job_ = Job::kQuit;
    ++generation_;
  }
  start_.notify_all();
  for (std::thread& t : threads_) {
    t.join();
  }
}

void LockstepTeamEnv::worker(int player) {
  uint64_t seen = 0;
  for (;;) {
    std::unique_lock lock(mutex_);
    start_.wait(lock, [&] { return generation_ != seen; });
    seen = generation_;
    if (job_ == Job::kQuit) {
      return;
    }
    lock.unlock();
    play(player);
    lock.lock();
    if (--pending_ == 0) {
      done_.notify_one();
    }
  }
}

void LockstepTeamEnv::play(int player) {
  const auto i = static_cast<size_t>(player);
  const size_t width = width_;  // not players_[0]'s: a kDestroy may have destroyed it already
  try {
    switch (job_) {
      case Job::kReset: players_[i]->reset(obs_.subspan(i * width, width)); break;
      case Job::kResetSeeded: players_[i]->reset(seed_ + i, obs_.subspan(i * width, width)); break;
      case Job::kStep: results_[i] = players_[i]->step(actions_[i], obs_.subspan(i * width, width)); break;
      case Job::kDestroy: players_[i].reset(); break;
      case Job::kNone:
      case Job::kQuit: break;
    }
  } catch (...) {
    errors_[i] = std::current_exception();
  }
}

void LockstepTeamEnv::run(Job job) {
  {
    const std::lock_guard lock(mutex_);
    job_ = job;
    pending_ = static_cast<int>(threads_.size());
    std::ranges::fill(errors_, nullptr);
    ++generation_;
  }
  start_.notify_all();
  play(0);
  {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return pending_ == 0; });
  }
  for (const std::exception_ptr& e : errors_) {
    if (e != nullptr) {
      std::rethrow_exception(e);
    }
  }
}

void LockstepTeamEnv::reset(uint64_t seed, std::span<float> obs) {
  seed_ = seed;
  obs_ = obs;
  run(Job::kResetSeeded);
}

void LockstepTeamEnv::reset(std::span<float> obs) {
  obs_ = obs;
  run(Job::kReset);
}

StepResult LockstepTeamEnv::step(const ParamAction& action, std::span<float> obs) {
  if (agents() != 1) {
    misuse("step() with one action on a team of several; use step_team()");
  }
  float reward = 0.0F;
  return step_team({&action, 1}, obs, {&reward, 1});
}

StepResult LockstepTeamEnv::step_team(std::span<const ParamAction> actions, std::span<float> obs,
                                      std::span<float> rewards) {
  if (static_cast<int>(actions.size()) != agents() || static_cast<int>(rewards.size()) != agents()) {
    misuse("step_team() takes one action and one reward slot per player");
  }
  actions_ = actions;
  obs_ = obs;
  run(Job::kStep);
  const int status = results_.front().status;
  float sum = 0.0F;
  for (size_t i = 0; i < results_.size(); ++i) {
    if (results_[i].status != status) {
      throw std::runtime_error(
          "the players of one team disagree on the episode's status (player 0: " + std::string(status_name(status)) +
          ", player " + std::to_string(i) + ": " + std::string(status_name(results_[i].status)) +
          "): they are not playing one game; start them on one server");
    }
    rewards[i] = results_[i].reward;
    sum += rewards[i];
  }
  const float mean = sum / static_cast<float>(results_.size());
  if (team_reward_) {
    std::ranges::fill(rewards, mean);
  }
  return {mean, status};
}

void LockstepTeamEnv::set_training_updates(int64_t updates) {
  for (const auto& p : players_) {
    p->set_training_updates(updates);
  }
}

std::span<const EnvCounter> LockstepTeamEnv::counters() const {
  counters_.clear();
  for (const auto& p : players_) {
    for (const EnvCounter& c : p->counters()) {
      const auto it = std::ranges::find(counters_, c.name, &EnvCounter::name);
      if (it == counters_.end()) {
        counters_.push_back(c);
      } else {
        it->value += c.value;
      }
    }
  }
  return counters_;
}

}  // namespace pamdp::hfo_server
