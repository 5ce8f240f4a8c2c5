#include "core/wire.hpp"

#include <cmath>

namespace pamdp::wire {
namespace {

void finish(flatbuffers::FlatBufferBuilder& fbb, Payload type, flatbuffers::Offset<void> payload) {
  EnvelopeBuilder env(fbb);
  env.add_schema_version(kSchemaVersion);
  env.add_payload_type(type);
  env.add_payload(payload);
  FinishEnvelopeBuffer(fbb, env.Finish());
}

bool all_finite(const flatbuffers::Vector<float>* v) {
  for (flatbuffers::uoffset_t i = 0; i < v->size(); ++i) {
    if (!std::isfinite(v->Get(i))) {
      return false;
    }
  }
  return true;
}

flatbuffers::Offset<TransitionBatch> batch_offset(flatbuffers::FlatBufferBuilder& fbb, uint32_t actor_id,
                                                  uint64_t sequence, const TransitionRows& r, uint8_t table = 0,
                                                  uint64_t writer = 0) {
  const size_t n = r.count;
  const auto states = fbb.CreateVector(r.states, n * r.obs_dim);
  const auto actions = fbb.CreateVector(r.actions, n * r.action_dim);
  const auto rewards = fbb.CreateVector(r.rewards, n);
  const auto next_states = fbb.CreateVector(r.next_states, n * r.obs_dim);
  const auto terminals = fbb.CreateVector(r.terminals, n);
  const auto returns = fbb.CreateVector(r.mc_returns, n);
  return CreateTransitionBatch(fbb, actor_id, sequence, r.obs_dim, r.action_dim, r.count, states, actions, rewards,
                               next_states, terminals, returns, table, writer);
}

}  // namespace

const Envelope* open_envelope(std::span<const uint8_t> bytes) {
  if (bytes.size() < 8 || !EnvelopeBufferHasIdentifier(bytes.data())) {
    return nullptr;
  }
  flatbuffers::Verifier verifier(bytes.data(), bytes.size());
  if (!VerifyEnvelopeBuffer(verifier)) {
    return nullptr;
  }
  const Envelope* env = GetEnvelope(bytes.data());
  if (env->schema_version() != kSchemaVersion || env->payload() == nullptr) {
    return nullptr;
  }
  // The verifier of our FlatBuffers (2.0) checks a vector's length prefix for alignment, not its
  // elements: a crafted Heartbeat can place its 8-byte counters at an address that is not a
  // multiple of 8, and reading them would be undefined behaviour (found by fuzz/fuzz_envelope). An
  // empty vector has nothing to read, and builders do not align it.
  if (const Heartbeat* hb = env->payload_as_Heartbeat();
      hb != nullptr && hb->counters() != nullptr && hb->counters()->size() > 0 &&
      reinterpret_cast<uintptr_t>(hb->counters()->data()) % alignof(int64_t) != 0) {
    return nullptr;
  }
  return env;
}

bool valid_batch(const TransitionBatch* b, uint32_t obs_dim, uint32_t action_dim, uint32_t max_count) {
  if (b == nullptr || b->obs_dim() != obs_dim || b->action_dim() != action_dim || b->count() == 0 ||
      b->count() > max_count) {
    return false;
  }
  const size_t n = b->count();
  if (b->states() == nullptr || b->actions() == nullptr || b->rewards() == nullptr || b->next_states() == nullptr ||
      b->terminals() == nullptr || b->mc_returns() == nullptr) {
    return false;
  }
  if (b->states()->size() != n * obs_dim || b->next_states()->size() != n * obs_dim ||
      b->actions()->size() != n * action_dim || b->rewards()->size() != n || b->terminals()->size() != n ||
      b->mc_returns()->size() != n) {
    return false;
  }
  return all_finite(b->states()) && all_finite(b->next_states()) && all_finite(b->actions()) &&
         all_finite(b->rewards()) && all_finite(b->mc_returns());
}

TransitionRows rows_of(const TransitionBatch* b) {
  return {b->count(),
          b->obs_dim(),
          b->action_dim(),
          b->states()->data(),
          b->actions()->data(),
          b->rewards()->data(),
          b->next_states()->data(),
          b->terminals()->data(),
          b->mc_returns()->data()};
}

void build_join_request(flatbuffers::FlatBufferBuilder& fbb, Role role, const std::string& name,
                        const std::string& shard_insert_endpoint, const std::string& shard_sample_endpoint,
                        uint32_t actor_envs, const std::string& metrics_url) {
  fbb.Clear();
  const auto n = fbb.CreateString(name);
  const auto e = fbb.CreateString(shard_insert_endpoint);
  const auto s = fbb.CreateString(shard_sample_endpoint);
  const auto m = fbb.CreateString(metrics_url);
  finish(fbb, Payload::JoinRequest, CreateJoinRequest(fbb, role, n, e, actor_envs, s, m).Union());
}

void build_cluster_map(flatbuffers::FlatBufferBuilder& fbb, uint64_t version, const std::string& config_toml,
                       const std::vector<std::string>& shard_insert_endpoints,
                       const std::vector<std::string>& shard_sample_endpoints, const std::string& weights_endpoint,
                       uint32_t actor_index, uint32_t num_actors_hint, uint64_t weights_version) {
  fbb.Clear();
  const auto cfg = fbb.CreateString(config_toml);
  const auto inserts = fbb.CreateVectorOfStrings(shard_insert_endpoints);
  const auto samples = fbb.CreateVectorOfStrings(shard_sample_endpoints);
  const auto weights = fbb.CreateString(weights_endpoint);
  finish(fbb, Payload::ClusterMap,
         CreateClusterMap(fbb, version, cfg, inserts, weights, actor_index, num_actors_hint, weights_version, samples)
             .Union());
}

void build_transition_batch(flatbuffers::FlatBufferBuilder& fbb, uint32_t actor_id, uint64_t sequence,
                            const TransitionRows& rows, uint8_t table, uint64_t writer) {
  fbb.Clear();
  finish(fbb, Payload::TransitionBatch, batch_offset(fbb, actor_id, sequence, rows, table, writer).Union());
}

void build_sample_request(flatbuffers::FlatBufferBuilder& fbb, uint64_t request_id, uint32_t batch_size,
                          uint32_t demo_batch_size) {
  fbb.Clear();
  finish(fbb, Payload::SampleRequest, CreateSampleRequest(fbb, request_id, batch_size, demo_batch_size).Union());
}

void build_sample_reply(flatbuffers::FlatBufferBuilder& fbb, uint64_t request_id, const TransitionRows& rows,
                        const TransitionRows* demos) {
  fbb.Clear();
  const auto batch = batch_offset(fbb, 0, request_id, rows);
  flatbuffers::Offset<TransitionBatch> demo_batch;
  if (demos != nullptr) {
    demo_batch = batch_offset(fbb, 0, request_id, *demos, kDemoTable);
  }
  finish(fbb, Payload::SampleReply, CreateSampleReply(fbb, request_id, batch, demo_batch).Union());
}

void build_policy_weights(flatbuffers::FlatBufferBuilder& fbb, uint64_t version, int64_t updates,
                          std::string_view algorithm, uint8_t bound, std::span<const NetworkView> networks) {
  fbb.Clear();
  std::vector<flatbuffers::Offset<NamedNetwork>> nets;
  nets.reserve(networks.size());
  for (const NetworkView& n : networks) {
    const auto name = fbb.CreateString(n.name.data(), n.name.size());
    const auto w = fbb.CreateVector(n.widths.data(), n.widths.size());
    const auto p = fbb.CreateVector(n.params.data(), n.params.size());
    nets.push_back(CreateNamedNetwork(fbb, name, w, p));
  }
  const auto list = fbb.CreateVector(nets);
  const auto name = fbb.CreateString(algorithm.data(), algorithm.size());
  finish(fbb, Payload::PolicyWeights, CreatePolicyWeights(fbb, version, updates, {}, bound, {}, name, list).Union());
}

std::vector<NetworkView> policy_networks(const PolicyWeights& w, std::string_view& algorithm) {
  const auto view = [](const flatbuffers::String* name, const flatbuffers::Vector<int32_t>* widths,
                       const flatbuffers::Vector<float>* params, std::string_view fallback) {
    return NetworkView{
        name != nullptr ? std::string_view(name->c_str(), name->size()) : fallback,
        widths != nullptr ? std::span<const int>(widths->data(), widths->size()) : std::span<const int>(),
        params != nullptr ? std::span<const float>(params->data(), params->size()) : std::span<const float>()};
  };
  std::vector<NetworkView> out;
  if (w.networks() != nullptr) {
    algorithm = w.algorithm() != nullptr ? std::string_view(w.algorithm()->c_str(), w.algorithm()->size()) : "";
    for (const NamedNetwork* n : *w.networks()) {
      out.push_back(view(n->name(), n->widths(), n->params(), ""));
    }
  } else if (w.widths() != nullptr) {
    algorithm = "ddpg";
    out.push_back(view(nullptr, w.widths(), w.params(), "actor"));
  }
  return out;
}

void build_episode_report(flatbuffers::FlatBufferBuilder& fbb, uint32_t actor_id, uint64_t episode, float ret,
                          uint32_t steps, int32_t status, uint64_t policy_version, bool scripted) {
  fbb.Clear();
  finish(fbb, Payload::EpisodeReport,
         CreateEpisodeReport(fbb, kSchemaVersion, actor_id, episode, ret, steps, status, policy_version, scripted)
             .Union());
}

void build_heartbeat(flatbuffers::FlatBufferBuilder& fbb, Role role, const std::string& name, uint64_t map_version,
                     std::span<const int64_t> counters) {
  fbb.Clear();
  const auto n = fbb.CreateString(name);
  const auto c = fbb.CreateVector(counters.data(), counters.size());
  finish(fbb, Payload::Heartbeat, CreateHeartbeat(fbb, role, n, map_version, c).Union());
}

void build_insert_ack(flatbuffers::FlatBufferBuilder& fbb, uint64_t sequence, uint32_t inserted) {
  fbb.Clear();
  finish(fbb, Payload::InsertAck, CreateInsertAck(fbb, sequence, inserted).Union());
}

void build_metrics_urls_request(flatbuffers::FlatBufferBuilder& fbb) {
  fbb.Clear();
  finish(fbb, Payload::MetricsUrlsRequest, CreateMetricsUrlsRequest(fbb).Union());
}

void build_metrics_urls(flatbuffers::FlatBufferBuilder& fbb, const std::vector<std::string>& urls) {
  fbb.Clear();
  const auto u = fbb.CreateVectorOfStrings(urls);
  finish(fbb, Payload::MetricsUrls, CreateMetricsUrls(fbb, u).Union());
}

}  // namespace pamdp::wire
