#include "actor/actor_loop.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "actor/acting_policy.hpp"
#include "actor/episode_player.hpp"
#include "core/log.hpp"
#include "core/rng.hpp"
#include "core/wire.hpp"
#include "replay/episode_buffer.hpp"

namespace pamdp {
namespace {

// A nonzero random 64-bit id (0 means "no writer" on the wire).
uint64_t draw_writer_id() {
  std::random_device rd;
  const uint64_t high = rd();
  const uint64_t low = rd();
  const uint64_t id =
      (high << 32U) ^ low ^ static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  return id == 0 ? 1 : id;
}

using Clock = std::chrono::steady_clock;

constexpr int64_t kMaxWeightsBytes = int64_t{64} << 20;  // 16M parameters
constexpr int64_t kMaxShardMessageBytes = 64 << 10;      // shards send actors InsertAcks only
constexpr int kMaxLayerWidth = 1 << 16;
// Control sockets (weights, learner answers) are looked at this often: often enough that new
// weights apply within a millisecond, rarely enough that the poll syscalls cost nothing per step.
constexpr auto kControlPeriod = std::chrono::milliseconds(1);
// Messages taken from one control socket per look, so that a flooding peer cannot hold the env
// loop; the rest wait for the next look.
constexpr int kMaxMessagesPerLook = 64;

int64_t ms_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(to - from).count();
}

size_t area(int rows, int width) {
  return static_cast<size_t>(rows) * static_cast<size_t>(width);
}

// Rows of the next TransitionBatch, row-major as the wire wants them.
class OutgoingBatch {
 public:
  OutgoingBatch(int capacity, int obs, int act)
      : obs_(static_cast<size_t>(obs)),
        act_(static_cast<size_t>(act)),
        states_(area(capacity, obs)),
        next_(area(capacity, obs)),
        actions_(area(capacity, act)),
        rewards_(static_cast<size_t>(capacity)),
        returns_(static_cast<size_t>(capacity)),
        terminals_(static_cast<size_t>(capacity)) {}

  [[nodiscard]] bool empty() const { return n_ == 0; }
  [[nodiscard]] bool full() const { return n_ == rewards_.size(); }
  void clear() { n_ = 0; }

  void append(const TransitionView& t) {
    std::copy(t.state.begin(), t.state.end(), states_.begin() + static_cast<ptrdiff_t>(n_ * obs_));
    std::copy(t.next_state.begin(), t.next_state.end(), next_.begin() + static_cast<ptrdiff_t>(n_ * obs_));
    std::copy(t.action.begin(), t.action.end(), actions_.begin() + static_cast<ptrdiff_t>(n_ * act_));
    rewards_[n_] = t.reward;
    returns_[n_] = t.mc_return;
    terminals_[n_] = t.terminal ? 1 : 0;
    ++n_;
  }

  [[nodiscard]] wire::TransitionRows rows() const {
    return {static_cast<uint32_t>(n_),
            static_cast<uint32_t>(obs_),
            static_cast<uint32_t>(act_),
            states_.data(),
            actions_.data(),
            rewards_.data(),
            next_.data(),
            terminals_.data(),
            returns_.data()};
  }

 private:
  size_t obs_, act_;
  size_t n_ = 0;
  std::vector<float> states_, next_, actions_, rewards_, returns_;
  std::vector<uint8_t> terminals_;
};

// A team game's teachers, one per player (none without demonstrations).
std::vector<std::unique_ptr<Policy>> make_teachers(const Env& env,
                                                   const std::function<std::unique_ptr<Policy>()>& make) {
  std::vector<std::unique_ptr<Policy>> out;
  if (make) {
    for (int i = 0; i < env.agents(); ++i) {
      out.push_back(make());
    }
  }
  return out;
}

struct EnvSlot {
  std::unique_ptr<Env> env;
  std::vector<std::unique_ptr<Policy>> teachers;  // with demonstrations, one per player
  EpisodePlayer player;                           // its episodes, played as `pamdp train` plays them
  uint64_t seed = 0;
  uint64_t episodes = 0;

  EnvSlot(std::unique_ptr<Env> e, const std::function<std::unique_ptr<Policy>()>& make_teacher, bool labels, uint64_t s)
      : env(std::move(e)), teachers(make_teachers(*env, make_teacher)), player(*env, teachers, labels), seed(s) {}
};

// The sequences of the batches sent to one shard and not yet acknowledged, oldest first: a ring
// of fixed capacity (cluster.actor_batches_in_flight), allocated when the shard is connected.
class AckWindow {
 public:
  explicit AckWindow(int capacity) : seq_(static_cast<size_t>(capacity)) {}
  [[nodiscard]] bool full() const { return count_ == seq_.size(); }
  [[nodiscard]] bool empty() const { return count_ == 0; }
  [[nodiscard]] size_t size() const { return count_; }
  void push(uint64_t sequence) {
    seq_[(head_ + count_) % seq_.size()] = sequence;
    ++count_;
  }
  void pop_oldest() {
    head_ = (head_ + 1) % seq_.size();
    --count_;
  }
  void clear() { head_ = count_ = 0; }
  // An InsertAck for `sequence` covers it and every earlier batch (one connection is in order).
  // Returns how many batches it retired.
  size_t acknowledge(uint64_t sequence) {
    size_t n = 0;
    while (count_ > 0 && seq_[head_] <= sequence) {
      pop_oldest();
      ++n;
    }
    return n;
  }

 private:
  std::vector<uint64_t> seq_;
  size_t head_ = 0;
  size_t count_ = 0;
};

struct Shard {
  std::string endpoint;
  net::Socket dealer;
  net::DisconnectWatch connection;  // a lost connection took the unacknowledged batches with it
  AckWindow unacked;
  Clock::time_point last_progress;                 // the last acknowledgement, or the send into an empty window
  std::optional<Clock::time_point> blocked_since;  // first failed send of the current stall
  std::optional<Clock::time_point> skipped_until;  // out of the rotation until then, then probed
  net::PeerCounters* peer = nullptr;               // its traffic (ActorCounters::peers)

  Shard(net::Context& ctx, std::string ep, int window)
      : endpoint(std::move(ep)), dealer(ctx, net::SocketType::kDealer), connection(ctx, dealer), unacked(window) {}
  [[nodiscard]] bool available(Clock::time_point now) const { return !skipped_until || now >= *skipped_until; }
};

const Env& first_env(const std::vector<std::unique_ptr<Env>>& envs) {
  if (envs.empty() || envs.front() == nullptr) {
    throw std::invalid_argument("ActorLoop: needs at least one env");
  }
  const Env& first = *envs.front();
  for (const auto& e : envs) {
    if (e == nullptr || e->observation_size() != first.observation_size() ||
        e->action_space().output_width() != first.action_space().output_width() ||
        e->action_space().num_actions() != first.action_space().num_actions() || e->agents() != first.agents()) {
      throw std::invalid_argument("ActorLoop: every env must have the same observation size, action space and players");
    }
  }
  if (first.max_episode_steps() < 1) {
    throw std::invalid_argument("ActorLoop: env max_episode_steps() must be at least 1");
  }
  return first;
}

ActorLoopConfig checked(ActorLoopConfig c) {
  if (c.batch_transitions < 1) {
    throw std::invalid_argument("ActorLoop: batch_transitions must be at least 1");
  }
  if (!(c.gamma >= 0.0 && c.gamma <= 1.0)) {
    throw std::invalid_argument("ActorLoop: gamma must lie in [0, 1]");
  }
  if (c.exploration.demo_fraction > 0.0 && !c.make_teacher) {
    throw std::invalid_argument("ActorLoop: exploration.demo_fraction > 0 needs a teacher (make_teacher)");
  }
  if (c.exploration.demo_relabel && !(c.demo_table && c.make_teacher)) {
    throw std::invalid_argument("ActorLoop: exploration.demo_relabel needs the demonstration table and a teacher");
  }
  if (c.batches_in_flight < 1 || c.batches_in_flight > 1024) {
    throw std::invalid_argument("ActorLoop: batches_in_flight must be within [1, 1024]");
  }
  if (c.heartbeat_ms < 1 || c.peer_timeout_ms < 1 || c.send_attempt_ms < 1 || c.tick_ms < 1 || c.shard_send_hwm < 1) {
    throw std::invalid_argument(
        "ActorLoop: heartbeat_ms, peer_timeout_ms, send_attempt_ms, tick_ms and shard_send_hwm must be positive");
  }
  return c;
}

}  // namespace

struct ActorLoop::Impl {
  Impl(net::Context& ctx, LearnerLink link, const ClusterInfo& map, std::vector<std::unique_ptr<Env>> env_list,
       ActorLoopConfig config, ActorCounters& counters);

  void run(const std::atomic<bool>& stop, const std::function<void(const ActorCounters&, double)>& on_tick,
           const std::function<void(int, double, int)>& on_episode);

  void step(EnvSlot& slot);
  void finish_episode(EnvSlot& slot, int status);
  void reset(EnvSlot& slot);

  void send_batch(OutgoingBatch& b, uint8_t table);
  // Appends an episode whose returns are computed, sending every batch it fills.
  void add_rows(const EpisodeBuffer& ep, OutgoingBatch& b, uint8_t table);
  bool try_send(size_t index, std::span<const uint8_t> bytes, int timeout_ms, OutgoingBatch& b);
  Shard* pick_shard(Clock::time_point now);
  [[nodiscard]] bool another_available(size_t index, Clock::time_point now) const;
  void final_flush();

  void serve_control(Clock::time_point now);
  void poll_weights();
  const wire::PolicyWeights* check_weights(std::span<const uint8_t> bytes);
  void apply_weights(const wire::PolicyWeights* w);
  void poll_learner(Clock::time_point now);
  void apply_map(const ClusterInfo& map);
  void heartbeat(Clock::time_point now);
  void read_acks();
  // Waits up to send_attempt_ms for an InsertAck (the shard in turn has a full window, or every
  // shard is skipped).
  void wait_for_acks();
  void heard_learner(Clock::time_point now);
  void update_epsilon();
  void note_malformed(const char* what);

  net::Context& ctx;
  ActorLoopConfig config;
  ActorCounters& counters;
  LearnerLink link;

  // Shapes, fixed by the envs.
  int obs_dim;
  int width;
  const ActionSpace& space;
  uint32_t actor_index;

  // The cluster as the newest map describes it.
  uint64_t map_version = 0;
  uint32_t num_actors_hint = 0;
  std::string weights_endpoint;
  std::vector<Shard> shards;
  net::Poller shard_poller;  // every shard's DEALER, rebuilt with the map
  size_t next_shard = 0;
  net::Socket sub;
  std::array<net::Message, 2> weights_msg;  // newest valid one and the one being received
  net::Message junk;
  ClusterInfo incoming_map;

  // Acting.
  std::vector<EnvSlot> envs;
  EpsilonGreedy explore;
  std::unique_ptr<ActingPolicy> policy;  // null until the first PolicyWeights
  std::string policy_algorithm;          // the algorithm `policy` plays
  // Built by check_weights for a message naming another algorithm than `policy`'s, taken by
  // apply_weights; and the networks of the message being checked or applied.
  std::unique_ptr<ActingPolicy> pending_policy;
  std::string pending_algorithm;
  std::vector<NetworkView> weights_networks;
  EpisodePlayer::Act act;  // the acting policy's output (empty until the first weights)
  uint64_t weights_version = 0;
  int64_t updates = 0;
  double eps = 1.0;

  // Sending.
  OutgoingBatch batch;
  std::optional<OutgoingBatch> demo_batch;  // for the demonstration table (config.demo_table)
  flatbuffers::FlatBufferBuilder batch_fbb;
  uint64_t sequence = 0;
  // This process's id on its batches (TransitionBatch.writer): shards store a batch once. Drawn
  // from the OS, not the seed: two actors started with one seed must still differ.
  const uint64_t writer = draw_writer_id();

  // Timing and state of the control plane.
  const std::atomic<bool>* stop = nullptr;
  const std::function<void(const ActorCounters&, double)>* on_tick = nullptr;
  const std::function<void(int, double, int)>* on_episode = nullptr;
  Clock::time_point next_control, next_heartbeat, next_tick, learner_heard, rejoin_sent, last_malformed_log;
  bool rejoin_pending = false;
  bool learner_silent = false;
  net::PeerCounters* learner_peer = &counters.peers.peer("learner");
  bool waiting_for_shards_logged = false;
};

ActorLoop::Impl::Impl(net::Context& c, LearnerLink l, const ClusterInfo& map,
                      std::vector<std::unique_ptr<Env>> env_list, ActorLoopConfig cfg, ActorCounters& cnt)
    : ctx(c),
      config(checked(std::move(cfg))),
      counters(cnt),
      link(std::move(l)),
      obs_dim(first_env(env_list).observation_size()),
      width(env_list.front()->action_space().output_width()),
      space(env_list.front()->action_space()),
      actor_index(map.actor_index),
      sub(ctx, net::SocketType::kSub),
      explore(env_list.front()->action_space(), config.exploration,
              mix_seeds(config.seed, 1000 + uint64_t{map.actor_index})),
      batch(config.batch_transitions, obs_dim, width),
      batch_fbb(static_cast<size_t>(config.batch_transitions) * (2 * area(1, obs_dim) + area(1, width) + 3) * 4 +
                1024) {
  const uint64_t actor_seed = mix_seeds(config.seed, 2000 + uint64_t{actor_index});
  envs.reserve(env_list.size());
  for (size_t k = 0; k < env_list.size(); ++k) {
    envs.emplace_back(std::move(env_list[k]), config.make_teacher, config.exploration.demo_relabel,
                      mix_seeds(actor_seed, k));
  }
  if (config.demo_table) {
    demo_batch.emplace(config.batch_transitions, obs_dim, width);
  }
  sub.set_max_message_bytes(kMaxWeightsBytes);
  sub.set_recv_hwm(4);  // only the newest weights matter
  if (config.curve) {
    sub.make_curve_client(*config.curve);
  }
  sub.subscribe_all();
  counters.malformed_messages.fetch_add(link.malformed_during_join(), std::memory_order_relaxed);
  link.count_traffic(learner_peer);
  apply_map(map);
}

// ---------------------------------------------------------------------------------------------
// Acting

void ActorLoop::Impl::run(const std::atomic<bool>& stop_flag,
                          const std::function<void(const ActorCounters&, double)>& tick,
                          const std::function<void(int, double, int)>& episode_end) {
  stop = &stop_flag;
  on_tick = &tick;
  on_episode = &episode_end;
  const auto now = Clock::now();
  next_control = now;
  next_heartbeat = now;
  next_tick = now + std::chrono::milliseconds(config.tick_ms);
  learner_heard = now;
  for (EnvSlot& slot : envs) {
    reset(slot);
  }
  log::info("actor {}: stepping {} {} env(s), {} shard(s), batches of {} transitions", actor_index, envs.size(),
            envs.front().env->name(), shards.size(), config.batch_transitions);
  size_t k = 0;
  while (!stop_flag.load(std::memory_order_relaxed)) {
    const auto t = Clock::now();
    if (t >= next_control) {
      serve_control(t);
    }
    if (policy == nullptr && !config.exploration.uniform_random_params) {
      // Its random steps play the network's parameters, which it has not got yet.
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    step(envs[k]);
    k = k + 1 == envs.size() ? 0 : k + 1;
  }
  final_flush();
  log::info("actor {}: stopped after {} env steps, {} episodes, {} batches", actor_index, counters.env_steps.load(),
            counters.episodes.load(), counters.batches_sent.load());
  stop = nullptr;
  on_tick = nullptr;
  on_episode = nullptr;
}

void ActorLoop::Impl::reset(EnvSlot& slot) {
  const ExplorationConfig& x = config.exploration;
  slot.env->set_training_updates(updates);
  slot.player.begin(mix_seeds(slot.seed, slot.episodes),
                    demo_share(updates, x.demo_fraction, x.demo_anneal_updates, x.demo_fraction_end), explore.rng());
}

void ActorLoop::Impl::step(EnvSlot& slot) {
  const StepResult sr = slot.player.step(act, explore, eps);
  // One decision per player: a team's cycle is agents() steps.
  counters.env_steps.fetch_add(slot.player.players(), std::memory_order_relaxed);
  if (slot.player.ended()) {
    finish_episode(slot, sr.status);
  }
}

void ActorLoop::Impl::finish_episode(EnvSlot& slot, int status) {
  // The last step is terminal, time-outs included, as in the paper's code and `pamdp train`.
  // Returns are computed once per buffer; a demonstration's rows go to both tables.
  // A team's players each send their own episode.
  EpisodePlayer& p = slot.player;
  for (int i = 0; i < p.players(); ++i) {
    p.episode(i).compute_returns(config.gamma);
    add_rows(p.episode(i), batch, wire::kReplayTable);
    if (p.demo() && demo_batch) {
      add_rows(p.episode(i), *demo_batch, wire::kDemoTable);
    }
    if (EpisodeBuffer* labels = p.labels(i)) {
      labels->compute_returns(config.gamma);
      add_rows(*labels, *demo_batch, wire::kDemoTable);
    }
  }
  // The ended episode goes out now, in a partial batch if need be, as `pamdp train` puts each
  // episode into its replay when it ends. Held back until a batch filled, the rows of episodes a
  // few steps long reached the learner up to a batch's worth of steps late, and MP-DQN on Goal
  // fell into shooting at once far more often (docs/results.md, "Goal and Platform on the
  // cluster").
  if (!batch.empty()) {
    send_batch(batch, wire::kReplayTable);
  }
  if (demo_batch && !demo_batch->empty()) {
    send_batch(*demo_batch, wire::kDemoTable);
  }
  ++slot.episodes;
  const int64_t episode = counters.episodes.fetch_add(1, std::memory_order_relaxed) + 1;
  if (!link.send_episode_report(actor_index, static_cast<uint64_t>(episode), p.episode_return(),
                                static_cast<uint32_t>(p.steps()), status, p.demo() ? 0 : weights_version, p.demo())) {
    counters.reports_dropped.fetch_add(1, std::memory_order_relaxed);
  }
  if (on_episode != nullptr && *on_episode && !p.demo()) {
    (*on_episode)(status, p.episode_return(), p.steps());
  }
  reset(slot);
}

// ---------------------------------------------------------------------------------------------
// Sending

Shard* ActorLoop::Impl::pick_shard(Clock::time_point now) {
  for (size_t j = 0; j < shards.size(); ++j) {
    const size_t i = (next_shard + j) % shards.size();
    if (shards[i].available(now)) {
      next_shard = i;
      return &shards[i];
    }
  }
  return nullptr;
}

bool ActorLoop::Impl::another_available(size_t index, Clock::time_point now) const {
  for (size_t i = 0; i < shards.size(); ++i) {
    if (i != index && shards[i].available(now)) {
      return true;
    }
  }
  return false;
}

// One send attempt to shards[index]; on success the batch is gone and the rotation moves on.
bool ActorLoop::Impl::try_send(size_t index, std::span<const uint8_t> bytes, int timeout_ms, OutgoingBatch& b) {
  Shard& s = shards[index];
  if (!s.dealer.send(bytes, timeout_ms)) {
    return false;
  }
  s.peer->sent(bytes.size());
  if (s.skipped_until) {
    log::info("actor {}: shard {} accepts batches again", actor_index, s.endpoint);
  }
  if (s.unacked.empty()) {
    s.last_progress = Clock::now();
  }
  if (s.unacked.full()) {
    s.unacked.pop_oldest();  // the final flush's send past the window
  }
  s.unacked.push(sequence);
  s.blocked_since.reset();
  s.skipped_until.reset();
  next_shard = (index + 1) % shards.size();
  ++sequence;
  counters.batches_sent.fetch_add(1, std::memory_order_relaxed);
  counters.transitions_sent.fetch_add(b.rows().count, std::memory_order_relaxed);
  b.clear();
  return true;
}

// Blocks (serving the control sockets) until a shard takes the batch or stop is set, in which
// case the batch is dropped.
void ActorLoop::Impl::add_rows(const EpisodeBuffer& ep, OutgoingBatch& b, uint8_t table) {
  for (size_t i = 0; i < ep.size(); ++i) {
    b.append(ep.transition(i));
    if (b.full()) {
      send_batch(b, table);
    }
  }
}

void ActorLoop::Impl::send_batch(OutgoingBatch& b, uint8_t table) {
  wire::build_transition_batch(batch_fbb, actor_index, sequence, b.rows(), table, writer);
  const std::span<const uint8_t> bytes = wire::bytes_of(batch_fbb);
  while (!stop->load(std::memory_order_relaxed)) {
    const auto now = Clock::now();
    if (now >= next_control) {
      serve_control(now);
    }
    read_acks();
    Shard* target = pick_shard(now);
    if (target == nullptr) {
      if (shards.empty()) {
        if (!waiting_for_shards_logged) {
          log::warn("actor {}: no replay shard in the cluster map; holding the batch until one joins", actor_index);
          waiting_for_shards_logged = true;
        }
        link.wait_readable(config.send_attempt_ms);
        counters.send_blocked_ms.fetch_add(ms_between(now, Clock::now()), std::memory_order_relaxed);
        continue;
      }
      // Every shard skipped or its window full: probe the skipped ones that have room, then wait
      // for acknowledgements (backpressure: the shards' rate limiters hold them back).
      for (size_t j = 0; j < shards.size(); ++j) {
        const size_t i = (next_shard + j) % shards.size();
        if (!shards[i].unacked.full() && try_send(i, bytes, 0, b)) {
          return;
        }
      }
      wait_for_acks();
      counters.send_blocked_ms.fetch_add(ms_between(now, Clock::now()), std::memory_order_relaxed);
      continue;
    }
    if (target->unacked.full()) {
      // Its turn, and its window is full: the shard's rate limiter holds inserts back. As with a
      // full queue, a shard that answers nothing for a whole peer timeout while another could
      // take the batch is skipped for a peer timeout.
      if (ms_between(target->last_progress, now) >= config.peer_timeout_ms && another_available(next_shard, now)) {
        log::info("actor {}: shard {} has acknowledged none of its {} batches for {} ms; sending to the others",
                  actor_index, target->endpoint, target->unacked.size(), ms_between(target->last_progress, now));
        target->skipped_until = now + std::chrono::milliseconds(config.peer_timeout_ms);
        target->last_progress = now;
        next_shard = (next_shard + 1) % shards.size();
        continue;
      }
      wait_for_acks();
      counters.send_blocked_ms.fetch_add(ms_between(now, Clock::now()), std::memory_order_relaxed);
      continue;
    }
    const size_t index = next_shard;
    const bool probing = target->skipped_until.has_value();
    if (try_send(index, bytes, probing ? 0 : config.send_attempt_ms, b)) {
      return;
    }
    const auto after = Clock::now();
    counters.send_blocked_ms.fetch_add(ms_between(now, after), std::memory_order_relaxed);
    if (probing) {
      target->skipped_until = after + std::chrono::milliseconds(config.peer_timeout_ms);
      continue;
    }
    if (!target->blocked_since) {
      target->blocked_since = now;
    }
    // A full queue is backpressure and we wait; but if this shard takes nothing for a whole peer
    // timeout while another could, it is probably gone: skip it (the learner drops a dead shard
    // from the map within the same timeout, and then we disconnect it for good).
    if (ms_between(*target->blocked_since, after) >= config.peer_timeout_ms && another_available(index, after)) {
      log::warn("actor {}: shard {} has taken no batch for {} ms; sending to the other shards", actor_index,
                target->endpoint, ms_between(*target->blocked_since, after));
      target->blocked_since.reset();
      target->skipped_until = after + std::chrono::milliseconds(config.peer_timeout_ms);
      next_shard = (index + 1) % shards.size();
    }
  }
  b.clear();
}

void ActorLoop::Impl::wait_for_acks() {
  if (shard_poller.poll(config.send_attempt_ms) > 0) {
    read_acks();
  }
}

void ActorLoop::Impl::read_acks() {
  for (Shard& s : shards) {
    const int disconnects = s.connection.take();
    if (disconnects > 0 && !s.unacked.empty()) {
      // The shard's end of the connection died (killed, or restarted on the same endpoint): what
      // it had not acknowledged is gone, and it will not be acknowledged.
      log::warn("actor {}: lost the connection to shard {}; its {} unacknowledged batches are lost", actor_index,
                s.endpoint, s.unacked.size());
      counters.batches_lost.fetch_add(static_cast<int64_t>(s.unacked.size()), std::memory_order_relaxed);
      s.unacked.clear();
    }
    for (int n = 0; n < disconnects; ++n) {
      s.peer->reconnected();  // libzmq connects again by itself
    }
    for (int n = 0; n < kMaxMessagesPerLook && s.dealer.recv(junk, 0); ++n) {
      if (s.dealer.too_big(junk)) {
        s.peer->refused_oversized(junk.size());
        note_malformed("a shard sent a frame over the size limit of an InsertAck");
        continue;
      }
      s.peer->received(junk.size());
      const wire::Envelope* env = wire::open_envelope(junk.bytes());
      if (env == nullptr || env->payload_type() != wire::Payload::InsertAck) {
        note_malformed("a shard sent something other than an InsertAck");
        continue;
      }
      counters.transitions_acknowledged.fetch_add(env->payload_as_InsertAck()->inserted(), std::memory_order_relaxed);
      const size_t retired = s.unacked.acknowledge(env->payload_as_InsertAck()->sequence());
      if (retired > 0) {
        s.last_progress = Clock::now();
        counters.batches_acknowledged.fetch_add(static_cast<int64_t>(retired), std::memory_order_relaxed);
      }
    }
  }
}

void ActorLoop::Impl::final_flush() {
  const auto flush = [&](OutgoingBatch& b, uint8_t table) {
    if (b.empty()) {
      return;
    }
    wire::build_transition_batch(batch_fbb, actor_index, sequence, b.rows(), table, writer);
    for (size_t j = 0; j < shards.size(); ++j) {
      if (try_send((next_shard + j) % shards.size(), wire::bytes_of(batch_fbb), config.send_attempt_ms, b)) {
        return;
      }
    }
    b.clear();
  };
  flush(batch, wire::kReplayTable);
  if (demo_batch) {
    flush(*demo_batch, wire::kDemoTable);
  }
}

// ---------------------------------------------------------------------------------------------
// Control plane

void ActorLoop::Impl::serve_control(Clock::time_point now) {
  next_control = now + kControlPeriod;
  poll_weights();
  poll_learner(now);
  counters.weights_age_updates.store(policy != nullptr ? std::max<int64_t>(0, link.learner_updates() - updates) : 0,
                                     std::memory_order_relaxed);
  if (now >= next_heartbeat) {
    heartbeat(now);
    next_heartbeat = now + std::chrono::milliseconds(config.heartbeat_ms);
  }
  if (now >= next_tick) {
    next_tick = now + std::chrono::milliseconds(config.tick_ms);
    if (on_tick != nullptr && *on_tick) {
      (*on_tick)(counters, eps);
    }
  }
}

void ActorLoop::Impl::note_malformed(const char* what) {
  const int64_t n = counters.malformed_messages.fetch_add(1, std::memory_order_relaxed) + 1;
  const auto now = Clock::now();
  if (n == 1 || ms_between(last_malformed_log, now) >= 1000) {
    last_malformed_log = now;
    log::warn("actor {}: dropped a malformed message ({}); {} so far", actor_index, what, n);
  }
}

const wire::PolicyWeights* ActorLoop::Impl::check_weights(std::span<const uint8_t> bytes) {
  const wire::Envelope* env = wire::open_envelope(bytes);
  if (env == nullptr || env->payload_type() != wire::Payload::PolicyWeights) {
    note_malformed("weights socket: not a verified PolicyWeights");
    return nullptr;
  }
  const wire::PolicyWeights* w = env->payload_as_PolicyWeights();
  std::string_view algorithm;
  weights_networks = wire::policy_networks(*w, algorithm);
  if (weights_networks.empty()) {
    note_malformed("PolicyWeights: no networks");
    return nullptr;
  }
  for (const NetworkView& n : weights_networks) {
    if (n.widths.size() < 2) {
      note_malformed("PolicyWeights: a network with fewer than two layer widths");
      return nullptr;
    }
    int64_t expected = 0;
    for (size_t l = 0; l < n.widths.size(); ++l) {
      if (n.widths[l] < 1 || n.widths[l] > kMaxLayerWidth) {
        note_malformed("PolicyWeights: a layer width out of range");
        return nullptr;
      }
      if (l > 0) {
        expected += int64_t{n.widths[l - 1]} * n.widths[l] + n.widths[l];
      }
    }
    if (static_cast<int64_t>(n.params.size()) != expected) {
      note_malformed("PolicyWeights: parameter count does not match the widths");
      return nullptr;
    }
    if (!std::all_of(n.params.begin(), n.params.end(), [](float v) { return std::isfinite(v); })) {
      note_malformed("PolicyWeights: a parameter is not finite");
      return nullptr;
    }
  }
  if (policy == nullptr || algorithm != policy_algorithm) {
    // Only on the first weights (or a learner restarted with another algorithm): not per step.
    const ActingPolicyRegistration* r = acting_policy_registry().find(algorithm);
    if (r == nullptr) {
      note_malformed("PolicyWeights: an algorithm this actor's build has no acting policy for");
      return nullptr;
    }
    pending_policy = r->make(obs_dim, space);
    pending_algorithm.assign(algorithm);
  } else {
    pending_policy.reset();
  }
  const ActingPolicy& judge = pending_policy != nullptr ? *pending_policy : *policy;
  if (const char* why = judge.check(weights_networks, w->bound()); why != nullptr) {
    note_malformed(why);
    return nullptr;
  }
  return w;
}

void ActorLoop::Impl::poll_weights() {
  int pending = -1;  // index into weights_msg of the newest valid weights, if any
  for (int n = 0; n < kMaxMessagesPerLook; ++n) {
    const int slot = pending == 0 ? 1 : 0;
    if (!sub.recv(weights_msg[static_cast<size_t>(slot)], 0)) {
      break;
    }
    if (sub.too_big(weights_msg[static_cast<size_t>(slot)])) {
      learner_peer->refused_oversized(weights_msg[static_cast<size_t>(slot)].size());
      note_malformed("PolicyWeights over the actor's size limit for weights");
      continue;
    }
    learner_peer->received(weights_msg[static_cast<size_t>(slot)].size());
    if (check_weights(weights_msg[static_cast<size_t>(slot)].bytes()) != nullptr) {
      pending = slot;
    }
  }
  if (pending >= 0) {
    const wire::Envelope* env = wire::open_envelope(weights_msg[static_cast<size_t>(pending)].bytes());
    apply_weights(env->payload_as_PolicyWeights());
  }
}

void ActorLoop::Impl::apply_weights(const wire::PolicyWeights* w) {
  const bool first = policy == nullptr;
  std::string_view algorithm;
  weights_networks = wire::policy_networks(*w, algorithm);
  if (policy == nullptr || algorithm != policy_algorithm) {  // check_weights found its acting policy
    policy = pending_policy != nullptr && pending_algorithm == algorithm
                 ? std::move(pending_policy)
                 : acting_policy_registry().find(algorithm)->make(obs_dim, space);
    policy_algorithm.assign(algorithm);
  }
  pending_policy.reset();
  policy->load(weights_networks, w->bound());
  if (!act) {
    act = [this](std::span<const float> obs, std::span<float> out) { policy->act(obs, out); };
  }
  weights_version = w->version();
  updates = w->updates();
  counters.weights_version.store(static_cast<int64_t>(weights_version), std::memory_order_relaxed);
  update_epsilon();
  if (first) {
    log::info("actor {}: first weights ({}, version {}, {} learner updates, {} parameters); epsilon {:.3f}",
              actor_index, policy_algorithm, weights_version, updates, policy->num_params(), eps);
  }
}

void ActorLoop::Impl::update_epsilon() {
  const ExplorationConfig& e = config.exploration;
  if (policy == nullptr) {
    eps = 1.0;
  } else if (config.apex_epsilon) {
    const auto n = static_cast<int>(std::max(num_actors_hint, actor_index + 1));
    eps = apex_epsilon(static_cast<int>(actor_index), n, config.apex_base, config.apex_alpha);
  } else {
    eps = linear_epsilon(updates, e.epsilon_start, e.epsilon_end, e.epsilon_anneal_updates);
  }
  counters.epsilon.store(eps, std::memory_order_relaxed);
}

void ActorLoop::Impl::heard_learner(Clock::time_point now) {
  learner_heard = now;
  if (learner_silent) {
    log::info("actor {}: the learner answers again", actor_index);
    learner_silent = false;
    learner_peer->reconnected();  // silent past the peer timeout, then back
  }
}

void ActorLoop::Impl::poll_learner(Clock::time_point now) {
  for (int n = 0; n < kMaxMessagesPerLook; ++n) {
    uint64_t learner_version = 0;
    switch (link.receive(incoming_map, learner_version)) {
      case LearnerLink::Received::kNothing: return;
      case LearnerLink::Received::kMalformed:
        note_malformed("join socket: not a verified ClusterMap or Heartbeat");
        break;
      case LearnerLink::Received::kHeartbeat:
        heard_learner(now);
        // A different version is a newer map, or a restarted learner: ask for the map again
        // (and again after a peer timeout if the answer got lost).
        if (learner_version != map_version &&
            (!rejoin_pending || ms_between(rejoin_sent, now) >= config.peer_timeout_ms)) {
          log::info("actor {}: the learner's map is version {}, ours {}; re-joining", actor_index, learner_version,
                    map_version);
          link.send_join_request();
          rejoin_pending = true;
          rejoin_sent = now;
        }
        break;
      case LearnerLink::Received::kClusterMap:
        heard_learner(now);
        apply_map(incoming_map);
        rejoin_pending = false;
        break;
    }
  }
}

void ActorLoop::Impl::apply_map(const ClusterInfo& map) {
  const bool had_shards = !shards.empty();
  map_version = map.version;
  num_actors_hint = map.num_actors_hint;
  if (map.actor_index != actor_index) {
    // The index we were first given stays ours: it seeds our streams, picks our ε and tags
    // our batches; a learner that hands out a new index per join does not change it.
    log::debug("actor {}: the map names us actor {}; keeping {}", actor_index, map.actor_index, actor_index);
  }
  if (map.weights_endpoint != weights_endpoint) {
    try {
      if (!weights_endpoint.empty()) {
        sub.disconnect(weights_endpoint);
      }
      sub.connect(map.weights_endpoint);
      weights_endpoint = map.weights_endpoint;
    } catch (const std::runtime_error& e) {
      note_malformed("cluster map: weights endpoint cannot be connected");
      log::warn("actor {}: {}", actor_index, e.what());
    }
  }
  std::vector<Shard> next;
  next.reserve(map.shard_endpoints.size());
  for (const std::string& ep : map.shard_endpoints) {
    auto it = std::find_if(shards.begin(), shards.end(), [&](const Shard& s) { return s.endpoint == ep; });
    if (it != shards.end()) {
      next.push_back(std::move(*it));
      it->endpoint.clear();  // moved; not reported as removed below
      continue;
    }
    try {
      Shard s(ctx, ep, config.batches_in_flight);
      // The window bounds what is in flight; the queue only needs to hold it.
      s.dealer.set_send_hwm(std::max(config.shard_send_hwm, config.batches_in_flight));
      s.dealer.set_max_message_bytes(kMaxShardMessageBytes);
      if (config.curve) {
        s.dealer.make_curve_client(*config.curve);
      }
      s.dealer.connect(ep);
      s.peer = &counters.peers.peer("replay:" + ep);
      next.push_back(std::move(s));
      log::info("actor {}: sending to shard {}", actor_index, ep);
    } catch (const std::runtime_error& e) {
      note_malformed("cluster map: shard endpoint cannot be connected");
      log::warn("actor {}: {}", actor_index, e.what());
    }
  }
  for (const Shard& s : shards) {
    if (!s.endpoint.empty()) {
      log::info("actor {}: shard {} left the map; disconnecting", actor_index, s.endpoint);
    }
  }
  shards = std::move(next);
  shard_poller.clear();
  for (Shard& s : shards) {
    shard_poller.add(s.dealer);
  }
  if (!shards.empty()) {
    next_shard = had_shards ? next_shard % shards.size() : actor_index % shards.size();
    waiting_for_shards_logged = false;
  }
  update_epsilon();
}

void ActorLoop::Impl::heartbeat(Clock::time_point now) {
  const std::array<int64_t, 7> c{counters.env_steps.load(std::memory_order_relaxed),
                                 counters.episodes.load(std::memory_order_relaxed),
                                 counters.batches_sent.load(std::memory_order_relaxed),
                                 counters.transitions_sent.load(std::memory_order_relaxed),
                                 counters.weights_version.load(std::memory_order_relaxed),
                                 counters.malformed_messages.load(std::memory_order_relaxed),
                                 counters.send_blocked_ms.load(std::memory_order_relaxed)};
  link.send_heartbeat(map_version, c);
  read_acks();
  if (!learner_silent && ms_between(learner_heard, now) > config.peer_timeout_ms) {
    log::warn("actor {}: no answer from the learner for {} ms; acting on with weights version {}", actor_index,
              ms_between(learner_heard, now), weights_version);
    learner_silent = true;
  }
}

// ---------------------------------------------------------------------------------------------

ActorLoop::ActorLoop(net::Context& ctx, LearnerLink link, const ClusterInfo& map,
                     std::vector<std::unique_ptr<Env>> envs, ActorLoopConfig config, ActorCounters& counters)
    : impl_(std::make_unique<Impl>(ctx, std::move(link), map, std::move(envs), std::move(config), counters)) {}

ActorLoop::~ActorLoop() = default;

void ActorLoop::run(const std::atomic<bool>& stop) {
  impl_->run(stop, on_tick, on_episode);
}

uint32_t ActorLoop::actor_index() const {
  return impl_->actor_index;
}

double ActorLoop::epsilon() const {
  return impl_->eps;
}

}  // namespace pamdp
