// Snapshot of a ReplayBuffer's contents on disk, so that a resumed run samples from exactly
// the memory it had (bit-for-bit resume) and a restarted shard keeps what it had accepted.
// Format: a fixed header (magic "PRPL", version, capacity, widths, counters), the stored rows,
// then an FNV-1a checksum of everything before it. Written atomically.
#pragma once

#include <string>

#include "replay/replay_buffer.hpp"

namespace pamdp {

void save_replay_snapshot(const std::string& path, const ReplayBuffer& buffer);
// Restores into `buffer`, which must have the same capacity and widths. Throws
// std::runtime_error naming the file and the problem (missing, truncated, corrupt, mismatch).
void load_replay_snapshot(const std::string& path, ReplayBuffer& buffer);

}  // namespace pamdp
