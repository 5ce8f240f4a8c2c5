// A checkpoint file as `--resume` and `pamdp eval --checkpoint` read it: read_checkpoint_config,
// then load_checkpoint into a learner of the toy task's shape. The loader reads files only, so
// each input goes through a per-process file in /dev/shm (or /tmp). Refusals are exceptions
// naming the file and the problem; anything else (a crash, a sanitizer report) is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/files.hpp"
#include "envs/toy/reach_stop.hpp"
#include "fuzz/scratch_file.hpp"
#include "learner/checkpoint.hpp"
#include "learner/ddpg_algorithm.hpp"

namespace {

struct Learner {
  pamdp::toy::ReachStopEnv env;
  std::unique_ptr<pamdp::DdpgAlgorithm> ddpg;
  Learner() {
    pamdp::DdpgConfig config;
    config.hidden = {8, 8};  // fuzz_seeds writes its checkpoints with these widths
    ddpg = std::make_unique<pamdp::DdpgAlgorithm>(env.observation_size(), env.action_space(), config, 1,
                                                  pamdp::UpdateDevice::kCpu);
  }
};

void load(const std::string& path, const uint8_t* data, size_t size, pamdp::Algorithm& ddpg) {
  if (FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  } else {
    return;
  }
  try {
    (void)pamdp::read_checkpoint_config(path);
  } catch (const std::runtime_error&) {
  }
  try {
    (void)pamdp::load_checkpoint(path, ddpg);
  } catch (const std::runtime_error&) {
  }
}

}  // namespace

// Each input twice: as it is, and with its last 12 bytes replaced by a right checksum trailer
// (learner/checkpoint.cpp), so that mutations of the buffer reach the verifier and the loader.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const pamdp::fuzz::ScratchFile scratch("checkpoint", ".ckpt");
  const std::string& path = scratch.path;
  static Learner learner;
  load(path, data, size, *learner.ddpg);
  constexpr size_t kTrailer = sizeof(uint64_t) + 4;
  if (size >= kTrailer) {
    std::vector<uint8_t> fixed(data, data + size);
    const uint64_t sum = pamdp::fnv1a64(fixed.data(), size - kTrailer);
    std::memcpy(fixed.data() + size - kTrailer, &sum, sizeof(sum));
    std::memcpy(fixed.data() + size - 4, "PCK1", 4);
    load(path, fixed.data(), fixed.size(), *learner.ddpg);
  }
  return 0;
}
