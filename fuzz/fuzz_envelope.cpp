// Opens fuzzed bytes as a protocol frame (wire::open_envelope: identifier, verifier, schema
// version) and, if they open, reads every field of the payload the way its receiver does. After
// verification no read may leave the buffer; ASan and UBSan turn any that does into a crash.
#include <cstddef>
#include <cstdint>
#include <span>

#include "core/wire.hpp"

namespace {

volatile uint64_t g_sink = 0;

template <typename T>
void touch_vector(const flatbuffers::Vector<T>* v) {
  if (v == nullptr) {
    return;
  }
  for (flatbuffers::uoffset_t i = 0; i < v->size(); ++i) {
    g_sink = g_sink + static_cast<uint64_t>(v->Get(i));
  }
}

void touch_string(const flatbuffers::String* s) {
  if (s != nullptr) {
    for (char c : s->string_view()) {
      g_sink = g_sink + static_cast<uint8_t>(c);
    }
  }
}

void touch_strings(const flatbuffers::Vector<flatbuffers::Offset<flatbuffers::String>>* v) {
  if (v != nullptr) {
    for (const flatbuffers::String* s : *v) {
      touch_string(s);
    }
  }
}

void touch_batch(const pamdp::wire::TransitionBatch* b) {
  if (b == nullptr) {
    return;
  }
  g_sink = g_sink + b->actor_id() + b->sequence() + b->obs_dim() + b->action_dim() + b->count();
  // The shard and the learner validate against their own widths; try the batch's own claims and
  // the toy task's, so that both the accept and the refuse paths run.
  for (const auto& [obs, act] : {std::pair<uint32_t, uint32_t>{b->obs_dim(), b->action_dim()}, {4, 3}, {58, 7}}) {
    if (pamdp::wire::valid_batch(b, obs, act, 4096)) {
      const pamdp::wire::TransitionRows r = pamdp::wire::rows_of(b);
      const size_t n = r.count;
      float sum = 0.0F;
      for (size_t i = 0; i < n * r.obs_dim; ++i) {
        sum += r.states[i] + r.next_states[i];
      }
      for (size_t i = 0; i < n * r.action_dim; ++i) {
        sum += r.actions[i];
      }
      for (size_t i = 0; i < n; ++i) {
        sum += r.rewards[i] + r.mc_returns[i] + static_cast<float>(r.terminals[i]);
      }
      g_sink = g_sink + static_cast<uint64_t>(sum != 0.0F);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace pamdp::wire;
  const Envelope* env = open_envelope(std::span<const uint8_t>(data, size));
  if (env == nullptr) {
    return 0;
  }
  switch (env->payload_type()) {
    case Payload::JoinRequest: {
      const JoinRequest* m = env->payload_as_JoinRequest();
      g_sink = g_sink + static_cast<uint64_t>(m->role()) + m->actor_envs();
      touch_string(m->name());
      touch_string(m->shard_endpoint());
      touch_string(m->shard_sample_endpoint());
      touch_string(m->metrics_url());
      break;
    }
    case Payload::ClusterMap: {
      const ClusterMap* m = env->payload_as_ClusterMap();
      g_sink = g_sink + m->version() + m->actor_index() + m->num_actors_hint() + m->weights_version();
      touch_string(m->config_toml());
      touch_strings(m->shard_endpoints());
      touch_strings(m->shard_sample_endpoints());
      touch_string(m->weights_endpoint());
      break;
    }
    case Payload::TransitionBatch: touch_batch(env->payload_as_TransitionBatch()); break;
    case Payload::SampleRequest: {
      const SampleRequest* m = env->payload_as_SampleRequest();
      g_sink = g_sink + m->request_id() + m->batch_size();
      break;
    }
    case Payload::SampleReply: {
      const SampleReply* m = env->payload_as_SampleReply();
      g_sink = g_sink + m->request_id();
      touch_batch(m->batch());
      break;
    }
    case Payload::PolicyWeights: {
      const PolicyWeights* m = env->payload_as_PolicyWeights();
      g_sink = g_sink + m->version() + static_cast<uint64_t>(m->updates()) + m->bound();
      touch_vector(m->widths());
      if (m->params() != nullptr) {
        float sum = 0.0F;
        for (float v : *m->params()) {
          sum += v;
        }
        g_sink = g_sink + static_cast<uint64_t>(sum != 0.0F);
      }
      // What an actor reads of it (actor/actor_loop.cpp): the named networks as views.
      std::string_view algorithm;
      for (const pamdp::NetworkView& n : pamdp::wire::policy_networks(*m, algorithm)) {
        g_sink = g_sink + n.name.size() + n.widths.size() + n.params.size() +
                 static_cast<uint64_t>(!n.widths.empty() && n.widths.back() != 0) +
                 static_cast<uint64_t>(!n.params.empty() && n.params.back() != 0.0F);
      }
      g_sink = g_sink + algorithm.size();
      break;
    }
    case Payload::EpisodeReport: {
      const EpisodeReport* m = env->payload_as_EpisodeReport();
      g_sink = g_sink + m->actor_id() + m->episode() + m->steps() + static_cast<uint64_t>(m->status()) +
               m->policy_version() + static_cast<uint64_t>(m->return_() != 0.0F);
      break;
    }
    case Payload::Heartbeat: {
      const Heartbeat* m = env->payload_as_Heartbeat();
      g_sink = g_sink + static_cast<uint64_t>(m->role()) + m->map_version();
      touch_string(m->name());
      touch_vector(m->counters());
      break;
    }
    case Payload::MetricsUrlsRequest: break;
    case Payload::MetricsUrls: touch_strings(env->payload_as_MetricsUrls()->urls()); break;
    case Payload::InsertAck: {
      const InsertAck* a = env->payload_as_InsertAck();
      g_sink = g_sink + a->sequence() + a->inserted();
      break;
    }
    default: break;
  }
  return 0;
}
