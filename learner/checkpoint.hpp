// Checkpoints of a learner: its algorithm's name and state as named tensors and counters
// (learner/algorithm.hpp; for DDPG the actor, critic, both targets, both Adam states and the
// actor's evaluation average), the run's counters, RNG streams and the resolved config, in one
// FlatBuffers file (schemas/checkpoint.fbs, version 2), written atomically (temp file + fsync +
// rename) so a crash never leaves a torn checkpoint. Version 1 files (DDPG, written before the
// algorithm seam) still load: their fields are read under the names DDPG's state uses.
// The file ends with an FNV-1a checksum of the buffer (a trailer; files without one still load).
// Loading checks the checksum, verifies the buffer and every size before touching the learner; a
// corrupt, truncated or mismatched file is refused with a message naming the file and the problem.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "learner/algorithm.hpp"

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

// Brings the algorithm's state to the host (Algorithm::sync_to_host) and writes it.
void save_checkpoint(const std::string& path, Algorithm& algorithm, const CheckpointMeta& meta);
// Restores `algorithm` (which must be the file's and have been built with the same shapes) and
// returns the metadata.
CheckpointMeta load_checkpoint(const std::string& path, Algorithm& algorithm);
// Warm start (train.init_from): the networks of another run's checkpoint of the same algorithm
// (its state tensors with widths, optional ones aside: for DDPG actor, critic and both targets)
// for a run whose observations extend that run's: the same first features, possibly more after
// them (1v0's 58 continued in 1v1's 66, where the goalie's 8 follow). Every network reads the
// state first, so the extra inputs go after the first `obs` inputs of its first layer. Hidden and
// action widths must match. The extra inputs start with zero weights, so the warm-started
// networks compute what the checkpoint's did (up to float summation order), whatever the extra
// features hold. Optimizer state, counters and random streams stay this run's own. Refused with
// the reason if the shapes differ.
void warm_start_from_checkpoint(const std::string& path, Algorithm& algorithm);
// Reads only the config stored in a checkpoint (to rebuild the learner before loading).
std::string read_checkpoint_config(const std::string& path);
// The algorithm that wrote a checkpoint ("ddpg" for version 1 files).
std::string read_checkpoint_algorithm(const std::string& path);

}  // namespace pamdp
