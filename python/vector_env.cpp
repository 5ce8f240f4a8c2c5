#include "python/vector_env.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace pamdp::python {

VectorEnv::VectorEnv(std::vector<std::unique_ptr<Env>> envs, int num_threads, AutoReset mode, int timeout_status,
                     std::function<std::unique_ptr<Env>()> rebuild)
    : envs_(std::move(envs)),
      num_threads_(std::clamp(num_threads, 1, std::max(1, static_cast<int>(envs_.size())))),
      mode_(mode),
      timeout_status_(timeout_status),
      rebuild_(std::move(rebuild)),
      obs_size_(envs_.empty() ? 0 : envs_[0]->observation_size()),
      num_params_(envs_.empty() ? 0 : envs_[0]->action_space().num_params()),
      agents_(envs_.empty() ? 1 : envs_[0]->agents()),
      actions_(envs_.size() * static_cast<size_t>(agents_)),
      needs_reset_(envs_.size(), 1),
      step_job_([this](int begin, int end) { step_slice(begin, end); }) {
  if (envs_.empty()) {
    throw std::invalid_argument("VectorEnv: needs at least one env");
  }
  for (const auto& env : envs_) {
    if (env->agents() != agents_) {
      throw std::invalid_argument("VectorEnv: every env needs the same number of players (" + std::to_string(agents_) +
                                  "), got one of " + std::to_string(env->agents()));
    }
  }
  for (int t = 1; t < num_threads_; ++t) {
    workers_.emplace_back([this, t] { worker(t); });
  }
}

VectorEnv::~VectorEnv() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (std::thread& t : workers_) {
    t.join();
  }
}

void VectorEnv::run(const std::function<void(int, int)>& slice) {
  const int n = num_envs();
  if (num_threads_ == 1) {
    slice(0, n);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &slice;
    running_ = num_threads_ - 1;
    ++generation_;
  }
  start_.notify_all();
  slice(0, n / num_threads_);
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return running_ == 0; });
  job_ = nullptr;
}

void VectorEnv::worker(int index) {
  const int n = num_envs();
  const int begin = static_cast<int>(static_cast<int64_t>(n) * index / num_threads_);
  const int end = static_cast<int>(static_cast<int64_t>(n) * (index + 1) / num_threads_);
  uint64_t seen = 0;
  for (;;) {
    const std::function<void(int, int)>* job = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) {
        return;
      }
      seen = generation_;
      job = job_;
    }
    (*job)(begin, end);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --running_;
    }
    done_.notify_one();
  }
}

void VectorEnv::reset(std::span<const uint64_t> seeds, const VectorBuffers& out) {
  out_ = out;
  if (rebuild_ && !seeds.empty()) {
    for (auto& env : envs_) {
      env = rebuild_();
    }
  }
  const auto agents = static_cast<size_t>(agents_);
  const auto obs = static_cast<size_t>(obs_size_) * agents;
  const std::function<void(int, int)> job = [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const auto k = static_cast<size_t>(i);
      const std::span<float> row = out.obs.subspan(k * obs, obs);
      if (seeds.empty()) {
        envs_[k]->reset(row);
      } else {
        envs_[k]->reset(seeds[k], row);
      }
      needs_reset_[k] = 0;
      std::fill_n(out.reward.begin() + static_cast<std::ptrdiff_t>(k * agents), agents, 0.0F);
      out.terminated[k] = 0;
      out.truncated[k] = 0;
      out.status[k] = 0;
      if (!out.has_final.empty()) {
        out.has_final[k] = 0;
      }
    }
  };
  run(job);
}

void VectorEnv::step(std::span<const int> ids, std::span<const float> params, const VectorBuffers& out) {
  ids_ = ids;
  params_ = params;
  out_ = out;
  run(step_job_);
}

void VectorEnv::step_slice(int begin, int end) {
  const auto agents = static_cast<size_t>(agents_);
  const auto obs = static_cast<size_t>(obs_size_) * agents;
  const auto np = static_cast<size_t>(num_params_);
  for (int i = begin; i < end; ++i) {
    const auto k = static_cast<size_t>(i);
    const std::span<float> row = out_.obs.subspan(k * obs, obs);
    const std::span<float> rewards = out_.reward.subspan(k * agents, agents);
    Env& env = *envs_[k];
    if (needs_reset_[k] != 0) {  // kNextStep: the step after a terminal one starts the next episode
      env.reset(row);
      needs_reset_[k] = 0;
      std::fill(rewards.begin(), rewards.end(), 0.0F);
      out_.terminated[k] = 0;
      out_.truncated[k] = 0;
      out_.status[k] = 0;
      continue;
    }
    // Env::step_team: a team's step, or for one player its step().
    const std::span<ParamAction> actions = std::span(actions_).subspan(k * agents, agents);
    for (size_t a = 0; a < agents; ++a) {
      const size_t j = k * agents + a;
      actions[a] = {ids_[j], params_.subspan(j * np, np)};
    }
    const StepResult r = env.step_team(actions, row, rewards);
    out_.status[k] = r.status;
    const bool timeout = r.status == timeout_status_;
    out_.terminated[k] = r.terminal() && !timeout ? 1 : 0;
    out_.truncated[k] = timeout ? 1 : 0;
    if (mode_ == AutoReset::kSameStep) {
      out_.has_final[k] = r.terminal() ? 1 : 0;
      if (r.terminal()) {
        std::copy(row.begin(), row.end(), out_.final_obs.begin() + static_cast<std::ptrdiff_t>(k * obs));
        env.reset(row);
      }
    } else {
      needs_reset_[k] = r.terminal() ? 1 : 0;
    }
  }
}

}  // namespace pamdp::python
