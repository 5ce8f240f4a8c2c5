#include "replay/shard_server.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include "core/files.hpp"
#include "core/log.hpp"
#include "replay/replay_snapshot.hpp"

namespace pamdp {
namespace {

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "replay shard: %s\n", what);
  std::abort();
}

constexpr int64_t kMaxSampleRequestBytes = int64_t{64} << 10;
constexpr int64_t kMaxJoinReplyBytes = int64_t{16} << 20;  // the ClusterMap carries the config text
constexpr int kJoinSendHwm = 16;                           // stale heartbeats to a dead learner stay few
// Messages read from one socket before the loop looks at the others again (fairness between
// actors' inserts, the learner's requests and the join socket).
constexpr int kDrainBudget = 64;

// tcp://0.0.0.0:PORT (what ZeroMQ reports for tcp://*:0) becomes tcp://HOST:PORT.

// Throws std::runtime_error if a config from the learner cannot make a shard (the checks that
// would otherwise be hard checks in ReplayBuffer and RateLimiter).
void check_shard_config(const ShardConfig& c) {
  const RateLimiterConfig& l = c.limiter;
  if (c.capacity < 1 || c.demo_capacity < 0 || c.obs_dim < 1 || c.action_dim < 1 || c.heartbeat_ms < 1 ||
      c.peer_timeout_ms < 1 || !(l.samples_per_insert > 0.0) || !std::isfinite(l.samples_per_insert) ||
      l.min_size < 0 || l.slack < 0) {
    throw std::runtime_error(
        "the learner's config gives capacity " + std::to_string(c.capacity) + ", widths " + std::to_string(c.obs_dim) +
        "/" + std::to_string(c.action_dim) + ", heartbeat " + std::to_string(c.heartbeat_ms) + " ms, timeout " +
        std::to_string(c.peer_timeout_ms) + " ms, " + std::to_string(l.samples_per_insert) +
        " samples per insert, min size " + std::to_string(l.min_size) + ", slack " + std::to_string(l.slack) +
        "; capacity, widths and times must be >= 1, the ratio > 0 (check replay.*, cluster.* and env)");
  }
}

int64_t to_ms(std::chrono::steady_clock::duration d) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(d).count();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// ReplayShard

ReplayShard::ReplayShard(const ShardConfig& config, int max_sample_batch)
    : config_(config),
      max_sample_batch_(max_sample_batch),
      buffer_(config.capacity, config.obs_dim, config.action_dim),
      limiter_(config.limiter),
      rng_(config.seed),
      reply_(config.obs_dim, config.action_dim, std::max(max_sample_batch, 1)),
      terminals_(static_cast<size_t>(std::max(max_sample_batch, 1))) {
  if (max_sample_batch < 1) {
    throw std::invalid_argument("ReplayShard: max_sample_batch must be >= 1");
  }
  if (config.demo_capacity > 0) {
    demos_.emplace(config.demo_capacity, config.obs_dim, config.action_dim);
    demo_reply_.emplace(config.obs_dim, config.action_dim, max_sample_batch);
    demo_terminals_.resize(static_cast<size_t>(max_sample_batch));
  }
}

namespace {
void insert_rows(ReplayBuffer& buffer, const wire::TransitionRows& rows) {
  const size_t obs = rows.obs_dim;
  const size_t act = rows.action_dim;
  for (size_t i = 0; i < rows.count; ++i) {
    buffer.insert(TransitionView{{rows.states + i * obs, obs},
                                 {rows.actions + i * act, act},
                                 rows.rewards[i],
                                 {rows.next_states + i * obs, obs},
                                 rows.terminals[i] != 0,
                                 rows.mc_returns[i]});
  }
}

wire::TransitionRows sample_rows(ReplayBuffer& buffer, Rng& rng, int n, BatchBuffers& reply,
                                 std::vector<uint8_t>& terminals) {
  buffer.sample(rng, n, reply);
  for (int j = 0; j < n; ++j) {
    terminals[static_cast<size_t>(j)] = reply.terminal[static_cast<size_t>(j)] != 0.0F ? 1 : 0;
  }
  return {static_cast<uint32_t>(n),
          static_cast<uint32_t>(reply.obs_dim),
          static_cast<uint32_t>(reply.action_dim),
          reply.states.data(),
          reply.actions.data(),
          reply.rewards.data(),
          reply.next_states.data(),
          terminals.data(),
          reply.mc_returns.data()};
}
}  // namespace

bool ReplayShard::can_sample(int64_t n) const {
  if (n < 1 || n > max_sample_batch_) {
    misuse("can_sample: n outside [1, max_sample_batch]");
  }
  return buffer_.size() > 0 && limiter_.can_sample(n);
}

void ReplayShard::insert(const wire::TransitionRows& rows) {
  if (static_cast<int>(rows.obs_dim) != config_.obs_dim || static_cast<int>(rows.action_dim) != config_.action_dim) {
    misuse("insert: rows have other widths than the shard (validate with wire::valid_batch first)");
  }
  if (rows.count < 1 || !limiter_.can_insert(rows.count)) {
    misuse("insert: empty rows, or the rate limiter does not admit inserts now");
  }
  insert_rows(buffer_, rows);
  limiter_.on_insert(rows.count);
}

void ReplayShard::insert_demos(const wire::TransitionRows& rows) {
  if (!demos_ || static_cast<int>(rows.obs_dim) != config_.obs_dim ||
      static_cast<int>(rows.action_dim) != config_.action_dim || rows.count < 1) {
    misuse("insert_demos: no demonstration table, or rows of other widths or none");
  }
  insert_rows(*demos_, rows);
}

wire::TransitionRows ReplayShard::sample_demos(int n) {
  if (demo_size() == 0 || n < 1 || n > max_sample_batch_) {
    misuse("sample_demos: the demonstration table is empty or absent, or n is outside [1, max_sample_batch]");
  }
  return sample_rows(*demos_, rng_, n, *demo_reply_, demo_terminals_);
}

wire::TransitionRows ReplayShard::sample(int n) {
  if (!can_sample(n)) {
    misuse("sample: the shard is empty or the rate limiter does not admit this sample now");
  }
  limiter_.on_sample(n);
  return sample_rows(buffer_, rng_, n, reply_, terminals_);
}

void ReplayShard::load_snapshot(const std::string& path) {
  load_replay_snapshot(path, buffer_);
  if (demos_ && std::filesystem::exists(path + ".demos")) {
    load_replay_snapshot(path + ".demos", *demos_);
  }
  const int64_t inserts = buffer_.size();
  const double allowed = config_.limiter.samples_per_insert * static_cast<double>(inserts - config_.limiter.min_size);
  limiter_.set_counters(inserts, allowed > 0.0 ? static_cast<int64_t>(std::floor(allowed)) : 0);
}

void ReplayShard::save_snapshot(const std::string& path) const {
  save_replay_snapshot(path, buffer_);
  if (demos_) {
    save_replay_snapshot(path + ".demos", *demos_);
  }
}

void ReplayShard::set_limiter_config(const RateLimiterConfig& config) {
  RateLimiter next(config);
  next.set_counters(limiter_.inserts(), limiter_.samples());
  limiter_ = next;
  config_.limiter = config;
}

// ---------------------------------------------------------------------------------------------
// ShardServer

bool ShardServer::LogGate::open(Clock::time_point now) {
  if (last && now - *last < interval) {
    ++suppressed;
    return false;
  }
  last = now;
  return true;
}

ShardServer::ShardServer(net::Context& ctx, ShardServerOptions options, ShardConfigFromMap config_from_map)
    : options_(std::move(options)),
      config_from_map_(std::move(config_from_map)),
      insert_(ctx, net::SocketType::kRouter),
      sample_(ctx, net::SocketType::kRouter),
      join_(ctx, net::SocketType::kDealer),
      handshakes_(ctx, {&insert_, &sample_}, "replay shard '" + options_.name + "'") {
  if (!config_from_map_) {
    misuse("ShardServer needs a config_from_map function");
  }
  writers_.reserve(kMaxWriters);
  if (options_.join_endpoint.empty()) {
    throw std::runtime_error("replay shard: no learner join endpoint given (e.g. --join tcp://LEARNER:5555)");
  }
  if (options_.max_batch_transitions < 1 || options_.max_batch_transitions > (1U << 20)) {
    throw std::runtime_error("replay shard: max_batch_transitions must be in [1, 1048576]");
  }
  if (options_.join_retry_ms < 1 || options_.poll_ms < 1 || options_.insert_recv_hwm < 1 ||
      options_.max_insert_message_bytes < 1) {
    throw std::runtime_error(
        "replay shard: join_retry_ms, poll_ms, insert_recv_hwm and max_insert_message_bytes must be >= 1");
  }
  insert_.set_recv_hwm(options_.insert_recv_hwm);
  insert_.set_kernel_buffers(1 << 16, 1 << 16);  // small per-connection buffers; the actors window their sends
  insert_.set_max_message_bytes(options_.max_insert_message_bytes);
  sample_.set_max_message_bytes(kMaxSampleRequestBytes);
  sample_.set_router_mandatory(true);  // a reply to a vanished learner fails visibly (counted)
  join_.set_max_message_bytes(kMaxJoinReplyBytes);
  join_.set_send_hwm(kJoinSendHwm);
  if (options_.curve_server) {
    insert_.make_curve_server(*options_.curve_server);
    sample_.make_curve_server(*options_.curve_server);
  }
  if (options_.curve_client) {
    join_.make_curve_client(*options_.curve_client);
  }
  insert_endpoint_ = net::advertised_endpoint(insert_.bind(options_.insert_bind), options_.advertise_host);
  sample_endpoint_ = net::advertised_endpoint(sample_.bind(options_.sample_bind), options_.advertise_host);
  join_.connect(options_.join_endpoint);

  poll_all_.add(join_);
  poll_all_.add(insert_);
  poll_all_.add(sample_);
  poll_join_insert_.add(join_);
  poll_join_insert_.add(insert_);
  poll_join_sample_.add(join_);
  poll_join_sample_.add(sample_);
  poll_join_.add(join_);
  log_waiting_.interval = std::chrono::seconds(5);
}

ShardServer::~ShardServer() = default;

ShardCounters ShardServer::counters() const {
  constexpr auto r = std::memory_order_relaxed;
  ShardCounters c;
  c.inserted = inserted_.load(r);
  c.demo_inserted = demo_inserted_.load(r);
  c.sampled = sampled_.load(r);
  c.malformed = malformed_.load(r);
  c.requests_waiting = waiting_now_.load(r);
  c.insert_blocked_ms = blocked_ms_.load(r);
  c.replies_dropped = replies_dropped_.load(r);
  c.acks_dropped = acks_dropped_.load(r);
  c.size = size_.load(r);
  c.map_version = map_version_pub_.load(r);
  c.joins = joins_.load(r);
  c.transitions_dropped = transitions_dropped_.load(r);
  c.capacity = capacity_.load(r);
  c.inserts_held = inserts_held_pub_.load(r);
  c.restored = restored_.load(r);
  c.evicted = evicted_.load(r);
  c.batches_duplicate = batches_duplicate_.load(r);
  c.batches_stale = batches_stale_.load(r);
  c.connections_refused = handshakes_.refused();
  return c;
}

void ShardServer::run() {
  if (ran_) {
    misuse("ShardServer::run() called twice");
  }
  ran_ = true;
  log::info("replay shard '{}': inserts at {}, samples at {}; joining the learner at {}", options_.name,
            insert_endpoint_, sample_endpoint_, options_.join_endpoint);
  last_tick_ = Clock::now();
  next_join_ = last_tick_;
  next_snapshot_ = last_tick_ + std::chrono::milliseconds(options_.snapshot_every_ms);
  started_ = last_tick_;
  while (!stop_.load(std::memory_order_relaxed)) {
    Clock::time_point now = Clock::now();
    if (inserts_held_) {
      blocked_ += now - last_tick_;
    }
    last_tick_ = now;

    if (!joined_) {
      if (options_.join_timeout_ms > 0 && now - started_ >= std::chrono::milliseconds(options_.join_timeout_ms)) {
        throw std::runtime_error("no answer from the learner at " + options_.join_endpoint + " within " +
                                 std::to_string(options_.join_timeout_ms) +
                                 " ms; start `pamdp learner` first or check the address (--join tcp://HOST:PORT), or "
                                 "wait longer with --join-timeout");
      }
      if (now >= next_join_) {
        if (log_waiting_.open(now)) {
          log::info("replay shard '{}': waiting for the learner at {} to answer (JoinRequest every {} ms)",
                    options_.name, options_.join_endpoint, options_.join_retry_ms);
        }
        send_join(now);
      }
    } else {
      if (now >= next_heartbeat_) {
        send_heartbeat(now);
      }
      if (now - last_heard_learner_ > std::chrono::milliseconds(peer_timeout_ms_) && now >= next_join_) {
        if (!learner_silent_) {
          learner_silent_ = true;
          learner_->reconnected();  // counted when it goes silent; it answers again or stays silent
        }
        if (log_silent_.open(now)) {
          log::warn("replay shard '{}': no word from the learner for {} ms; joining again", options_.name,
                    to_ms(now - last_heard_learner_));
        }
        send_join(now);
      }
    }

    const bool read_inserts = shard_ != nullptr && shard_->can_insert(1);
    const bool read_samples = shard_ != nullptr && waiting_count_ < kMaxWaitingRequests;
    inserts_held_ = shard_ != nullptr && !read_inserts;
    net::Poller& poller =
        read_inserts ? (read_samples ? poll_all_ : poll_join_insert_) : (read_samples ? poll_join_sample_ : poll_join_);
    // The next timed duty: a heartbeat, or a JoinRequest (retrying before the first map, or once
    // the learner has been silent for peer_timeout_ms).
    Clock::time_point next_event = next_join_;
    if (joined_) {
      const Clock::time_point silent_at = last_heard_learner_ + std::chrono::milliseconds(peer_timeout_ms_);
      next_event = std::min(next_heartbeat_, std::max(next_join_, silent_at));
    }
    const int64_t timeout_ms = std::clamp<int64_t>(to_ms(next_event - now) + 1, 0, options_.poll_ms);
    if (poller.poll(static_cast<int>(timeout_ms)) > 0) {
      now = Clock::now();
      if (poller.readable(0)) {
        read_join_socket(now);
      }
      if (read_inserts && poller.readable(1)) {
        read_insert_socket(now);
      }
      if (read_samples && poller.readable(read_inserts ? 2 : 1)) {
        read_sample_socket(now);
      }
    }
    if (shard_ != nullptr) {
      serve_waiting_requests(Clock::now());
      if (options_.snapshot_every_ms > 0 && !options_.snapshot_path.empty() && Clock::now() >= next_snapshot_) {
        shard_->save_snapshot(options_.snapshot_path);
        next_snapshot_ = Clock::now() + std::chrono::milliseconds(options_.snapshot_every_ms);
      }
    }
    publish_counters();
  }
  if (inserts_held_) {
    blocked_ += Clock::now() - last_tick_;
  }
  publish_counters();
  if (shard_ != nullptr && !options_.snapshot_path.empty()) {
    shard_->save_snapshot(options_.snapshot_path);
    log::info("replay shard '{}': wrote {} transitions to {}", options_.name, shard_->buffer().size(),
              options_.snapshot_path);
  }
}

void ShardServer::send_join(Clock::time_point now) {
  wire::build_join_request(fbb_, wire::Role::Shard, options_.name, insert_endpoint_, sample_endpoint_, 0,
                           options_.metrics_url);
  if (join_.send(wire::bytes_of(fbb_), 0)) {  // a full queue means the learner is away: the retry covers it
    learner_->sent(wire::bytes_of(fbb_).size());
  }
  next_join_ = now + std::chrono::milliseconds(joined_ ? heartbeat_ms_ : options_.join_retry_ms);
}

void ShardServer::send_heartbeat(Clock::time_point now) {
  const ShardCounters c = counters();
  hb_counters_[kHbInserted] = c.inserted;
  hb_counters_[kHbSampled] = c.sampled;
  hb_counters_[kHbMalformed] = c.malformed;
  hb_counters_[kHbWaiting] = waiting_count_;
  hb_counters_[kHbBlockedMs] = to_ms(blocked_);
  hb_counters_[kHbSize] = shard_ != nullptr ? shard_->buffer().size() : 0;
  wire::build_heartbeat(fbb_, wire::Role::Shard, options_.name, map_version_, hb_counters_);
  if (join_.send(wire::bytes_of(fbb_), 0)) {
    learner_->sent(wire::bytes_of(fbb_).size());
  }
  next_heartbeat_ = now + std::chrono::milliseconds(heartbeat_ms_);
}

void ShardServer::read_join_socket(Clock::time_point now) {
  for (int i = 0; i < kDrainBudget && join_.recv(frame_, 0); ++i) {
    learner_silent_ = false;
    if (join_.too_big(frame_)) {
      learner_->refused_oversized(frame_.size());
      oversized(log_join_, "join", learner_->name, frame_.size(), join_.max_message_bytes(), now);
      continue;
    }
    learner_->received(frame_.size());
    const wire::Envelope* env = wire::open_envelope(frame_.bytes());
    if (env == nullptr) {
      malformed(log_join_, "join", "not a verified envelope of this schema", now);
      continue;
    }
    switch (env->payload_type()) {
      case wire::Payload::ClusterMap: take_cluster_map(*env->payload_as_ClusterMap(), now); break;
      case wire::Payload::Heartbeat: {
        last_heard_learner_ = now;
        const uint64_t learner_version = env->payload_as_Heartbeat()->map_version();
        // Another version means the map changed or the learner restarted: either way it may not
        // list this shard as it is now, so join again.
        if (joined_ && learner_version != map_version_ && now >= next_join_) {
          log::info("replay shard '{}': learner is at map version {}, this shard joined {}; joining again",
                    options_.name, learner_version, map_version_);
          send_join(now);
        }
        break;
      }
      default: malformed(log_join_, "join", "a payload the learner does not send to shards", now);
    }
  }
}

void ShardServer::take_cluster_map(const wire::ClusterMap& map, Clock::time_point now) {
  if (map.config_toml() == nullptr) {
    malformed(log_join_, "join", "ClusterMap without config_toml", now);
    return;
  }
  ShardConfig config;
  try {
    config = config_from_map_(map.config_toml()->str());
    check_shard_config(config);
  } catch (const std::exception& e) {
    if (shard_ == nullptr) {
      throw;  // nothing to serve with: a start-up error for the caller
    }
    // Already serving: keep the data and the settings, and say so (the next heartbeat answer
    // asks again, so this repeats at most once per second until the learner is fixed).
    if (log_join_.open(now)) {
      log::error("replay shard '{}': ignoring the learner's map version {}: {}; serving with the previous settings",
                 options_.name, map.version(), e.what());
    }
    return;
  }
  // Shards of one experiment share its seed; the endpoint keeps their sampling streams apart.
  config.seed ^= fnv1a64(insert_endpoint_.data(), insert_endpoint_.size());
  const int max_sample = static_cast<int>(options_.max_batch_transitions);
  if (shard_ == nullptr) {
    shard_ = std::make_unique<ReplayShard>(config, max_sample);
    if (!options_.snapshot_path.empty() && std::filesystem::exists(options_.snapshot_path)) {
      shard_->load_snapshot(options_.snapshot_path);
      restored_.store(static_cast<int64_t>(shard_->buffer().size()), std::memory_order_relaxed);
      log::info("replay shard '{}': restored {} transitions from {}", options_.name, shard_->buffer().size(),
                options_.snapshot_path);
    }
  } else if (config.capacity != shard_->config().capacity || config.obs_dim != shard_->config().obs_dim ||
             config.action_dim != shard_->config().action_dim) {
    log::warn(
        "replay shard '{}': the learner's new config changes capacity or widths ({}, {}/{} -> {}, {}/{}); "
        "dropping the {} stored transitions",
        options_.name, shard_->config().capacity, shard_->config().obs_dim, shard_->config().action_dim,
        config.capacity, config.obs_dim, config.action_dim, shard_->buffer().size());
    evicted_.fetch_add(static_cast<int64_t>(shard_->buffer().size()), std::memory_order_relaxed);
    shard_ = std::make_unique<ReplayShard>(config, max_sample);
    size_.store(0, std::memory_order_relaxed);
  } else if (!(config.limiter == shard_->config().limiter)) {
    shard_->set_limiter_config(config.limiter);
  }
  heartbeat_ms_ = config.heartbeat_ms;
  peer_timeout_ms_ = config.peer_timeout_ms;
  if (!joined_ || map.version() != map_version_) {
    log::info(
        "replay shard '{}': joined map version {}: capacity {}, widths {}/{}, {} samples per insert, min size {}, "
        "slack {}",
        options_.name, map.version(), config.capacity, config.obs_dim, config.action_dim,
        config.limiter.samples_per_insert, config.limiter.min_size, config.limiter.slack);
  }
  joined_ = true;
  map_version_ = map.version();
  last_heard_learner_ = now;
  next_join_ = now + std::chrono::milliseconds(heartbeat_ms_);
  next_heartbeat_ = now + std::chrono::milliseconds(heartbeat_ms_);
  joins_.fetch_add(1, std::memory_order_relaxed);
}

void ShardServer::read_insert_socket(Clock::time_point now) {
  const auto obs = static_cast<uint32_t>(shard_->config().obs_dim);
  const auto act = static_cast<uint32_t>(shard_->config().action_dim);
  for (int i = 0; i < kDrainBudget && shard_->can_insert(1) && insert_.recv_from(identity_, frame_, 0); ++i) {
    if (insert_.too_big(frame_)) {
      // Counted against its actor when it opens as a batch, and acknowledged with nothing stored
      // so that the actor's window moves on.
      const wire::Envelope* env = wire::open_envelope(frame_.bytes());
      const wire::TransitionBatch* batch = env != nullptr ? env->payload_as_TransitionBatch() : nullptr;
      net::PeerCounters& from = batch != nullptr ? actor_peer(batch->actor_id()) : peers_.peer("actor:?");
      from.refused_oversized(frame_.size());
      oversized(log_insert_, "insert", from.name, frame_.size(), insert_.max_message_bytes(), now);
      if (batch != nullptr) {
        acknowledge(batch->sequence(), 0);
        from.sent(ack_fbb_.GetSize());
      }
      continue;
    }
    const wire::Envelope* env = wire::open_envelope(frame_.bytes());
    if (env == nullptr) {
      malformed(log_insert_, "insert", "not a verified envelope of this schema", now);
      continue;
    }
    const wire::TransitionBatch* batch = env->payload_as_TransitionBatch();
    if (batch == nullptr) {
      malformed(log_insert_, "insert", "not a TransitionBatch", now);
      continue;
    }
    // Every batch read is acknowledged, stored or not, so that its actor's window moves on.
    net::PeerCounters& actor = actor_peer(batch->actor_id());
    actor.received(frame_.size());
    acknowledge(batch->sequence(), insert_batch(*batch, obs, act, now));
    actor.sent(ack_fbb_.GetSize());
  }
}

uint32_t ShardServer::insert_batch(const wire::TransitionBatch& batch, uint32_t obs, uint32_t act,
                                   Clock::time_point now) {
  if (!wire::valid_batch(&batch, obs, act, options_.max_batch_transitions)) {
    malformed(log_insert_, "insert", "TransitionBatch with wrong widths, sizes, count or non-finite values", now);
    return 0;
  }
  if (batch.table() == wire::kDemoTable) {
    if (!shard_->has_demo_table()) {
      malformed(log_insert_, "insert",
                "TransitionBatch for the demonstration table, and this run keeps none (ddpg.demo_bc_weight = 0)", now);
      return 0;
    }
    shard_->insert_demos(wire::rows_of(&batch));
    demo_inserted_.fetch_add(batch.count(), std::memory_order_relaxed);
    return batch.count();
  }
  if (batch.table() != wire::kReplayTable) {
    malformed(log_insert_, "insert", "TransitionBatch for a table that does not exist", now);
    return 0;
  }
  if (duplicate(batch.writer(), batch.sequence(), now)) {
    return 0;
  }
  const auto before = static_cast<int64_t>(shard_->buffer().size());
  shard_->insert(wire::rows_of(&batch));
  const auto after = static_cast<int64_t>(shard_->buffer().size());
  mark_stored(batch.writer(), batch.sequence());
  inserted_.fetch_add(batch.count(), std::memory_order_relaxed);
  evicted_.fetch_add(before + static_cast<int64_t>(batch.count()) - after, std::memory_order_relaxed);
  size_.store(after, std::memory_order_relaxed);
  return batch.count();
}

net::PeerCounters& ShardServer::actor_peer(uint32_t actor_id) {
  // "actor:#INDEX" (the learner's actor index; the learner names actors by host and pid), built
  // in a fixed buffer: the lookup allocates only the first time an actor is seen.
  std::array<char, 32> name{};
  const int n = std::snprintf(name.data(), name.size(), "actor:#%u", actor_id);
  return peers_.peer(std::string_view(name.data(), static_cast<size_t>(n)));
}

bool ShardServer::duplicate(uint64_t writer, uint64_t sequence, Clock::time_point now) {
  if (writer == 0) {
    return false;  // an actor from before TransitionBatch.writer
  }
  for (const WriterMark& m : writers_) {
    if (m.writer != writer) {
      continue;
    }
    if (sequence > m.newest) {
      return false;
    }
    const uint64_t d = m.newest - sequence;
    if (d >= kWindow) {
      const int64_t total = batches_stale_.fetch_add(1, std::memory_order_relaxed) + 1;
      if (log_duplicate_.open(now)) {
        log::warn(
            "replay shard '{}': refused a batch older than the deduplication window (writer {:016x}, "
            "sequence {}, newest {}); {} in all",
            options_.name, writer, sequence, m.newest, total);
      }
      return true;
    }
    if ((m.stored[d / 64] >> (d % 64) & 1U) == 0) {
      return false;  // a late first arrival
    }
    const int64_t total = batches_duplicate_.fetch_add(1, std::memory_order_relaxed) + 1;
    if (log_duplicate_.open(now)) {
      log::warn("replay shard '{}': refused a batch stored already (writer {:016x}, sequence {}); {} in all",
                options_.name, writer, sequence, total);
    }
    return true;
  }
  return false;
}

namespace {
// Shifts a window of bits (bit d of word d / 64) up by `by`: bit d moves to d + by, those past the
// end fall off.
template <size_t N>
void shift_window(std::array<uint64_t, N>& w, uint64_t by) {
  if (by >= 64 * N) {
    w.fill(0);
    return;
  }
  const size_t words = by / 64;
  const unsigned bits = by % 64;
  for (size_t i = N; i-- > 0;) {
    uint64_t v = i >= words ? w[i - words] << bits : 0;
    if (bits != 0 && i >= words + 1) {
      v |= w[i - words - 1] >> (64 - bits);
    }
    w[i] = v;
  }
}
}  // namespace

void ShardServer::mark_stored(uint64_t writer, uint64_t sequence) {
  if (writer == 0) {
    return;
  }
  ++batches_seen_;
  WriterMark* oldest = nullptr;
  for (WriterMark& m : writers_) {
    if (m.writer == writer) {
      if (sequence > m.newest) {
        shift_window(m.stored, sequence - m.newest);
        m.newest = sequence;
        m.stored[0] |= 1U;
      } else {
        const uint64_t d = m.newest - sequence;  // < kWindow: duplicate() let it through
        m.stored[d / 64] |= uint64_t{1} << (d % 64);
      }
      m.last_seen = batches_seen_;
      return;
    }
    if (oldest == nullptr || m.last_seen < oldest->last_seen) {
      oldest = &m;
    }
  }
  WriterMark fresh{writer, sequence, batches_seen_, {}};
  fresh.stored[0] = 1U;
  if (writers_.size() < kMaxWriters) {
    writers_.push_back(fresh);  // within the reserved capacity
  } else {
    *oldest = fresh;
  }
}

void ShardServer::acknowledge(uint64_t sequence, uint32_t inserted) {
  wire::build_insert_ack(ack_fbb_, sequence, inserted);
  // A ROUTER drops what it cannot route or queue; the next acknowledgement covers this one.
  if (!insert_.send_to(identity_.bytes(), wire::bytes_of(ack_fbb_), 0)) {
    acks_dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

void ShardServer::read_sample_socket(Clock::time_point now) {
  for (int i = 0; i < kDrainBudget && waiting_count_ < kMaxWaitingRequests && sample_.recv_from(identity_, frame_, 0);
       ++i) {
    if (sample_.too_big(frame_)) {
      learner_->refused_oversized(frame_.size());
      oversized(log_sample_, "sample", learner_->name, frame_.size(), sample_.max_message_bytes(), now);
      continue;
    }
    learner_->received(frame_.size());
    const wire::Envelope* env = wire::open_envelope(frame_.bytes());
    if (env == nullptr) {
      malformed(log_sample_, "sample", "not a verified envelope of this schema", now);
      continue;
    }
    const wire::SampleRequest* request = env->payload_as_SampleRequest();
    if (request == nullptr) {
      malformed(log_sample_, "sample", "not a SampleRequest", now);
      continue;
    }
    if (request->batch_size() < 1 || request->batch_size() > options_.max_batch_transitions ||
        request->demo_batch_size() > options_.max_batch_transitions) {
      malformed(log_sample_, "sample", "SampleRequest batch_size outside [1, max_batch_transitions]", now);
      continue;
    }
    if (identity_.size() < 1 || identity_.size() > WaitingRequest{}.identity.size()) {
      malformed(log_sample_, "sample", "routing id of an unexpected size", now);
      continue;
    }
    WaitingRequest& slot = waiting_[static_cast<size_t>((waiting_head_ + waiting_count_) % kMaxWaitingRequests)];
    std::copy_n(identity_.data(), identity_.size(), slot.identity.begin());
    slot.identity_size = static_cast<uint8_t>(identity_.size());
    slot.request_id = request->request_id();
    slot.batch_size = request->batch_size();
    slot.demo_batch_size = request->demo_batch_size();
    ++waiting_count_;
    waiting_now_.store(waiting_count_, std::memory_order_relaxed);
    serve_waiting_requests(now);
  }
}

void ShardServer::serve_waiting_requests(Clock::time_point now) {
  while (waiting_count_ > 0) {
    const WaitingRequest& head = waiting_[static_cast<size_t>(waiting_head_)];
    if (!shard_->can_sample(head.batch_size)) {
      return;
    }
    const wire::TransitionRows rows = shard_->sample(static_cast<int>(head.batch_size));
    if (head.demo_batch_size > 0 && shard_->demo_size() > 0) {
      const wire::TransitionRows demos = shard_->sample_demos(static_cast<int>(head.demo_batch_size));
      wire::build_sample_reply(fbb_, head.request_id, rows, &demos);
    } else {
      wire::build_sample_reply(fbb_, head.request_id, rows);
    }
    // Counted before the send, so that whoever holds the reply sees the counters that include it
    // (the slot stays untouched until the next push).
    sampled_.fetch_add(head.batch_size, std::memory_order_relaxed);
    waiting_head_ = (waiting_head_ + 1) % kMaxWaitingRequests;
    --waiting_count_;
    waiting_now_.store(waiting_count_, std::memory_order_relaxed);
    const bool queued = sample_.send_to({head.identity.data(), head.identity_size}, wire::bytes_of(fbb_), 0);
    if (queued) {
      learner_->sent(wire::bytes_of(fbb_).size());
    } else {
      replies_dropped_.fetch_add(1, std::memory_order_relaxed);
      transitions_dropped_.fetch_add(head.batch_size, std::memory_order_relaxed);
      if (log_reply_.open(now)) {
        log::warn("replay shard '{}': could not queue a SampleReply (the learner is gone or not reading); {} dropped",
                  options_.name, replies_dropped_.load(std::memory_order_relaxed));
      }
    }
  }
}

void ShardServer::malformed(LogGate& gate, const char* socket, const char* why, Clock::time_point now) {
  const int64_t total = malformed_.fetch_add(1, std::memory_order_relaxed) + 1;
  if (gate.open(now)) {
    log::warn(
        "replay shard '{}': dropped a malformed message on the {} socket ({}); {} malformed in all, {} more "
        "on this socket since the last line",
        options_.name, socket, why, total, gate.suppressed);
    gate.suppressed = 0;
  }
}

void ShardServer::oversized(LogGate& gate, const char* socket, const std::string& peer, size_t bytes, int64_t limit,
                            Clock::time_point now) {
  const int64_t total = malformed_.fetch_add(1, std::memory_order_relaxed) + 1;
  if (gate.open(now)) {
    log::warn(
        "replay shard '{}': refused a frame of {} bytes from {} on the {} socket, over its limit of {} bytes (a "
        "peer of another build or configuration, or not one of ours; the insert limit is the shard option "
        "max_insert_message_bytes); {} malformed in all, {} more on this socket since the last line",
        options_.name, bytes, peer, socket, limit, total, gate.suppressed);
    gate.suppressed = 0;
  }
}

void ShardServer::publish_counters() {
  constexpr auto r = std::memory_order_relaxed;
  waiting_now_.store(waiting_count_, r);
  blocked_ms_.store(to_ms(blocked_), r);
  size_.store(shard_ != nullptr ? shard_->buffer().size() : 0, r);
  map_version_pub_.store(static_cast<int64_t>(map_version_), r);
  capacity_.store(shard_ != nullptr ? shard_->config().capacity : 0, r);
  inserts_held_pub_.store(inserts_held_ ? 1 : 0, r);
}

}  // namespace pamdp
