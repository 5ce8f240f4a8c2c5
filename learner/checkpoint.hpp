// Checkpoints of a DDPG learner: actor, critic, both targets, both Adam states, the actor's
// evaluation average (with ddpg.actor_average_tau > 0), counters, RNG streams and the resolved
// config, in one FlatBuffers file (schemas/checkpoint.fbs), written atomically (temp file +
// fsync + rename) so a crash never leaves a torn checkpoint.
// The file ends with an FNV-1a checksum of the buffer (a trailer; files without one still load).
// Loading checks the checksum, verifies the buffer and every size before touching the learner; a
// corrupt, truncated or mismatched file is refused with a message naming the file and the problem.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "learner/ddpg.hpp"

namespace pamdp {

struct CheckpointMeta {
  std::string config_toml;
  int64_t env_steps = 0;
  int64_t episodes = 0;
  double elapsed_seconds = 0.0;
  double update_credit = 0.0;   // fractional updates owed (train.updates_per_step < 1)
  int64_t weights_version = 0;  // last policy version published (pamdp learner; 0 in older files)
  std::vector<std::array<uint64_t, 4>> rng_states;
};

void save_checkpoint(const std::string& path, Ddpg& ddpg, const CheckpointMeta& meta);
// Restores `ddpg` (which must have been built with the same shapes) and returns the metadata.
CheckpointMeta load_checkpoint(const std::string& path, Ddpg& ddpg);
// Warm start (train.init_from): the networks of another run's checkpoint -- actor, critic and both
// targets -- for a run whose observations extend that run's: the same first features, possibly
// more after them (1v0's 58 continued in 1v1's 66, where the goalie's 8 follow). Hidden and action
// widths must match. The extra inputs start with zero weights, so the warm-started networks
// compute what the checkpoint's did (up to float summation order), whatever the extra features hold. Optimizer state,
// counters and random streams stay this run's own. Refused with the reason if the shapes differ.
void warm_start_from_checkpoint(const std::string& path, Ddpg& ddpg);
// Reads only the config stored in a checkpoint (to rebuild the learner before loading).
std::string read_checkpoint_config(const std::string& path);

}  // namespace pamdp
