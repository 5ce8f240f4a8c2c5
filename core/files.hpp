// Small file helpers shared by every role.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pamdp {

// Writes data to path atomically: path.tmp, fsync, rename. Throws std::runtime_error naming
// the file and the OS error.
void write_file_atomically(const std::string& path, const void* data, size_t size);

// Reads a whole file; throws std::runtime_error naming the file and the OS error.
std::vector<uint8_t> read_file_bytes(const std::string& path);

// FNV-1a 64-bit hash, used as a checksum of snapshot files.
uint64_t fnv1a64(const void* data, size_t size, uint64_t seed = 0xcbf29ce484222325ULL);

}  // namespace pamdp
