// A file of this fuzzer process's own (in /dev/shm when there is one), removed when the
// process exits: for loaders that read from a path.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace pamdp::fuzz {

struct ScratchFile {
  std::string path;
  ScratchFile(const std::string& name, const std::string& extension) {
    const char* dir = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
    path = std::string(dir) + "/pamdp-fuzz-" + name + "-" + std::to_string(getpid()) + extension;
  }
  ~ScratchFile() { std::remove(path.c_str()); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
};

}  // namespace pamdp::fuzz
