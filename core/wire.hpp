// The schema layer: the only code that touches generated FlatBuffers types for the protocol
// (schemas/messages.fbs, docs/protocol.md). Builders write one Envelope into a caller-owned
// FlatBufferBuilder (Clear()ed and reused, so steady-state sending allocates nothing once the
// builder has grown); open_envelope() verifies a received buffer before anything reads it.
#pragma once

#include <flatbuffers/flatbuffers.h>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/network_view.hpp"
#include "schemas/messages_generated.h"

namespace pamdp::wire {

inline constexpr uint16_t kSchemaVersion = 1;

// Returns the envelope if `bytes` is a well-formed, verified Envelope of our schema version,
// else nullptr (the caller counts and drops it).
const Envelope* open_envelope(std::span<const uint8_t> bytes);

// The finished buffer of a builder.
inline std::span<const uint8_t> bytes_of(const flatbuffers::FlatBufferBuilder& fbb) {
  return {fbb.GetBufferPointer(), fbb.GetSize()};
}

// Rows of transitions, row-major: states count*obs_dim, actions count*action_dim, ...
struct TransitionRows {
  uint32_t count = 0;
  uint32_t obs_dim = 0;
  uint32_t action_dim = 0;
  const float* states = nullptr;
  const float* actions = nullptr;
  const float* rewards = nullptr;
  const float* next_states = nullptr;
  const uint8_t* terminals = nullptr;
  const float* mc_returns = nullptr;
};

// True if every array of `batch` has the sizes its count and the expected widths imply, the
// count is within max_count, and every float is finite.
bool valid_batch(const TransitionBatch* batch, uint32_t obs_dim, uint32_t action_dim, uint32_t max_count);
// Views of a validated batch.
TransitionRows rows_of(const TransitionBatch* batch);

void build_join_request(flatbuffers::FlatBufferBuilder& fbb, Role role, const std::string& name,
                        const std::string& shard_insert_endpoint, const std::string& shard_sample_endpoint,
                        uint32_t actor_envs, const std::string& metrics_url = "");
void build_cluster_map(flatbuffers::FlatBufferBuilder& fbb, uint64_t version, const std::string& config_toml,
                       const std::vector<std::string>& shard_insert_endpoints,
                       const std::vector<std::string>& shard_sample_endpoints, const std::string& weights_endpoint,
                       uint32_t actor_index, uint32_t num_actors_hint, uint64_t weights_version);
// TransitionBatch.table: the replay table, and the demonstration table that cloning samples.
inline constexpr uint8_t kReplayTable = 0;
inline constexpr uint8_t kDemoTable = 1;

// writer: the sending process's random id (TransitionBatch.writer); 0 opts out of deduplication.
void build_transition_batch(flatbuffers::FlatBufferBuilder& fbb, uint32_t actor_id, uint64_t sequence,
                            const TransitionRows& rows, uint8_t table = kReplayTable, uint64_t writer = 0);
// demo_batch_size > 0: the shard also sends that many demonstrations when it holds any.
void build_sample_request(flatbuffers::FlatBufferBuilder& fbb, uint64_t request_id, uint32_t batch_size,
                          uint32_t demo_batch_size = 0);
void build_sample_reply(flatbuffers::FlatBufferBuilder& fbb, uint64_t request_id, const TransitionRows& rows,
                        const TransitionRows* demos = nullptr);
// `algorithm` names the acting policy the actors build from `networks` (actor/acting_policy.hpp).
void build_policy_weights(flatbuffers::FlatBufferBuilder& fbb, uint64_t version, int64_t updates,
                          std::string_view algorithm, uint8_t bound, std::span<const NetworkView> networks);
// The networks of a verified PolicyWeights as views into it: its named networks, or a message
// from a learner before the algorithm seam read as DDPG's actor. `algorithm` receives the name
// ("ddpg" for the older messages). Empty when it carries none.
std::vector<NetworkView> policy_networks(const PolicyWeights& w, std::string_view& algorithm);
void build_episode_report(flatbuffers::FlatBufferBuilder& fbb, uint32_t actor_id, uint64_t episode, float ret,
                          uint32_t steps, int32_t status, uint64_t policy_version, bool scripted = false);
void build_heartbeat(flatbuffers::FlatBufferBuilder& fbb, Role role, const std::string& name, uint64_t map_version,
                     std::span<const int64_t> counters);
// Shard -> actor: the batch `sequence` was read, and `inserted` of its transitions stored.
void build_insert_ack(flatbuffers::FlatBufferBuilder& fbb, uint64_t sequence, uint32_t inserted);
void build_metrics_urls_request(flatbuffers::FlatBufferBuilder& fbb);
void build_metrics_urls(flatbuffers::FlatBufferBuilder& fbb, const std::vector<std::string>& urls);

}  // namespace pamdp::wire
