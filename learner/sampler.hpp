// Where a run's updates draw their minibatches. One seam over a local table and remote ones, as
// Reverb's one Sampler reads either: `pamdp train` samples its in-process replay buffer
// (LocalSampler); `pamdp learner` samples the replay shards (LearnerServer, which pumps the
// cluster's sockets until a shard's reply is in). A run updates through update_from(), whichever
// it holds.
#pragma once

#include <optional>

#include "core/rng.hpp"
#include "learner/algorithm.hpp"
#include "replay/replay_buffer.hpp"

namespace pamdp {

// One minibatch as an update reads it, and the demonstrations to clone with it when the run
// keeps them. Not owned: valid until the sampler's next call.
struct Sample {
  std::optional<BatchView> batch;  // set in every sample a sampler returns
  std::optional<BatchView> demos;  // empty: no demonstrations to clone with this batch
};

class Sampler {
 public:
  virtual ~Sampler() = default;
  // The next full minibatch; nullptr when there is none now. A local sampler has none while its
  // table is below warm-up; a remote one when it was stopped or reached its limits.
  virtual const Sample* next() = 0;
};

// Draws one minibatch from `sampler` and runs one update of `algorithm` on it (cloning the
// demonstrations the sample carries). nullopt, and no update, when the sampler had none.
std::optional<UpdateStats> update_from(Sampler& sampler, Algorithm& algorithm);

// The in-process replay buffer, and the demonstrations' own table when the learner clones them
// (`demos`, may be null). Draws the batch first, then the demonstrations when their table holds
// any, from one random stream, so a seeded run draws the same batches every time. Allocates
// nothing per sample. The tables and the stream must outlive the sampler.
class LocalSampler final : public Sampler {
 public:
  LocalSampler(const ReplayBuffer& replay, const ReplayBuffer* demos, Rng& rng, int batch_size, int64_t warmup);
  const Sample* next() override;

 private:
  const ReplayBuffer& replay_;
  const ReplayBuffer* demos_;
  Rng& rng_;
  int batch_size_;
  int64_t warmup_;
  BatchBuffers batch_;
  BatchBuffers demo_batch_;
  Sample sample_;
};

// A sampled batch in `b` (its first `batch_size` columns) as an update reads it: no copy.
BatchView view_of(const BatchBuffers& b, int batch_size);

}  // namespace pamdp
