#include "learner/learner_server.hpp"

#include <algorithm>
#include <cstring>

#include "core/log.hpp"
#include "core/wire.hpp"

namespace pamdp {

struct FbbHolder {
  flatbuffers::FlatBufferBuilder fbb{1 << 16};
  flatbuffers::FlatBufferBuilder weights{1 << 22};
};

struct LearnerServer::Shard {
  std::string insert_endpoint;
  std::string sample_endpoint;
  std::vector<uint8_t> join_identity;  // the shard's DEALER identity on our join socket
  net::Socket dealer;
  int in_flight = 0;
  std::chrono::steady_clock::time_point last_heard;
  int64_t samples = 0;
  net::PeerCounters* traffic = nullptr;  // the peer it joined as ("replay:NAME")
  Shard(net::Context& ctx) : dealer(ctx, net::SocketType::kDealer) {}
};

namespace {

using Clock = std::chrono::steady_clock;

int64_t ms_since(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t).count();
}

}  // namespace

LearnerServer::LearnerServer(net::Context& ctx, Algorithm& algorithm, LearnerServerConfig config)
    : ctx_(ctx),
      algorithm_(algorithm),
      config_(std::move(config)),
      join_(ctx, net::SocketType::kRouter),
      weights_(ctx, net::SocketType::kPub),
      handshakes_(ctx, {&join_, &weights_}, "learner"),
      fbb_(std::make_unique<FbbHolder>()) {
  // A join socket peer can send at most a JoinRequest, heartbeats and episode reports: small.
  join_.set_max_message_bytes(1 << 20);
  join_.set_recv_hwm(10000);
  weights_.set_send_hwm(4);  // slow subscribers get the newest weights, not a backlog
  counters_.weights_version = config_.weights_version;
  if (config_.curve) {
    join_.make_curve_server(*config_.curve);
    weights_.make_curve_server(*config_.curve);
  }
  join_endpoint_ = net::advertised_endpoint(join_.bind(config_.join_bind), config_.advertise_host);
  weights_endpoint_ = net::advertised_endpoint(weights_.bind(config_.weights_bind), config_.advertise_host);
}

LearnerServer::~LearnerServer() = default;

void LearnerServer::note_malformed(const char* what) {
  ++counters_.malformed_messages;
  if (ms_since(last_malformed_log_) >= 1000) {
    last_malformed_log_ = Clock::now();
    log::warn("learner: dropped a malformed message ({}); {} so far", what, counters_.malformed_messages);
  }
}

void LearnerServer::send_map(std::span<const uint8_t> identity, uint32_t actor_index) {
  std::vector<std::string> inserts;
  std::vector<std::string> samples;
  for (const auto& s : shards_) {
    inserts.push_back(s->insert_endpoint);
    samples.push_back(s->sample_endpoint);
  }
  wire::build_cluster_map(fbb_->fbb, map_version_, config_.config_toml, inserts, samples, weights_endpoint_,
                          actor_index, next_actor_index_, static_cast<uint64_t>(counters_.weights_version));
  if (join_.send_to(identity, wire::bytes_of(fbb_->fbb), 100)) {
    count_sent(identity, wire::bytes_of(fbb_->fbb).size());
  }
}

void LearnerServer::count_sent(std::span<const uint8_t> identity, size_t bytes) {
  const auto peer = peers_.find(std::string(reinterpret_cast<const char*>(identity.data()), identity.size()));
  if (peer != peers_.end() && peer->second.traffic != nullptr) {
    peer->second.traffic->sent(bytes);
  }
}

void LearnerServer::publish_weights() {
  algorithm_.sync_acting();  // and moves an evaluation average
  const ActingWeights acting = algorithm_.acting_weights();
  ++counters_.weights_version;
  wire::build_policy_weights(fbb_->weights, static_cast<uint64_t>(counters_.weights_version), algorithm_.updates(),
                             acting.algorithm, acting.bound, acting.networks);
  weights_.send(wire::bytes_of(fbb_->weights), 0);
  last_published_at_ = algorithm_.updates();
}

void LearnerServer::handle_join_socket() {
  net::Message identity;
  net::Message payload;
  while (join_.recv_from(identity, payload, 0)) {
    if (join_.too_big(payload)) {
      const auto p = peers_.find(std::string(reinterpret_cast<const char*>(identity.data()), identity.size()));
      net::PeerCounters& from =
          p != peers_.end() && p->second.traffic != nullptr ? *p->second.traffic : peers_table_.peer("unknown");
      from.refused_oversized(payload.size());
      note_malformed(
          "join socket: a frame over its size limit, refused unread (pamdp_peer_frames_refused_for_size_total)");
      continue;
    }
    const wire::Envelope* env = wire::open_envelope(payload.bytes());
    if (env == nullptr) {
      note_malformed("join socket: not a verified envelope");
      continue;
    }
    const std::vector<uint8_t> id(identity.data(), identity.data() + identity.size());
    const std::string peer_id(reinterpret_cast<const char*>(identity.data()), identity.size());
    net::PeerCounters* traffic = nullptr;
    if (const auto p = peers_.find(peer_id); p != peers_.end()) {
      traffic = p->second.traffic;
    }
    if (traffic == nullptr && env->payload_type() == wire::Payload::JoinRequest) {
      // A peer is named by the role and name it joins with; the same name on a new connection
      // is the same peer reconnected (after a partition, or a restart under the same name).
      const auto* j = env->payload_as_JoinRequest();
      const std::string name = std::string(j->role() == wire::Role::Shard ? "replay:" : "actor:") +
                               (j->name() != nullptr ? j->name()->str() : "?");
      const bool seen = peers_table_.knows(name);
      traffic = &peers_table_.peer(name);
      if (seen) {
        traffic->reconnected();
      }
    }
    if (traffic != nullptr) {
      traffic->received(payload.size());
    }
    switch (env->payload_type()) {
      case wire::Payload::JoinRequest: {
        const auto* j = env->payload_as_JoinRequest();
        if (j->role() == wire::Role::Shard) {
          if (j->shard_endpoint() == nullptr || j->shard_sample_endpoint() == nullptr ||
              j->shard_endpoint()->size() == 0 || j->shard_sample_endpoint()->size() == 0) {
            note_malformed("shard JoinRequest without endpoints");
            continue;
          }
          const std::string insert = j->shard_endpoint()->str();
          const std::string sample = j->shard_sample_endpoint()->str();
          auto it =
              std::find_if(shards_.begin(), shards_.end(), [&](const auto& s) { return s->insert_endpoint == insert; });
          if (it != shards_.end() && (*it)->sample_endpoint != sample) {
            shards_.erase(it);  // same insert address, new process: start over
            it = shards_.end();
          }
          if (it == shards_.end()) {
            auto shard = std::make_unique<Shard>(ctx_);
            shard->insert_endpoint = insert;
            shard->sample_endpoint = sample;
            shard->dealer.set_max_message_bytes(64 << 20);
            if (config_.curve_client) {
              shard->dealer.make_curve_client(*config_.curve_client);
            }
            shard->dealer.connect(sample);
            shards_.push_back(std::move(shard));
            shards_changed();
            log::info("learner: shard joined: insert {} sample {} ({} shards)", insert, sample, shards_.size());
            it = std::prev(shards_.end());
          }
          (*it)->join_identity = id;
          (*it)->last_heard = Clock::now();
          (*it)->traffic = traffic;
          peers_[peer_id] = {false, j->metrics_url() != nullptr ? j->metrics_url()->str() : "", Clock::now(), traffic};
          refresh_peers(false);
          send_map(identity.bytes(), 0);
        } else if (j->role() == wire::Role::Actor) {
          // An actor that joins again (its map went stale) keeps its index.
          auto known = actor_index_.find(id);
          if (known == actor_index_.end()) {
            known = actor_index_.emplace(id, next_actor_index_++).first;
            ++counters_.actors_joined;
            log::info("learner: actor {} joined ({}, {} envs)", known->second, j->name() ? j->name()->str() : "?",
                      j->actor_envs());
          }
          peers_[peer_id] = {true, j->metrics_url() != nullptr ? j->metrics_url()->str() : "", Clock::now(), traffic};
          refresh_peers(false);
          send_map(identity.bytes(), known->second);
          // The newcomer subscribes only after it has the map: publish again shortly.
          republish_at_ = Clock::now() + std::chrono::milliseconds(200);
        } else {
          note_malformed("JoinRequest from an unexpected role");
        }
        break;
      }
      case wire::Payload::Heartbeat: {
        // An actor counts as known while it is alive (in peers_): one silent past the peer
        // timeout was dropped from peers_, and when it is heard again (a healed partition) it
        // must join again to be counted, listed and sent the map; it keeps its index.
        bool known = actor_index_.count(id) != 0 && peers_.count(peer_id) != 0;
        if (auto peer = peers_.find(peer_id); peer != peers_.end()) {
          peer->second.last_heard = Clock::now();
        }
        for (auto& s : shards_) {
          if (s->join_identity == id) {
            s->last_heard = Clock::now();
            known = true;
          }
        }
        // A peer this learner does not know (it restarted, or dropped the shard) is told map
        // version 0, which never matches, so the peer joins again.
        const int64_t c[] = {counters_.updates, counters_.weights_version};
        wire::build_heartbeat(fbb_->fbb, wire::Role::Learner, "learner", known ? map_version_ : 0, c);
        if (join_.send_to(identity.bytes(), wire::bytes_of(fbb_->fbb), 0) && traffic != nullptr) {
          traffic->sent(wire::bytes_of(fbb_->fbb).size());
        }
        break;
      }
      case wire::Payload::EpisodeReport: {
        const auto* r = env->payload_as_EpisodeReport();
        // Only an actor that joined this learner reports episodes: anything else (a stray peer,
        // or an actor whose learner restarted, until it joins again) is counted and dropped.
        if (actor_index_.count(id) == 0) {
          if (counters_.episode_reports_refused++ % 1000 == 0) {
            log::warn("learner: episode report from a peer that has not joined as an actor, dropped ({} so far)",
                      counters_.episode_reports_refused);
          }
          break;
        }
        ++counters_.episodes;
        if (on_episode) {
          on_episode({r->actor_id(), r->return_(), r->steps(), r->status(), r->policy_version(), r->scripted()});
        }
        break;
      }
      case wire::Payload::MetricsUrlsRequest:
        wire::build_metrics_urls(fbb_->fbb, metrics_urls_);
        join_.send_to(identity.bytes(), wire::bytes_of(fbb_->fbb), 0);
        break;
      default: note_malformed("unexpected message type on the join socket"); break;
    }
  }
}

void LearnerServer::refresh_peers(bool drop_silent) {
  if (drop_silent) {
    std::erase_if(peers_, [&](const auto& p) { return ms_since(p.second.last_heard) > config_.peer_timeout_ms; });
  }
  counters_.actors_alive = std::count_if(peers_.begin(), peers_.end(), [](const auto& p) { return p.second.actor; });
  // The learner first, then shards, then actors, each sorted: a stable order for files and monitors.
  std::vector<std::string> urls;
  std::vector<std::string> actors;
  for (const auto& [id, peer] : peers_) {
    if (!peer.metrics_url.empty()) {
      (peer.actor ? actors : urls).push_back(peer.metrics_url);
    }
  }
  std::sort(urls.begin(), urls.end());
  std::sort(actors.begin(), actors.end());
  urls.insert(urls.end(), actors.begin(), actors.end());
  urls.erase(std::unique(urls.begin(), urls.end()), urls.end());
  if (!config_.metrics_url.empty()) {
    urls.insert(urls.begin(), config_.metrics_url);
  }
  if (urls != metrics_urls_) {
    metrics_urls_ = std::move(urls);
    if (on_metrics_urls) {
      on_metrics_urls(metrics_urls_);
    }
  }
}

void LearnerServer::request_samples(Shard& shard) {
  while (shard.in_flight < config_.requests_in_flight_per_shard) {
    const auto B = static_cast<uint32_t>(algorithm_.batch_size());
    wire::build_sample_request(fbb_->fbb, next_request_id_++, B, config_.clone_demos ? B : 0);
    if (!shard.dealer.send(wire::bytes_of(fbb_->fbb), 0)) {
      return;
    }
    if (shard.traffic != nullptr) {
      shard.traffic->sent(wire::bytes_of(fbb_->fbb).size());
    }
    ++shard.in_flight;
  }
}

namespace {
// A validated batch as the update reads it; `terminal` receives the 0/1 flags as floats.
BatchView view_of(const wire::TransitionRows& rows, std::vector<float>& terminal) {
  const auto B = static_cast<Eigen::Index>(rows.count);
  for (uint32_t i = 0; i < rows.count; ++i) {
    terminal[i] = rows.terminals[i] != 0 ? 1.0F : 0.0F;
  }
  return {
      Eigen::Map<const Eigen::MatrixXf>(rows.states, rows.obs_dim, B),
      Eigen::Map<const Eigen::MatrixXf>(rows.actions, rows.action_dim, B),
      Eigen::Map<const Eigen::VectorXf>(rows.rewards, B),
      Eigen::Map<const Eigen::MatrixXf>(rows.next_states, rows.obs_dim, B),
      Eigen::Map<const Eigen::VectorXf>(terminal.data(), B),
      Eigen::Map<const Eigen::VectorXf>(rows.mc_returns, B),
  };
}
}  // namespace

const Sample* LearnerServer::take_reply(Shard& shard) {
  net::Message& msg = reply_;  // reused: its aligned copy buffer grows once
  const auto obs = static_cast<uint32_t>(algorithm_.obs_dim());
  const auto act = static_cast<uint32_t>(algorithm_.output_width());
  const int B = algorithm_.batch_size();
  // At most one reply per call: the loop alternates shards and the join socket, so heartbeats
  // and episode reports are answered between updates.
  if (!shard.dealer.recv(msg, 0)) {
    return nullptr;
  }
  shard.in_flight = std::max(0, shard.in_flight - 1);
  shard.last_heard = Clock::now();
  if (shard.dealer.too_big(msg)) {
    if (shard.traffic != nullptr) {
      shard.traffic->refused_oversized(msg.size());
    }
    note_malformed("a shard's reply over its size limit, refused unread (pamdp_peer_frames_refused_for_size_total)");
    return nullptr;
  }
  if (shard.traffic != nullptr) {
    shard.traffic->received(msg.size());
  }
  const wire::Envelope* env = wire::open_envelope(msg.bytes());
  if (env == nullptr || env->payload_type() != wire::Payload::SampleReply) {
    note_malformed("shard reply is not a SampleReply");
    return nullptr;
  }
  const wire::TransitionBatch* b = env->payload_as_SampleReply()->batch();
  if (!wire::valid_batch(b, obs, act, static_cast<uint32_t>(B)) || b->count() != static_cast<uint32_t>(B)) {
    note_malformed("SampleReply with wrong sizes");
    return nullptr;
  }
  const wire::TransitionBatch* d = config_.clone_demos ? env->payload_as_SampleReply()->demos() : nullptr;
  if (d != nullptr &&
      (!wire::valid_batch(d, obs, act, static_cast<uint32_t>(B)) || d->count() != static_cast<uint32_t>(B))) {
    note_malformed("SampleReply with demonstrations of wrong sizes");
    return nullptr;
  }
  // Ask for the next batch before the caller updates, so the shard works while it does.
  request_samples(shard);
  sample_.batch.emplace(view_of(wire::rows_of(b), terminal_scratch_));
  sample_.demos.reset();
  if (d != nullptr) {
    sample_.demos.emplace(view_of(wire::rows_of(d), demo_terminal_scratch_));
    counters_.demo_samples_received += B;
  }
  ++counters_.updates;  // the caller updates on it at once
  counters_.samples_received += B;
  shard.samples += B;
  return &sample_;
}

void LearnerServer::drop_dead_shards() {
  const auto before = shards_.size();
  std::erase_if(shards_, [&](const auto& s) {
    if (ms_since(s->last_heard) > config_.peer_timeout_ms) {
      log::warn("learner: shard {} silent for {} ms; sampling from the others until it rejoins", s->insert_endpoint,
                ms_since(s->last_heard));
      return true;
    }
    return false;
  });
  if (shards_.size() != before) {
    shards_changed();
  }
}

void LearnerServer::shards_changed() {
  ++map_version_;
  counters_.shards = static_cast<int64_t>(shards_.size());
}

void LearnerServer::begin() {
  started_ = true;
  terminal_scratch_.assign(static_cast<size_t>(algorithm_.batch_size()), 0.0F);
  demo_terminal_scratch_.assign(static_cast<size_t>(algorithm_.batch_size()), 0.0F);
  start_ = Clock::now();
  last_tick_ = start_;
  waiting_since_ = Clock::now();
  last_published_at_ = algorithm_.updates();
  publish_weights();
  metrics_urls_.clear();
  if (!config_.metrics_url.empty()) {
    metrics_urls_.push_back(config_.metrics_url);
  }
  if (on_metrics_urls) {
    on_metrics_urls(metrics_urls_);
  }
  log::info("learner: join {} weights {}", join_endpoint_, weights_endpoint_);
}

bool LearnerServer::limit_reached() const {
  return stop_.load() || algorithm_.updates() >= config_.max_updates ||
         (config_.max_seconds > 0.0 &&
          std::chrono::duration<double>(Clock::now() - start_).count() >= config_.max_seconds);
}

void LearnerServer::end_round() {
  round_open_ = false;
  if (poller_.readable(0)) {
    handle_join_socket();
  }
  for (auto& s : shards_) {
    request_samples(*s);
  }
  drop_dead_shards();
  if (republish_at_ && Clock::now() >= *republish_at_) {
    republish_at_.reset();
    publish_weights();
  }
  // Waiting-for-data accounting: no batch in this round although we asked.
  if (!round_sampled_) {
    if (!waiting_) {
      waiting_ = true;
      waiting_since_ = Clock::now();
    }
  } else if (waiting_) {
    counters_.waiting_for_data_ms += ms_since(waiting_since_);
    waiting_ = false;
  }
  if (ms_since(last_tick_) >= 1000) {
    last_tick_ = Clock::now();
    refresh_peers(true);
    counters_.connections_refused = handshakes_.refused();
    if (waiting_) {
      counters_.waiting_for_data_ms += ms_since(waiting_since_);
      waiting_since_ = Clock::now();
    }
    if (on_tick) {
      on_tick(counters_);
    }
  }
}

const Sample* LearnerServer::next() {
  if (finished_) {
    return nullptr;
  }
  if (!started_) {
    begin();
  }
  // The caller updated on the previous sample: publish when it is time.
  if (algorithm_.updates() - last_published_at_ >= config_.publish_every_updates) {
    publish_weights();
  }
  for (;;) {
    if (limit_reached()) {
      finished_ = true;
      counters_.connections_refused = handshakes_.refused();
      publish_weights();
      return nullptr;
    }
    if (!round_open_) {
      if (poller_.size() != shards_.size() + 1 || poller_version_ != map_version_) {
        poller_.clear();
        poller_.add(join_);
        for (auto& s : shards_) {
          poller_.add(s->dealer);
        }
        poller_version_ = map_version_;
      }
      polled_ = shards_.size();
      poller_.poll(20);
      cursor_ = 0;
      round_open_ = true;
      round_sampled_ = false;
    }
    // Shards first, each once per round: handling the join socket may add or replace shards.
    while (cursor_ < polled_) {
      const size_t i = cursor_++;
      if (poller_.readable(i + 1)) {
        if (const Sample* s = take_reply(*shards_[i])) {
          round_sampled_ = true;
          return s;
        }
      }
    }
    end_round();
  }
}

void LearnerServer::run() {
  while (const std::optional<UpdateStats> stats = update_from(*this, algorithm_)) {
    if (on_update) {
      on_update(*stats);
    }
  }
}

}  // namespace pamdp
