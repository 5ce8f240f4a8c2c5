#include "learner/checkpoint.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>

#include "core/files.hpp"
#include "core/mlp.hpp"
#include "schemas/checkpoint_generated.h"

namespace pamdp {
namespace {

// The FlatBuffers verifier proves a checkpoint safe to read, not unchanged: a flipped byte in the
// parameters still verifies. So the file ends with a trailer, the FNV-1a checksum of the buffer
// and a magic word; files without it (written before the trailer existed) are only verified.
constexpr char kTrailerMagic[4] = {'P', 'C', 'K', '1'};
constexpr size_t kTrailerSize = sizeof(uint64_t) + sizeof(kTrailerMagic);
constexpr uint16_t kSchemaVersion = 2;  // 1: DDPG in fixed fields, before the algorithm seam

std::vector<uint8_t> read_all(const std::string& path) {
  return read_file_bytes(path);
}

// The FlatBuffers part of a checkpoint file: all of it, less a trailer whose checksum matches.
size_t buffer_size(const std::vector<uint8_t>& bytes, const std::string& path) {
  if (bytes.size() < kTrailerSize ||
      std::memcmp(bytes.data() + bytes.size() - sizeof(kTrailerMagic), kTrailerMagic, sizeof(kTrailerMagic)) != 0) {
    return bytes.size();
  }
  const size_t size = bytes.size() - kTrailerSize;
  uint64_t sum = 0;
  std::memcpy(&sum, bytes.data() + size, sizeof(sum));
  if (sum != fnv1a64(bytes.data(), size)) {
    throw std::runtime_error("checkpoint '" + path +
                             "' is corrupt (checksum mismatch); use an earlier checkpoint (best.ckpt, a copy) or "
                             "start a new run");
  }
  return size;
}

const wire::Checkpoint* verified(const std::vector<uint8_t>& bytes, const std::string& path) {
  if (bytes.size() < 8 || !wire::CheckpointBufferHasIdentifier(bytes.data())) {
    throw std::runtime_error(
        "'" + path + "' is not a pamdp checkpoint (wrong file identifier); pass a .ckpt file written by pamdp train");
  }
  // With alignment checks (found by fuzz/fuzz_checkpoint: without them a crafted file put a float
  // vector at an odd address). The builder aligns what it writes, and the bytes start malloc-aligned.
  flatbuffers::Verifier verifier(bytes.data(), buffer_size(bytes, path), 64, 1000000, /*check_alignment=*/true);
  if (!wire::VerifyCheckpointBuffer(verifier)) {
    throw std::runtime_error("checkpoint '" + path +
                             "' is corrupt or truncated (FlatBuffers verification failed); use an earlier checkpoint");
  }
  const auto* ck = wire::GetCheckpoint(bytes.data());
  if (ck->schema_version() != 1 && ck->schema_version() != kSchemaVersion) {
    throw std::runtime_error(
        "checkpoint '" + path + "' has schema version " + std::to_string(ck->schema_version()) +
        "; this build reads versions 1 and 2 (a newer pamdp wrote it: evaluate it with that build)");
  }
  return ck;
}

std::vector<int> widths_of(const flatbuffers::Vector<int32_t>* v) {
  return v != nullptr ? std::vector<int>(v->begin(), v->end()) : std::vector<int>{};
}

// A checkpoint's state, by name, whichever version wrote it.
struct StoredTensor {
  const flatbuffers::Vector<float>* values = nullptr;
  std::vector<int> widths;
};
struct StoredState {
  std::string algorithm;
  std::map<std::string, StoredTensor> tensors;
  std::map<std::string, int64_t> counters;
};

StoredState stored_state(const wire::Checkpoint* ck, const std::string& path) {
  StoredState s;
  if (ck->schema_version() == 1) {
    // DDPG's state under the names DdpgAlgorithm gives it (learner/ddpg_algorithm.hpp).
    s.algorithm = "ddpg";
    const std::vector<int> aw = widths_of(ck->actor_widths());
    const std::vector<int> cw = widths_of(ck->critic_widths());
    s.tensors["actor"] = {ck->actor(), aw};
    s.tensors["critic"] = {ck->critic(), cw};
    s.tensors["target_actor"] = {ck->target_actor(), aw};
    s.tensors["target_critic"] = {ck->target_critic(), cw};
    const auto adam = [&](const std::string& name, const wire::AdamState* a) {
      if (a != nullptr) {
        s.tensors[name + ".m"] = {a->first_moment(), {}};
        s.tensors[name + ".v"] = {a->second_moment(), {}};
        s.counters[name + ".steps"] = a->steps();
      }
    };
    adam("actor_adam", ck->actor_adam());
    adam("critic_adam", ck->critic_adam());
    s.counters["updates"] = ck->updates();
    if (ck->actor_average() != nullptr) {
      s.tensors["actor_average"] = {ck->actor_average(), aw};
      s.counters["actor_average_updates"] = ck->actor_average_updates();
    }
    return s;
  }
  if (ck->algorithm() == nullptr || ck->tensors() == nullptr) {
    throw std::runtime_error("checkpoint '" + path +
                             "' names no algorithm or holds no state; use an earlier checkpoint");
  }
  s.algorithm = ck->algorithm()->str();
  for (const wire::Tensor* t : *ck->tensors()) {
    if (t->name() == nullptr || t->values() == nullptr) {
      throw std::runtime_error("checkpoint '" + path +
                               "': a tensor without a name or values; use an earlier checkpoint");
    }
    s.tensors[t->name()->str()] = {t->values(), widths_of(t->widths())};
  }
  if (ck->counters() != nullptr) {
    for (const wire::Counter* c : *ck->counters()) {
      if (c->name() != nullptr) {
        s.counters[c->name()->str()] = c->value();
      }
    }
  }
  return s;
}

void check_algorithm(const StoredState& s, const Algorithm& algorithm, const std::string& path) {
  if (s.algorithm != algorithm.name()) {
    throw std::runtime_error("checkpoint '" + path + "' was written by algorithm '" + s.algorithm +
                             "', this run's is '" + std::string(algorithm.name()) + "' (set train.algorithm = \"" +
                             s.algorithm + "\", or start a new run in another --run-dir)");
  }
}

void copy_into(const flatbuffers::Vector<float>* src, std::span<float> dst, const std::string& what,
               const std::string& path) {
  if (src == nullptr || src->size() != dst.size()) {
    throw std::runtime_error(
        "checkpoint '" + path + "': " + what + " has " + std::to_string(src ? src->size() : 0) +
        " values, this learner needs " + std::to_string(dst.size()) +
        " (written with other network widths or another env: resume without the --set that changes ddpg.hidden or "
        "env, or start a new run in another --run-dir)");
  }
  std::memcpy(dst.data(), src->data(), dst.size() * sizeof(float));
}

}  // namespace

void save_checkpoint(const std::string& path, Algorithm& algorithm, const CheckpointMeta& meta) {
  algorithm.sync_to_host();
  flatbuffers::FlatBufferBuilder fbb(1 << 20);
  const auto config = fbb.CreateString(meta.config_toml);
  const auto name = fbb.CreateString(std::string(algorithm.name()));
  std::vector<flatbuffers::Offset<wire::Tensor>> tensors;
  for (const StateTensor& t : algorithm.state_tensors()) {
    const auto n = fbb.CreateString(t.name);
    const auto w = fbb.CreateVector(t.widths);
    const auto v = fbb.CreateVector(t.values.data(), t.values.size());
    tensors.push_back(wire::CreateTensor(fbb, n, w, v));
  }
  const auto tensor_vec = fbb.CreateVector(tensors);
  std::vector<flatbuffers::Offset<wire::Counter>> counters;
  for (const StateCounter& c : algorithm.state_counters()) {
    counters.push_back(wire::CreateCounter(fbb, fbb.CreateString(c.name), *c.value));
  }
  const auto counter_vec = fbb.CreateVector(counters);
  std::vector<uint64_t> rng_words;
  for (const auto& s : meta.rng_states) {
    rng_words.insert(rng_words.end(), s.begin(), s.end());
  }
  const auto rngs = fbb.CreateVector(rng_words);
  wire::CheckpointBuilder b(fbb);
  b.add_schema_version(kSchemaVersion);
  b.add_config_toml(config);
  b.add_obs_dim(algorithm.obs_dim());
  b.add_action_dim(algorithm.output_width());
  b.add_updates(algorithm.updates());
  b.add_env_steps(meta.env_steps);
  b.add_episodes(meta.episodes);
  b.add_rng_states(rngs);
  b.add_elapsed_seconds(meta.elapsed_seconds);
  b.add_update_credit(meta.update_credit);
  b.add_weights_version(meta.weights_version);
  b.add_algorithm(name);
  b.add_tensors(tensor_vec);
  b.add_counters(counter_vec);
  wire::FinishCheckpointBuffer(fbb, b.Finish());
  const uint64_t sum = fnv1a64(fbb.GetBufferPointer(), fbb.GetSize());
  uint8_t trailer[kTrailerSize];
  std::memcpy(trailer, &sum, sizeof(sum));
  std::memcpy(trailer + sizeof(sum), kTrailerMagic, sizeof(kTrailerMagic));
  std::vector<uint8_t> file(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
  file.insert(file.end(), trailer, trailer + kTrailerSize);
  write_file_atomically(path, file.data(), file.size());
}

CheckpointMeta load_checkpoint(const std::string& path, Algorithm& algorithm) {
  const std::vector<uint8_t> bytes = read_all(path);
  const wire::Checkpoint* ck = verified(bytes, path);
  const StoredState stored = stored_state(ck, path);
  check_algorithm(stored, algorithm, path);
  if (ck->obs_dim() != algorithm.obs_dim() || ck->action_dim() != algorithm.output_width()) {
    throw std::runtime_error("checkpoint '" + path + "' is for observations of " + std::to_string(ck->obs_dim()) +
                             " and actions of " + std::to_string(ck->action_dim()) + ", this env has " +
                             std::to_string(algorithm.obs_dim()) + " and " + std::to_string(algorithm.output_width()));
  }
  // Every size is checked before anything is copied, so a refused file leaves the learner as it was.
  const std::vector<StateTensor> tensors = algorithm.state_tensors();
  std::vector<std::string> missing;
  for (const StateTensor& t : tensors) {
    const auto it = stored.tensors.find(t.name);
    if (it == stored.tensors.end()) {
      if (!t.optional) {
        throw std::runtime_error("checkpoint '" + path + "': missing " + t.name + "; use an earlier checkpoint");
      }
      missing.push_back(t.name);
    } else if (it->second.values->size() != t.values.size()) {
      copy_into(it->second.values, t.values, t.name, path);  // throws with the sizes
    }
  }
  for (const StateTensor& t : tensors) {
    const auto it = stored.tensors.find(t.name);
    if (it != stored.tensors.end()) {
      copy_into(it->second.values, t.values, t.name, path);
    }
  }
  for (const StateCounter& c : algorithm.state_counters()) {
    const auto it = stored.counters.find(c.name);
    if (it != stored.counters.end()) {
      *c.value = it->second;
    }
  }
  algorithm.restored(missing);
  CheckpointMeta meta;
  meta.config_toml = ck->config_toml() != nullptr ? ck->config_toml()->str() : "";
  meta.env_steps = ck->env_steps();
  meta.episodes = ck->episodes();
  meta.elapsed_seconds = ck->elapsed_seconds();
  meta.update_credit = ck->update_credit();
  meta.weights_version = ck->weights_version();
  if (const auto* r = ck->rng_states()) {
    // FlatBuffers 2.0's verifier does not check the alignment of 8-byte elements.
    if (r->size() % 4 != 0 || (r->size() > 0 && reinterpret_cast<uintptr_t>(r->data()) % alignof(uint64_t) != 0)) {
      throw std::runtime_error("checkpoint '" + path + "': RNG state is malformed");
    }
    for (flatbuffers::uoffset_t i = 0; i < r->size(); i += 4) {
      meta.rng_states.push_back({r->Get(i), r->Get(i + 1), r->Get(i + 2), r->Get(i + 3)});
    }
  }
  return meta;
}

namespace {

std::string join_widths(const std::vector<int>& w) {
  std::string s;
  for (const int x : w) {
    s += (s.empty() ? "" : "-") + std::to_string(x);
  }
  return s;
}

// Copies `src` (flat parameters of a network with widths `from`) into `dst` (widths `to`), whose
// first layer has `extra` more inputs inserted after the first `kept` ones (zero weights); every
// other layer is copied as is.
void widen_into(const flatbuffers::Vector<float>* src, const std::vector<int>& from, int kept, int extra,
                const std::vector<int>& to, std::span<float> dst_values, const std::string& what,
                const std::string& path) {
  Mlp<float> old(from, 1);
  copy_into(src, old.params(), what, path);
  Mlp<float> dst(to, 1);
  auto w0 = dst.weight(0);
  const auto o0 = old.weight(0);
  const int rest = o0.cols() - kept;
  w0.leftCols(kept) = o0.leftCols(kept);
  w0.middleCols(kept, extra).setZero();
  w0.rightCols(rest) = o0.rightCols(rest);
  dst.bias(0) = old.bias(0);
  for (int l = 1; l < dst.num_layers(); ++l) {
    dst.weight(l) = old.weight(l);
    dst.bias(l) = old.bias(l);
  }
  std::copy(dst.params().begin(), dst.params().end(), dst_values.begin());
}

}  // namespace

void warm_start_from_checkpoint(const std::string& path, Algorithm& algorithm) {
  const std::vector<uint8_t> bytes = read_all(path);
  const wire::Checkpoint* ck = verified(bytes, path);
  const StoredState stored = stored_state(ck, path);
  check_algorithm(stored, algorithm, path);
  const int obs = ck->obs_dim();
  const int extra = algorithm.obs_dim() - obs;
  std::vector<StateTensor> networks;
  for (StateTensor& t : algorithm.state_tensors()) {
    if (!t.widths.empty() && !t.optional) {
      networks.push_back(std::move(t));
    }
  }
  std::string theirs;
  std::string ours;
  bool fits = extra >= 0 && ck->action_dim() == algorithm.output_width();
  for (const StateTensor& t : networks) {
    const auto it = stored.tensors.find(t.name);
    std::vector<int> from = it != stored.tensors.end() ? it->second.widths : std::vector<int>{};
    theirs += (theirs.empty() ? "" : " / ") + (from.empty() ? std::string("none") : join_widths(from));
    ours += (ours.empty() ? "" : " / ") + join_widths(t.widths);
    if (!from.empty()) {
      from.front() += extra;
    }
    fits = fits && from == t.widths;
  }
  if (!fits) {
    throw std::runtime_error(
        "train.init_from: checkpoint '" + path + "' has networks " + theirs + " for " + std::to_string(obs) +
        " observations; this run's are " + ours + " for " + std::to_string(algorithm.obs_dim()) +
        ". A warm start needs the same ddpg.hidden and actions and at least the checkpoint's observations "
        "(set ddpg.hidden to the checkpoint's, or leave train.init_from empty)");
  }
  for (const StateTensor& t : networks) {
    const StoredTensor& from = stored.tensors.at(t.name);
    widen_into(from.values, from.widths, obs, extra, t.widths, t.values, t.name, path);
  }
  algorithm.warm_started();
}

std::string read_checkpoint_algorithm(const std::string& path) {
  const std::vector<uint8_t> bytes = read_all(path);
  return stored_state(verified(bytes, path), path).algorithm;
}

std::string read_checkpoint_config(const std::string& path) {
  const std::vector<uint8_t> bytes = read_all(path);
  const wire::Checkpoint* ck = verified(bytes, path);
  if (ck->config_toml() == nullptr) {
    throw std::runtime_error("checkpoint '" + path + "' holds no config");
  }
  return ck->config_toml()->str();
}

}  // namespace pamdp
