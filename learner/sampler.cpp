#include "learner/sampler.hpp"

#include <algorithm>

namespace pamdp {

std::optional<UpdateStats> update_from(Sampler& sampler, Algorithm& algorithm) {
  const Sample* s = sampler.next();
  if (s == nullptr) {
    return std::nullopt;
  }
  return algorithm.update(*s->batch, s->demos ? &*s->demos : nullptr);
}

BatchView view_of(const BatchBuffers& b, int batch_size) {
  const Eigen::Index B = batch_size;
  return {
      Eigen::Map<const Eigen::MatrixXf>(b.states.data(), b.obs_dim, B),
      Eigen::Map<const Eigen::MatrixXf>(b.actions.data(), b.action_dim, B),
      Eigen::Map<const Eigen::VectorXf>(b.rewards.data(), B),
      Eigen::Map<const Eigen::MatrixXf>(b.next_states.data(), b.obs_dim, B),
      Eigen::Map<const Eigen::VectorXf>(b.terminal.data(), B),
      Eigen::Map<const Eigen::VectorXf>(b.mc_returns.data(), B),
  };
}

LocalSampler::LocalSampler(const ReplayBuffer& replay, const ReplayBuffer* demos, Rng& rng, int batch_size,
                           int64_t warmup)
    : replay_(replay),
      demos_(demos),
      rng_(rng),
      batch_size_(batch_size),
      // An empty table has nothing to draw, whatever the configured warm-up.
      warmup_(std::max<int64_t>(1, warmup)),
      batch_(replay.obs_dim(), replay.action_dim(), batch_size),
      demo_batch_(replay.obs_dim(), replay.action_dim(), demos != nullptr ? batch_size : 0) {
  // The views never move: they map the buffers above, which sampling refills in place.
  sample_.batch.emplace(view_of(batch_, batch_size_));
}

const Sample* LocalSampler::next() {
  if (replay_.size() < warmup_) {
    return nullptr;
  }
  replay_.sample(rng_, batch_size_, batch_);
  sample_.demos.reset();
  if (demos_ != nullptr && demos_->size() > 0) {
    demos_->sample(rng_, batch_size_, demo_batch_);
    sample_.demos.emplace(view_of(demo_batch_, batch_size_));
  }
  return &sample_;
}

}  // namespace pamdp
