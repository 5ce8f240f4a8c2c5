// A replay shard's snapshot file (`pamdp replay --snapshot`, a resumed train's replay.bin) as
// load_replay_snapshot reads it into a buffer of the toy task's shape (capacity 64, widths 3/4,
// the shape fuzz_seeds writes). Refusals are exceptions naming the problem; anything else is a
// finding. Inputs go through a per-process file in /dev/shm (or /tmp): the loader reads files.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/files.hpp"
#include "fuzz/scratch_file.hpp"
#include "replay/replay_snapshot.hpp"

namespace {

void load(const std::string& path, const uint8_t* data, size_t size, pamdp::ReplayBuffer& buffer) {
  if (FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  } else {
    return;
  }
  try {
    pamdp::load_replay_snapshot(path, buffer);
  } catch (const std::runtime_error&) {
  }
}

}  // namespace

// Each input twice: as it is, and with its last 8 bytes replaced by the right checksum, so that
// mutations of the header and rows reach the checks after the checksum (a forged or buggy file).
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const pamdp::fuzz::ScratchFile scratch("snapshot", ".replay");
  const std::string& path = scratch.path;
  static pamdp::ReplayBuffer buffer(64, 3, 4);
  load(path, data, size, buffer);
  if (size >= sizeof(uint64_t)) {
    std::vector<uint8_t> fixed(data, data + size);
    const uint64_t sum = pamdp::fnv1a64(fixed.data(), size - sizeof(uint64_t));
    std::memcpy(fixed.data() + size - sizeof(uint64_t), &sum, sizeof(sum));
    load(path, fixed.data(), fixed.size(), buffer);
  }
  return 0;
}
