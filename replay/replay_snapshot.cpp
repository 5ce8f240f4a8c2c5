#include "replay/replay_snapshot.hpp"

#include <cstring>
#include <stdexcept>
#include <vector>

#include "core/files.hpp"

namespace pamdp {
namespace {

struct Header {
  char magic[4] = {'P', 'R', 'P', 'L'};
  uint32_t version = 1;
  int64_t capacity = 0;
  int32_t obs_dim = 0;
  int32_t action_dim = 0;
  int64_t size = 0;
  int64_t inserted = 0;
};

}  // namespace

void save_replay_snapshot(const std::string& path, const ReplayBuffer& buffer) {
  Header h;
  h.capacity = buffer.capacity();
  h.obs_dim = buffer.obs_dim();
  h.action_dim = buffer.action_dim();
  h.size = buffer.size();
  h.inserted = buffer.inserted();
  const size_t row = 2 * static_cast<size_t>(h.obs_dim) + static_cast<size_t>(h.action_dim) + 3;
  const size_t payload = static_cast<size_t>(h.size) * row * sizeof(float);
  std::vector<uint8_t> bytes(sizeof(Header) + payload + sizeof(uint64_t));
  std::memcpy(bytes.data(), &h, sizeof(Header));
  std::memcpy(bytes.data() + sizeof(Header), buffer.raw().data(), payload);
  const uint64_t sum = fnv1a64(bytes.data(), sizeof(Header) + payload);
  std::memcpy(bytes.data() + sizeof(Header) + payload, &sum, sizeof(sum));
  write_file_atomically(path, bytes.data(), bytes.size());
}

void load_replay_snapshot(const std::string& path, ReplayBuffer& buffer) {
  const std::vector<uint8_t> bytes = read_file_bytes(path);
  Header h;
  if (bytes.size() < sizeof(Header) + sizeof(uint64_t)) {
    throw std::runtime_error("replay snapshot '" + path + "' is truncated");
  }
  std::memcpy(&h, bytes.data(), sizeof(Header));
  if (std::memcmp(h.magic, "PRPL", 4) != 0 || h.version != 1) {
    throw std::runtime_error("'" + path + "' is not a pamdp replay snapshot (version 1)");
  }
  if (h.capacity != buffer.capacity() || h.obs_dim != buffer.obs_dim() || h.action_dim != buffer.action_dim()) {
    throw std::runtime_error("replay snapshot '" + path + "' was written for capacity " + std::to_string(h.capacity) +
                             " and widths " + std::to_string(h.obs_dim) + "/" + std::to_string(h.action_dim) +
                             "; this run has " + std::to_string(buffer.capacity()) + " and " +
                             std::to_string(buffer.obs_dim()) + "/" + std::to_string(buffer.action_dim()));
  }
  const size_t row = 2 * static_cast<size_t>(h.obs_dim) + static_cast<size_t>(h.action_dim) + 3;
  if (h.size < 0 || h.size > h.capacity || h.inserted < h.size) {
    throw std::runtime_error("replay snapshot '" + path + "' is corrupt (bad size or insert count)");
  }
  const size_t payload = static_cast<size_t>(h.size) * row * sizeof(float);
  if (bytes.size() != sizeof(Header) + payload + sizeof(uint64_t)) {
    throw std::runtime_error("replay snapshot '" + path + "' is truncated or has trailing bytes");
  }
  uint64_t sum = 0;
  std::memcpy(&sum, bytes.data() + sizeof(Header) + payload, sizeof(sum));
  if (sum != fnv1a64(bytes.data(), sizeof(Header) + payload)) {
    throw std::runtime_error("replay snapshot '" + path + "' is corrupt (checksum mismatch)");
  }
  std::memcpy(buffer.raw_mutable().data(), bytes.data() + sizeof(Header), payload);
  buffer.set_counters(h.size, h.inserted);
}

}  // namespace pamdp
