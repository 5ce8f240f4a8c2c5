#include "core/transport.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zmq.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>
#include <zmq.hpp>

#include "core/log.hpp"

namespace pamdp::net {
namespace {

int zmq_type(SocketType t) {
  switch (t) {
    case SocketType::kRouter: return ZMQ_ROUTER;
    case SocketType::kDealer: return ZMQ_DEALER;
    case SocketType::kPub: return ZMQ_PUB;
    case SocketType::kSub: return ZMQ_SUB;
    case SocketType::kPush: return ZMQ_PUSH;
    case SocketType::kPull: return ZMQ_PULL;
  }
  return ZMQ_DEALER;
}

bool wait_for(void* socket, short events, int timeout_ms) {
  zmq_pollitem_t item{socket, 0, events, 0};
  while (true) {
    const int rc = zmq_poll(&item, 1, timeout_ms);
    if (rc >= 0) {
      return rc > 0 && (item.revents & events) != 0;
    }
    if (zmq_errno() != EINTR) {
      return false;
    }
  }
}

}  // namespace

struct Context::Impl {
  zmq::context_t ctx{1};
};
Context::Context() : impl_(std::make_unique<Impl>()) {}
Context::~Context() = default;
void* Context::raw() const {
  return impl_->ctx.handle();
}

// FlatBuffers reads scalars in place, so a frame must start 8-byte aligned. ZeroMQ's TCP decoder
// hands out large frames that point into its receive buffer just past the frame header
// (zero-copy), at any alignment; data() copies those into an aligned buffer that grows once and is
// then reused. raw() is how every receive reaches the frame, so it marks the copy stale.
struct Message::Impl {
  zmq::message_t msg;
  bool settled = false;
  const uint8_t* data = nullptr;
  std::vector<uint64_t> aligned;

  void settle() {
    const auto* p = static_cast<const uint8_t*>(msg.data());
    data = p;
    if (reinterpret_cast<uintptr_t>(p) % alignof(uint64_t) != 0) {
      const size_t words = (msg.size() + sizeof(uint64_t) - 1) / sizeof(uint64_t);
      if (aligned.size() < words) {
        aligned.resize(words);
      }
      std::memcpy(aligned.data(), p, msg.size());
      data = reinterpret_cast<const uint8_t*>(aligned.data());
    }
    settled = true;
  }
};
Message::Message() : impl_(std::make_unique<Impl>()) {}
Message::~Message() = default;
const uint8_t* Message::data() const {
  if (!impl_->settled) {
    impl_->settle();
  }
  return impl_->data;
}
size_t Message::size() const {
  return impl_->msg.size();
}
void* Message::raw() {
  impl_->settled = false;
  return &impl_->msg;
}

Socket::Socket(Context& ctx, SocketType type) : sock_(zmq_socket(ctx.raw(), zmq_type(type))) {
  if (sock_ == nullptr) {
    throw std::runtime_error(std::string("cannot create socket: ") + zmq_strerror(zmq_errno()));
  }
  const int linger = 0;
  zmq_setsockopt(sock_, ZMQ_LINGER, &linger, sizeof(linger));
  // Liveness on real links (docs/reliability.md, "Faults: a bad network"). A link that drops
  // packets without a FIN or RST (a partition, a vanished host) leaves TCP's connection open,
  // and its retransmissions back off to tens of seconds: without these a link healed after 30 s
  // could stay silent 20 s longer. ZMTP heartbeats close a connection that has been silent for
  // kHeartbeatTimeoutMs, so libzmq reconnects; a connect that gets no answer is abandoned after
  // kConnectTimeoutMs and retried every ZMQ_RECONNECT_IVL (100 ms), so a healed link is used
  // again within about kConnectTimeoutMs. The timeout is generous because a peer that holds its
  // socket unread (backpressure) leaves pings unread too. inproc:// ignores all three.
  const int heartbeat_ivl = kHeartbeatIntervalMs;
  const int heartbeat_timeout = kHeartbeatTimeoutMs;
  const int connect_timeout = kConnectTimeoutMs;
  zmq_setsockopt(sock_, ZMQ_HEARTBEAT_IVL, &heartbeat_ivl, sizeof(heartbeat_ivl));
  zmq_setsockopt(sock_, ZMQ_HEARTBEAT_TIMEOUT, &heartbeat_timeout, sizeof(heartbeat_timeout));
  zmq_setsockopt(sock_, ZMQ_CONNECT_TIMEOUT, &connect_timeout, sizeof(connect_timeout));
}

Socket::~Socket() {
  if (sock_ != nullptr) {
    zmq_close(sock_);
  }
}

Socket::Socket(Socket&& o) noexcept : sock_(o.sock_), max_frame_bytes_(o.max_frame_bytes_) {
  o.sock_ = nullptr;
}

Socket& Socket::operator=(Socket&& o) noexcept {
  if (this != &o) {
    if (sock_ != nullptr) {
      zmq_close(sock_);
    }
    sock_ = o.sock_;
    max_frame_bytes_ = o.max_frame_bytes_;
    o.sock_ = nullptr;
  }
  return *this;
}

namespace {
void setopt(void* s, int opt, const void* value, size_t len, const char* what) {
  if (zmq_setsockopt(s, opt, value, len) != 0) {
    throw std::runtime_error(std::string("cannot set ") + what + ": " + zmq_strerror(zmq_errno()));
  }
}
void setint(void* s, int opt, int v, const char* what) {
  setopt(s, opt, &v, sizeof(v), what);
}
}  // namespace

void Socket::set_send_hwm(int messages) {
  setint(raw(), ZMQ_SNDHWM, messages, "send high water mark");
}
void Socket::set_recv_hwm(int messages) {
  setint(raw(), ZMQ_RCVHWM, messages, "receive high water mark");
}
void Socket::set_linger_ms(int ms) {
  setint(raw(), ZMQ_LINGER, ms, "linger");
}
void Socket::set_kernel_buffers(int send_bytes, int recv_bytes) {
  setint(raw(), ZMQ_SNDBUF, send_bytes, "kernel send buffer");
  setint(raw(), ZMQ_RCVBUF, recv_bytes, "kernel receive buffer");
}
void Socket::set_router_mandatory(bool on) {
  setint(raw(), ZMQ_ROUTER_MANDATORY, on ? 1 : 0, "router mandatory");
}
void Socket::set_max_message_bytes(int64_t bytes) {
  const int64_t cap = bytes < 0 ? -1 : bytes * kFrameCapFactor;
  setopt(raw(), ZMQ_MAXMSGSIZE, &cap, sizeof(cap), "max message size");
  max_frame_bytes_ = bytes < 0 ? -1 : bytes;
}
void Socket::subscribe_all() {
  setopt(raw(), ZMQ_SUBSCRIBE, "", 0, "subscription");
}

void Socket::make_curve_server(const CurveServerKeys& keys) {
  setint(raw(), ZMQ_CURVE_SERVER, 1, "CURVE server mode");
  setopt(raw(), ZMQ_CURVE_SECRETKEY, keys.secret_key.c_str(), keys.secret_key.size(), "CURVE secret key");
}

void Socket::make_curve_client(const CurveClientKeys& keys) {
  setopt(raw(), ZMQ_CURVE_SERVERKEY, keys.server_public_key.c_str(), keys.server_public_key.size(),
         "CURVE server public key");
  setopt(raw(), ZMQ_CURVE_PUBLICKEY, keys.public_key.c_str(), keys.public_key.size(), "CURVE public key");
  setopt(raw(), ZMQ_CURVE_SECRETKEY, keys.secret_key.c_str(), keys.secret_key.size(), "CURVE secret key");
}

std::string Socket::bind(const std::string& endpoint) {
  if (zmq_bind(raw(), endpoint.c_str()) != 0) {
    const int err = zmq_errno();
    std::string hint = err == EADDRINUSE ? " (address in use: pick another port or stop the process holding it)"
                                         : " (expected tcp://HOST:PORT, tcp://*:PORT, ipc://PATH or inproc://NAME)";
    throw std::runtime_error("cannot bind '" + endpoint + "': " + zmq_strerror(err) + hint);
  }
  char buf[512];
  size_t len = sizeof(buf);
  if (zmq_getsockopt(raw(), ZMQ_LAST_ENDPOINT, buf, &len) != 0) {
    return endpoint;
  }
  return std::string(buf);
}

void Socket::connect(const std::string& endpoint) {
  if (zmq_connect(raw(), endpoint.c_str()) != 0) {
    throw std::runtime_error("cannot connect to '" + endpoint + "': " + zmq_strerror(zmq_errno()) +
                             " (expected tcp://HOST:PORT, ipc://PATH or inproc://NAME)");
  }
}

void Socket::disconnect(const std::string& endpoint) {
  zmq_disconnect(raw(), endpoint.c_str());
}

bool Socket::send(std::span<const uint8_t> payload, int timeout_ms) {
  if (timeout_ms > 0 && !wait_for(raw(), ZMQ_POLLOUT, timeout_ms)) {
    return false;
  }
  const int flags = timeout_ms < 0 ? 0 : ZMQ_DONTWAIT;
  while (zmq_send(raw(), payload.data(), payload.size(), flags) < 0) {
    if (zmq_errno() != EINTR) {
      return false;
    }
  }
  return true;
}

bool Socket::send_to(std::span<const uint8_t> identity, std::span<const uint8_t> payload, int timeout_ms) {
  if (timeout_ms > 0 && !wait_for(raw(), ZMQ_POLLOUT, timeout_ms)) {
    return false;
  }
  const int flags = timeout_ms < 0 ? 0 : ZMQ_DONTWAIT;
  if (zmq_send(raw(), identity.data(), identity.size(), flags | ZMQ_SNDMORE) < 0) {
    return false;
  }
  return zmq_send(raw(), payload.data(), payload.size(), flags) >= 0;
}

bool Socket::recv(Message& out, int timeout_ms) {
  if (timeout_ms >= 0 && !wait_for(raw(), ZMQ_POLLIN, timeout_ms)) {
    return false;
  }
  auto* msg = static_cast<zmq::message_t*>(out.raw());
  while (zmq_msg_recv(msg->handle(), raw(), 0) < 0) {
    if (zmq_errno() != EINTR) {
      return false;
    }
  }
  // Drain any extra frames: the protocol sends one frame per message.
  while (msg->more()) {
    zmq::message_t extra;
    zmq_msg_recv(extra.handle(), raw(), 0);
    if (!extra.more()) {
      msg->rebuild(static_cast<size_t>(0));
      break;
    }
  }
  return true;
}

bool Socket::recv_from(Message& identity, Message& payload, int timeout_ms) {
  if (timeout_ms >= 0 && !wait_for(raw(), ZMQ_POLLIN, timeout_ms)) {
    return false;
  }
  auto* id = static_cast<zmq::message_t*>(identity.raw());
  auto* msg = static_cast<zmq::message_t*>(payload.raw());
  while (zmq_msg_recv(id->handle(), raw(), 0) < 0) {
    if (zmq_errno() != EINTR) {
      return false;
    }
  }
  if (!id->more()) {
    msg->rebuild(static_cast<size_t>(0));
    return true;
  }
  zmq_msg_recv(msg->handle(), raw(), 0);
  if (msg->more()) {
    // More than [identity, payload]: not our protocol. Drain and report an empty payload.
    zmq::message_t extra;
    do {
      zmq_msg_recv(extra.handle(), raw(), 0);
    } while (extra.more());
    msg->rebuild(static_cast<size_t>(0));
  }
  return true;
}

bool Socket::wait_readable(int timeout_ms) {
  return wait_for(raw(), ZMQ_POLLIN, timeout_ms);
}

std::string advertised_endpoint(const std::string& bound, const std::string& host) {
  const std::string tcp = "tcp://";
  if (bound.rfind(tcp, 0) != 0) {
    return bound;
  }
  const size_t colon = bound.rfind(':');
  if (colon == std::string::npos || colon < tcp.size()) {
    return bound;
  }
  const std::string bound_host = bound.substr(tcp.size(), colon - tcp.size());
  if (bound_host == "0.0.0.0" || bound_host == "*" || bound_host == "[::]" || bound_host == "::") {
    return tcp + host + bound.substr(colon);
  }
  return bound;
}

bool is_loopback_endpoint(const std::string& endpoint) {
  if (endpoint.rfind("inproc://", 0) == 0 || endpoint.rfind("ipc://", 0) == 0) {
    return true;
  }
  const std::string tcp = "tcp://";
  if (endpoint.rfind(tcp, 0) != 0) {
    return false;
  }
  const size_t colon = endpoint.rfind(':');
  if (colon == std::string::npos || colon < tcp.size()) {
    return false;
  }
  std::string host = endpoint.substr(tcp.size(), colon - tcp.size());
  if (host.find(';') != std::string::npos) {
    return false;  // tcp://SOURCE;DEST:PORT: not worth parsing, call it exposed
  }
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  if (host == "localhost" || host == "lo" || host == "::1") {
    return true;
  }
  // 127.0.0.0/8, written as a dotted quad.
  unsigned a = 0;
  unsigned b = 0;
  unsigned c = 0;
  unsigned d = 0;
  char tail = 0;
  return std::sscanf(host.c_str(), "%u.%u.%u.%u%c", &a, &b, &c, &d, &tail) == 4 && a == 127 && b < 256 && c < 256 &&
         d < 256;
}

struct HandshakeMonitor::Impl {
  std::vector<void*> watched;  // the sockets monitored
  std::vector<void*> pairs;    // their event streams
  std::string owner;
  std::thread thread;
  std::atomic<bool> stop{false};
  std::atomic<int64_t> refused{0};
};

namespace {

std::string handshake_failure(uint16_t event, uint32_t value) {
  if (event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) {
    return "client key not allowed (ZAP status " + std::to_string(value) + ")";
  }
  if (event == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) {
    if (value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH) {
      return "security mechanism mismatch (a peer without CURVE at a CURVE socket, or the reverse)";
    }
    if (value == ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC) {
      return "cryptographic error (a client that does not have the cluster's server public key)";
    }
    char hex[16];
    std::snprintf(hex, sizeof(hex), "0x%08x", value);
    return std::string("protocol error ") + hex;
  }
  return std::string("no detail: ") + std::strerror(static_cast<int>(value));
}

}  // namespace

HandshakeMonitor::HandshakeMonitor(Context& ctx, const std::vector<Socket*>& sockets, std::string owner)
    : impl_(std::make_unique<Impl>()) {
  static std::atomic<uint64_t> next_id{0};
  impl_->owner = std::move(owner);
  constexpr int kEvents =
      ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL | ZMQ_EVENT_HANDSHAKE_FAILED_AUTH;
  for (Socket* s : sockets) {
    const std::string endpoint = "inproc://pamdp-handshake-monitor-" + std::to_string(next_id.fetch_add(1));
    void* pair = zmq_socket(ctx.raw(), ZMQ_PAIR);
    if (pair == nullptr || zmq_socket_monitor(s->raw(), endpoint.c_str(), kEvents) != 0 ||
        zmq_connect(pair, endpoint.c_str()) != 0) {
      const std::string error = zmq_strerror(zmq_errno());
      if (pair != nullptr) {
        zmq_close(pair);
      }
      for (size_t i = 0; i < impl_->pairs.size(); ++i) {
        zmq_socket_monitor(impl_->watched[i], nullptr, 0);
        zmq_close(impl_->pairs[i]);
      }
      throw std::runtime_error("cannot monitor the handshakes of " + impl_->owner + "'s sockets: " + error);
    }
    impl_->watched.push_back(s->raw());
    impl_->pairs.push_back(pair);
  }
  impl_->thread = std::thread([impl = impl_.get()] {
    std::vector<zmq_pollitem_t> items;
    for (void* p : impl->pairs) {
      items.push_back({p, 0, ZMQ_POLLIN, 0});
    }
    std::chrono::steady_clock::time_point last_log{};
    int64_t unlogged = 0;
    while (!impl->stop.load()) {
      if (zmq_poll(items.data(), static_cast<int>(items.size()), 100) <= 0) {
        continue;
      }
      for (const zmq_pollitem_t& item : items) {
        if ((item.revents & ZMQ_POLLIN) == 0) {
          continue;
        }
        // An event is two frames: 2 bytes event id + 4 bytes value, then the socket's endpoint.
        zmq_msg_t head;
        zmq_msg_t where;
        zmq_msg_init(&head);
        zmq_msg_init(&where);
        if (zmq_msg_recv(&head, item.socket, ZMQ_DONTWAIT) >= 0 && zmq_msg_more(&head) != 0 &&
            zmq_msg_recv(&where, item.socket, ZMQ_DONTWAIT) >= 0 && zmq_msg_size(&head) >= 6) {
          uint16_t event = 0;
          uint32_t value = 0;
          std::memcpy(&event, zmq_msg_data(&head), sizeof(event));
          std::memcpy(&value, static_cast<const uint8_t*>(zmq_msg_data(&head)) + 2, sizeof(value));
          const int64_t n = impl->refused.fetch_add(1) + 1;
          ++unlogged;
          const auto now = std::chrono::steady_clock::now();
          if (now - last_log >= std::chrono::seconds(1)) {
            last_log = now;
            pamdp::log::warn("{}: refused a connection at {}: {} ({} refused so far, {} since the last line)",
                             impl->owner,
                             std::string(static_cast<const char*>(zmq_msg_data(&where)), zmq_msg_size(&where)),
                             handshake_failure(event, value), n, unlogged);
            unlogged = 0;
          }
        }
        zmq_msg_close(&head);
        zmq_msg_close(&where);
      }
    }
  });
}

HandshakeMonitor::~HandshakeMonitor() {
  impl_->stop.store(true);
  impl_->thread.join();
  for (size_t i = 0; i < impl_->pairs.size(); ++i) {
    zmq_socket_monitor(impl_->watched[i], nullptr, 0);
    zmq_close(impl_->pairs[i]);
  }
}

int64_t HandshakeMonitor::refused() const {
  return impl_->refused.load();
}

DisconnectWatch::DisconnectWatch(Context& ctx, Socket& socket) : watched_(socket.raw()) {
  static std::atomic<uint64_t> next_id{0};
  const std::string endpoint = "inproc://pamdp-disconnect-watch-" + std::to_string(next_id.fetch_add(1));
  pair_ = zmq_socket(ctx.raw(), ZMQ_PAIR);
  if (pair_ == nullptr || zmq_socket_monitor(watched_, endpoint.c_str(), ZMQ_EVENT_DISCONNECTED) != 0 ||
      zmq_connect(pair_, endpoint.c_str()) != 0) {
    const std::string error = zmq_strerror(zmq_errno());
    if (pair_ != nullptr) {
      zmq_socket_monitor(watched_, nullptr, 0);
      zmq_close(pair_);
    }
    throw std::runtime_error("cannot watch a socket's connections: " + error);
  }
}

DisconnectWatch::DisconnectWatch(DisconnectWatch&& other) noexcept
    : watched_(std::exchange(other.watched_, nullptr)), pair_(std::exchange(other.pair_, nullptr)) {}

DisconnectWatch::~DisconnectWatch() {
  if (pair_ != nullptr) {
    zmq_socket_monitor(watched_, nullptr, 0);
    zmq_close(pair_);
  }
}

int DisconnectWatch::take() {
  int n = 0;
  zmq_msg_t frame;
  zmq_msg_init(&frame);
  // An event is two frames: 2 bytes event id + 4 bytes value, then the endpoint.
  while (zmq_msg_recv(&frame, pair_, ZMQ_DONTWAIT) >= 0) {
    if (zmq_msg_more(&frame) == 0) {
      ++n;  // the event's last frame
    }
  }
  zmq_msg_close(&frame);
  return n;
}

void Poller::add(Socket& s) {
  sockets_.push_back(s.raw());
  revents_.push_back(0);
  items_.resize(sockets_.size() * sizeof(zmq_pollitem_t));
}

void Poller::clear() {
  sockets_.clear();
  revents_.clear();
  items_.clear();
}

int Poller::poll(int timeout_ms) {
  auto* items = reinterpret_cast<zmq_pollitem_t*>(items_.data());
  for (size_t i = 0; i < sockets_.size(); ++i) {
    items[i] = {sockets_[i], 0, ZMQ_POLLIN, 0};
  }
  int rc = 0;
  do {
    rc = zmq_poll(items, static_cast<int>(sockets_.size()), timeout_ms);
  } while (rc < 0 && zmq_errno() == EINTR);
  for (size_t i = 0; i < sockets_.size(); ++i) {
    revents_[i] = items[i].revents;
  }
  return rc < 0 ? 0 : rc;
}

bool Poller::readable(size_t index) const {
  return (revents_[index] & ZMQ_POLLIN) != 0;
}

CurveServerKeys generate_curve_keypair() {
  char pub[41];
  char sec[41];
  if (zmq_curve_keypair(pub, sec) != 0) {
    throw std::runtime_error(std::string("cannot generate CURVE keys: ") + zmq_strerror(zmq_errno()) +
                             " (libzmq built without CURVE support?)");
  }
  return {pub, sec};
}

namespace {

void write_secret_file(const std::string& path, const std::string& text) {
  // Created 0600 and exclusively: never readable by others, not even for a moment, and never
  // over an existing file.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    if (errno == EEXIST) {
      throw std::runtime_error("'" + path + "' exists; keys are never overwritten (remove it or choose another --dir)");
    }
    throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
  }
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n <= 0) {
      const int err = errno;
      ::close(fd);
      throw std::runtime_error("cannot write '" + path + "': " + std::strerror(err));
    }
    done += static_cast<size_t>(n);
  }
  ::close(fd);
}

std::map<std::string, std::string> read_key_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("cannot read CURVE key file '" + path +
                             "' (create the keys with: pamdp keygen --dir DIR)");
  }
  // A secret key every user of the machine can read is no secret: refuse it, as ssh does.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && (st.st_mode & S_IROTH) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw std::runtime_error("CURVE key file '" + path + "' is readable by every user (mode " + mode +
                             "), so its secret key is exposed: chmod 600 '" + path +
                             "' (pamdp keygen writes 0600; a Kubernetes secret volume needs defaultMode: 0400)");
  }
  std::map<std::string, std::string> kv;
  std::string line;
  while (std::getline(in, line)) {
    const auto eq = line.find('=');
    if (line.empty() || line[0] == '#' || eq == std::string::npos) {
      continue;
    }
    auto trim = [](std::string v) {
      const auto a = v.find_first_not_of(" \t\"");
      const auto b = v.find_last_not_of(" \t\"\r");
      return a == std::string::npos ? std::string() : v.substr(a, b - a + 1);
    };
    kv[trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
  }
  return kv;
}

std::string key(const std::map<std::string, std::string>& kv, const std::string& name, const std::string& path) {
  const auto it = kv.find(name);
  if (it == kv.end() || it->second.size() != 40) {
    throw std::runtime_error("CURVE key file '" + path + "' lacks a 40-character Z85 '" + name + "'");
  }
  return it->second;
}

}  // namespace

void write_curve_keyring(const std::string& dir) {
  std::filesystem::create_directories(dir);
  const CurveServerKeys server = generate_curve_keypair();
  const CurveServerKeys client = generate_curve_keypair();
  write_secret_file(dir + "/server.keys",
                    "# pamdp CURVE keys of the bound sockets (learner, replay shards)\npublic = \"" +
                        server.public_key + "\"\nsecret = \"" + server.secret_key + "\"\n");
  write_secret_file(dir + "/client.keys", "# pamdp CURVE keys of the connecting sockets (every process)\npublic = \"" +
                                              client.public_key + "\"\nsecret = \"" + client.secret_key +
                                              "\"\nserver_public = \"" + server.public_key + "\"\n");
}

CurveKeyring load_curve_keyring(const std::string& dir, bool need_server) {
  CurveKeyring k;
  const std::string cpath = dir + "/client.keys";
  const auto c = read_key_file(cpath);
  k.client = {key(c, "public", cpath), key(c, "secret", cpath), key(c, "server_public", cpath)};
  const std::string spath = dir + "/server.keys";
  if (need_server || std::filesystem::exists(spath)) {
    const auto s = read_key_file(spath);
    k.server = {key(s, "public", spath), key(s, "secret", spath)};
    if (k.server.public_key != k.client.server_public_key) {
      throw std::runtime_error("'" + spath + "' and '" + cpath + "' are not from the same pamdp keygen run");
    }
  }
  return k;
}

struct CurveAuthenticator::Impl {
  void* rep = nullptr;
  std::thread thread;
  std::atomic<bool> stop{false};
  std::atomic<int64_t> accepted{0};
  std::atomic<int64_t> refused{0};
  std::vector<std::string> allowed;  // 32-byte binary public keys
};

CurveAuthenticator::CurveAuthenticator(Context& ctx, const std::vector<std::string>& allowed_client_keys)
    : impl_(std::make_unique<Impl>()) {
  for (const std::string& z85 : allowed_client_keys) {
    uint8_t bin[32];
    if (z85.size() != 40 || zmq_z85_decode(bin, z85.c_str()) == nullptr) {
      throw std::runtime_error("CURVE client key '" + z85 + "' is not 40 characters of Z85");
    }
    impl_->allowed.emplace_back(reinterpret_cast<const char*>(bin), 32);
  }
  impl_->rep = zmq_socket(ctx.raw(), ZMQ_REP);
  if (impl_->rep == nullptr || zmq_bind(impl_->rep, "inproc://zeromq.zap.01") != 0) {
    throw std::runtime_error(std::string("cannot start the CURVE authenticator: ") + zmq_strerror(zmq_errno()));
  }
  impl_->thread = std::thread([impl = impl_.get()] {
    while (!impl->stop.load()) {
      zmq_pollitem_t item{impl->rep, 0, ZMQ_POLLIN, 0};
      if (zmq_poll(&item, 1, 100) <= 0) {
        continue;
      }
      // ZAP request (RFC 27): version, request id, domain, address, identity, mechanism, credentials.
      std::vector<std::string> frames;
      int more = 1;
      while (more != 0) {
        zmq_msg_t m;
        zmq_msg_init(&m);
        if (zmq_msg_recv(&m, impl->rep, 0) < 0) {
          zmq_msg_close(&m);
          break;
        }
        frames.emplace_back(static_cast<const char*>(zmq_msg_data(&m)), zmq_msg_size(&m));
        more = zmq_msg_more(&m);
        zmq_msg_close(&m);
      }
      const bool ok = frames.size() >= 7 && frames[5] == "CURVE" &&
                      std::find(impl->allowed.begin(), impl->allowed.end(), frames[6]) != impl->allowed.end();
      const std::string request_id = frames.size() > 1 ? frames[1] : std::string();
      if (ok) {
        impl->accepted.fetch_add(1);
      } else {
        const int64_t n = impl->refused.fetch_add(1) + 1;
        pamdp::log::warn("CURVE: refused a connection from {} without an allowed client key ({} refused so far)",
                         frames.size() > 3 ? frames[3] : std::string("?"), n);
      }
      const std::string reply[] = {"1.0", request_id, ok ? "200" : "400", ok ? "OK" : "client key not allowed", "", ""};
      for (size_t i = 0; i < 6; ++i) {
        zmq_send(impl->rep, reply[i].data(), reply[i].size(), i + 1 < 6 ? ZMQ_SNDMORE : 0);
      }
    }
  });
}

CurveAuthenticator::~CurveAuthenticator() {
  impl_->stop.store(true);
  impl_->thread.join();
  zmq_close(impl_->rep);
}

int64_t CurveAuthenticator::accepted() const {
  return impl_->accepted.load();
}
int64_t CurveAuthenticator::refused() const {
  return impl_->refused.load();
}

}  // namespace pamdp::net
