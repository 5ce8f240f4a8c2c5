#include "learner/checkpoint.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "core/files.hpp"
#include "schemas/checkpoint_generated.h"

namespace pamdp {
namespace {

// The FlatBuffers verifier proves a checkpoint safe to read, not unchanged: a flipped byte in the
// parameters still verifies. So the file ends with a trailer, the FNV-1a checksum of the buffer
// and a magic word; files without it (written before the trailer existed) are only verified.
constexpr char kTrailerMagic[4] = {'P', 'C', 'K', '1'};
constexpr size_t kTrailerSize = sizeof(uint64_t) + sizeof(kTrailerMagic);

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
  if (ck->schema_version() != 1) {
    throw std::runtime_error("checkpoint '" + path + "' has schema version " + std::to_string(ck->schema_version()) +
                             "; this build reads version 1");
  }
  return ck;
}

void copy_into(const flatbuffers::Vector<float>* src, std::span<float> dst, const char* what, const std::string& path) {
  if (src == nullptr || src->size() != dst.size()) {
    throw std::runtime_error(
        "checkpoint '" + path + "': " + what + " has " + std::to_string(src ? src->size() : 0) +
        " values, this learner needs " + std::to_string(dst.size()) +
        " (written with other network widths or another env: resume without the --set that changes ddpg.hidden or "
        "env, or start a new run in another --run-dir)");
  }
  std::memcpy(dst.data(), src->data(), dst.size() * sizeof(float));
}

flatbuffers::Offset<wire::AdamState> adam_state(flatbuffers::FlatBufferBuilder& fbb, Adam<float>& adam) {
  const auto m = fbb.CreateVector(adam.first_moment().data(), adam.first_moment().size());
  const auto v = fbb.CreateVector(adam.second_moment().data(), adam.second_moment().size());
  return wire::CreateAdamState(fbb, adam.steps(), m, v);
}

void restore_adam(const wire::AdamState* s, Adam<float>& adam, const char* what, const std::string& path) {
  if (s == nullptr) {
    throw std::runtime_error("checkpoint '" + path + "': missing " + what);
  }
  copy_into(s->first_moment(), adam.first_moment(), what, path);
  copy_into(s->second_moment(), adam.second_moment(), what, path);
  adam.set_steps(s->steps());
}

}  // namespace

void save_checkpoint(const std::string& path, Ddpg& ddpg, const CheckpointMeta& meta) {
  flatbuffers::FlatBufferBuilder fbb(1 << 20);
  const auto vec = [&](Mlp<float>& net) { return fbb.CreateVector(net.params().data(), net.params().size()); };
  const auto config = fbb.CreateString(meta.config_toml);
  const auto aw = fbb.CreateVector(ddpg.actor().widths());
  const auto cw = fbb.CreateVector(ddpg.critic().widths());
  const auto actor = vec(ddpg.actor());
  const auto critic = vec(ddpg.critic());
  const auto target_actor = vec(ddpg.target_actor());
  const auto target_critic = vec(ddpg.target_critic());
  const auto actor_adam = adam_state(fbb, ddpg.actor_optimizer());
  const auto critic_adam = adam_state(fbb, ddpg.critic_optimizer());
  const auto average =
      ddpg.averages_actor() ? vec(ddpg.actor_average()) : flatbuffers::Offset<flatbuffers::Vector<float>>();
  std::vector<uint64_t> rng_words;
  for (const auto& s : meta.rng_states) {
    rng_words.insert(rng_words.end(), s.begin(), s.end());
  }
  const auto rngs = fbb.CreateVector(rng_words);
  wire::CheckpointBuilder b(fbb);
  b.add_schema_version(1);
  b.add_config_toml(config);
  b.add_obs_dim(ddpg.obs_dim());
  b.add_action_dim(ddpg.output_width());
  b.add_actor_widths(aw);
  b.add_critic_widths(cw);
  b.add_actor(actor);
  b.add_critic(critic);
  b.add_target_actor(target_actor);
  b.add_target_critic(target_critic);
  b.add_actor_adam(actor_adam);
  b.add_critic_adam(critic_adam);
  b.add_updates(ddpg.updates());
  b.add_env_steps(meta.env_steps);
  b.add_episodes(meta.episodes);
  b.add_rng_states(rngs);
  b.add_elapsed_seconds(meta.elapsed_seconds);
  b.add_update_credit(meta.update_credit);
  b.add_weights_version(meta.weights_version);
  if (ddpg.averages_actor()) {
    b.add_actor_average(average);
    b.add_actor_average_updates(ddpg.actor_average_updates());
  }
  wire::FinishCheckpointBuffer(fbb, b.Finish());
  const uint64_t sum = fnv1a64(fbb.GetBufferPointer(), fbb.GetSize());
  uint8_t trailer[kTrailerSize];
  std::memcpy(trailer, &sum, sizeof(sum));
  std::memcpy(trailer + sizeof(sum), kTrailerMagic, sizeof(kTrailerMagic));
  std::vector<uint8_t> file(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
  file.insert(file.end(), trailer, trailer + kTrailerSize);
  write_file_atomically(path, file.data(), file.size());
}

CheckpointMeta load_checkpoint(const std::string& path, Ddpg& ddpg) {
  const std::vector<uint8_t> bytes = read_all(path);
  const wire::Checkpoint* ck = verified(bytes, path);
  if (ck->obs_dim() != ddpg.obs_dim() || ck->action_dim() != ddpg.output_width()) {
    throw std::runtime_error("checkpoint '" + path + "' is for observations of " + std::to_string(ck->obs_dim()) +
                             " and actions of " + std::to_string(ck->action_dim()) + ", this env has " +
                             std::to_string(ddpg.obs_dim()) + " and " + std::to_string(ddpg.output_width()));
  }
  copy_into(ck->actor(), ddpg.actor().params(), "actor", path);
  copy_into(ck->critic(), ddpg.critic().params(), "critic", path);
  copy_into(ck->target_actor(), ddpg.target_actor().params(), "target_actor", path);
  copy_into(ck->target_critic(), ddpg.target_critic().params(), "target_critic", path);
  restore_adam(ck->actor_adam(), ddpg.actor_optimizer(), "actor Adam state", path);
  restore_adam(ck->critic_adam(), ddpg.critic_optimizer(), "critic Adam state", path);
  ddpg.set_updates(ck->updates());
  if (ck->actor_average() != nullptr) {
    copy_into(ck->actor_average(), ddpg.actor_average().params(), "actor_average", path);
    ddpg.set_actor_average_updates(ck->actor_average_updates());
  } else {
    ddpg.reset_actor_average();  // written without one (ddpg.actor_average_tau was 0, or an older build)
  }
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

std::vector<int> widths_of(const flatbuffers::Vector<int32_t>* v) {
  return v != nullptr ? std::vector<int>(v->begin(), v->end()) : std::vector<int>{};
}

std::string join_widths(const std::vector<int>& w) {
  std::string s;
  for (const int x : w) {
    s += (s.empty() ? "" : "-") + std::to_string(x);
  }
  return s;
}

// Copies `src` (flat parameters of a network with widths `from`) into `dst`, whose first layer
// has `extra` more inputs inserted after the first `kept` ones (zero weights); every other layer
// is copied as is.
void widen_into(const flatbuffers::Vector<float>* src, const std::vector<int>& from, int kept, int extra,
                Mlp<float>& dst, const char* what, const std::string& path) {
  Mlp<float> old(from, 1);
  copy_into(src, old.params(), what, path);
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
}

}  // namespace

void warm_start_from_checkpoint(const std::string& path, Ddpg& ddpg) {
  const std::vector<uint8_t> bytes = read_all(path);
  const wire::Checkpoint* ck = verified(bytes, path);
  const int obs = ck->obs_dim();
  const int extra = ddpg.obs_dim() - obs;
  const std::vector<int> actor_from = widths_of(ck->actor_widths());
  const std::vector<int> critic_from = widths_of(ck->critic_widths());
  std::vector<int> actor_to = actor_from;
  std::vector<int> critic_to = critic_from;
  if (!actor_to.empty() && !critic_to.empty()) {
    actor_to.front() += extra;
    critic_to.front() += extra;
  }
  if (extra < 0 || ck->action_dim() != ddpg.output_width() || actor_to != ddpg.actor().widths() ||
      critic_to != ddpg.critic().widths()) {
    throw std::runtime_error(
        "train.init_from: checkpoint '" + path + "' has networks " + join_widths(actor_from) + " / " +
        join_widths(critic_from) + " for " + std::to_string(obs) + " observations; this run's are " +
        join_widths(ddpg.actor().widths()) + " / " + join_widths(ddpg.critic().widths()) + " for " +
        std::to_string(ddpg.obs_dim()) +
        ". A warm start needs the same ddpg.hidden and actions and at least the checkpoint's observations "
        "(set ddpg.hidden to the checkpoint's, or leave train.init_from empty)");
  }
  widen_into(ck->actor(), actor_from, obs, extra, ddpg.actor(), "actor", path);
  widen_into(ck->critic(), critic_from, obs, extra, ddpg.critic(), "critic", path);
  widen_into(ck->target_actor(), actor_from, obs, extra, ddpg.target_actor(), "target_actor", path);
  widen_into(ck->target_critic(), critic_from, obs, extra, ddpg.target_critic(), "target_critic", path);
  ddpg.reset_actor_average();  // this run's average starts at the weights it starts from
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
