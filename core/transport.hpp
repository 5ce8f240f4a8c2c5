// The transport seam: the only header that knows ZeroMQ. Roles send and receive opaque byte
// buffers (FlatBuffers envelopes, see core/wire.hpp) through these sockets, over inproc://,
// ipc:// or tcp://, optionally with CURVE encryption and authentication.
//
// Threading: a Context may be shared by threads; a Socket belongs to one thread at a time.
// Costs: send/recv copy nothing beyond what ZeroMQ itself does, except that Message::data()
// copies a frame ZeroMQ delivered at an address not 8-byte aligned (TCP frames, usually) into an
// aligned buffer, so that FlatBuffers can read it in place; Message objects are reused by the
// caller so that steady-state receiving allocates only inside ZeroMQ.
// Errors: setup failures a user can cause (a bad endpoint, a port in use) throw
// std::runtime_error naming the endpoint and the fix; timeouts are returned as false.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace pamdp::net {

class Context {
 public:
  Context();
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  [[nodiscard]] void* raw() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A received frame. Reuse one per receive site.
class Message {
 public:
  Message();
  ~Message();
  Message(const Message&) = delete;
  Message& operator=(const Message&) = delete;
  [[nodiscard]] const uint8_t* data() const;
  [[nodiscard]] size_t size() const;
  [[nodiscard]] std::span<const uint8_t> bytes() const { return {data(), size()}; }
  [[nodiscard]] void* raw();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

enum class SocketType { kRouter, kDealer, kPub, kSub, kPush, kPull };

// CURVE keys as 40-character Z85 strings (pamdp keygen writes them).
struct CurveServerKeys {
  std::string public_key;
  std::string secret_key;
};
struct CurveClientKeys {
  std::string public_key;
  std::string secret_key;
  std::string server_public_key;
};

// Liveness of every socket's TCP connections (set by the Socket constructor): a ZMTP ping every
// kHeartbeatIntervalMs; a connection silent for kHeartbeatTimeoutMs is closed and libzmq
// reconnects; a connect unanswered for kConnectTimeoutMs is retried. So a link that comes back
// after a partition is in use again within about kConnectTimeoutMs + 100 ms.
inline constexpr int kHeartbeatIntervalMs = 1000;
inline constexpr int kHeartbeatTimeoutMs = 10000;
inline constexpr int kConnectTimeoutMs = 2000;
// ZeroMQ's own limit on a frame, as a multiple of the caller's (Socket::set_max_message_bytes).
inline constexpr int64_t kFrameCapFactor = 2;

class Socket {
 public:
  Socket(Context& ctx, SocketType type);
  ~Socket();
  Socket(Socket&&) noexcept;
  Socket& operator=(Socket&&) noexcept;
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;

  // High water marks (messages queued before send blocks / incoming messages are held back).
  void set_send_hwm(int messages);
  void set_recv_hwm(int messages);
  void set_linger_ms(int ms);
  // Kernel socket buffer sizes (SO_SNDBUF / SO_RCVBUF). The high water marks count messages
  // in ZeroMQ's queues only; on loopback the kernel buffers can hold megabytes more, so tight
  // backpressure needs both small.
  void set_kernel_buffers(int send_bytes, int recv_bytes);
  // ROUTER: report unroutable messages as errors instead of dropping them silently.
  void set_router_mandatory(bool on);
  // The largest frame the caller accepts. A receive site refuses a bigger one with too_big() and
  // counts it against the peer it came from (PeerCounters::refused_for_size). ZeroMQ itself drops
  // the connection only for a frame over kFrameCapFactor times this (ZMQ_MAXMSGSIZE, which libzmq
  // 4.3 reports as a bare disconnect, from no peer in particular), so a frame a little too big is
  // seen, refused and counted, and a huge one never reaches memory. -1 = no limit.
  void set_max_message_bytes(int64_t bytes);
  // Whether a received frame is over set_max_message_bytes.
  [[nodiscard]] bool too_big(const Message& m) const {
    return max_frame_bytes_ >= 0 && static_cast<int64_t>(m.size()) > max_frame_bytes_;
  }
  [[nodiscard]] int64_t max_message_bytes() const { return max_frame_bytes_; }
  void subscribe_all();  // SUB only
  void make_curve_server(const CurveServerKeys& keys);
  void make_curve_client(const CurveClientKeys& keys);

  // Binds and returns the resolved endpoint (tcp://host:* becomes tcp://host:PORT).
  std::string bind(const std::string& endpoint);
  void connect(const std::string& endpoint);
  void disconnect(const std::string& endpoint);

  // Sends one frame. timeout_ms: -1 blocks, 0 never blocks, > 0 waits at most that long.
  // Returns false if it could not be queued in time (peer gone or queue full).
  bool send(std::span<const uint8_t> payload, int timeout_ms = -1);
  // ROUTER: sends [identity, payload].
  bool send_to(std::span<const uint8_t> identity, std::span<const uint8_t> payload, int timeout_ms = 0);
  // Receives one frame; false on timeout.
  bool recv(Message& out, int timeout_ms = -1);
  // ROUTER: receives [identity, payload]; extra frames are drained and the message is
  // reported as malformed by returning true with an empty payload.
  bool recv_from(Message& identity, Message& payload, int timeout_ms = -1);

  // Waits until the socket has something to read; false on timeout.
  bool wait_readable(int timeout_ms);
  [[nodiscard]] void* raw() const { return sock_; }

 private:
  void* sock_ = nullptr;  // the ZeroMQ socket handle
  int64_t max_frame_bytes_ = -1;
};

// The address peers use for a bound endpoint: a wildcard host (tcp://*:P, tcp://0.0.0.0:P,
// IPv6 wildcards) becomes tcp://<host>:P; anything else is returned unchanged.
std::string advertised_endpoint(const std::string& bound, const std::string& host);

// Whether an endpoint is reachable from this machine only: inproc://, ipc://, or tcp:// on a
// loopback address (127.0.0.0/8, [::1], localhost, the interface lo). A wildcard (tcp://*:P,
// 0.0.0.0, [::]) and every other host count as reachable from the network.
bool is_loopback_endpoint(const std::string& endpoint);

// Counts connections whose ZMTP handshake failed on the given bound sockets: a peer without CURVE
// at a CURVE socket (mechanism mismatch), a client that does not know the server's public key
// (cryptographic error), a client key the CurveAuthenticator refused (ZAP 400), a peer that is not
// ZeroMQ at all. libzmq's socket monitor (zmq_socket_monitor, events HANDSHAKE_FAILED_*) reports
// them; one thread reads the events, logs at most once per second and counts.
// Construct after the sockets, before binding them; destroy before them, after the thread that
// uses them has stopped (the destructor stops monitoring on each socket).
class HandshakeMonitor {
 public:
  HandshakeMonitor(Context& ctx, const std::vector<Socket*>& sockets, std::string owner);
  ~HandshakeMonitor();
  HandshakeMonitor(const HandshakeMonitor&) = delete;
  HandshakeMonitor& operator=(const HandshakeMonitor&) = delete;
  // Handshakes refused so far, all sockets; any thread.
  [[nodiscard]] int64_t refused() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Counts the connections a socket has lost (libzmq's socket monitor, ZMQ_EVENT_DISCONNECTED), read
// without a thread: take() drains the events queued so far and never blocks. An actor uses it to
// learn that the batches in flight to a shard died with its connection. Construct after the
// socket; destroy before it (a Socket's moves keep the watch valid). Throws std::runtime_error if
// the monitor cannot be set up.
class DisconnectWatch {
 public:
  DisconnectWatch(Context& ctx, Socket& socket);
  ~DisconnectWatch();
  DisconnectWatch(DisconnectWatch&& other) noexcept;
  DisconnectWatch& operator=(DisconnectWatch&&) = delete;
  DisconnectWatch(const DisconnectWatch&) = delete;
  DisconnectWatch& operator=(const DisconnectWatch&) = delete;
  // Disconnects since the last call.
  int take();

 private:
  void* watched_ = nullptr;
  void* pair_ = nullptr;
};

// Waits on several sockets at once; returns the indices of the readable ones.
class Poller {
 public:
  void add(Socket& s);
  void clear();
  [[nodiscard]] size_t size() const { return sockets_.size(); }
  // Returns how many are readable; readable(i) tells which.
  int poll(int timeout_ms);
  [[nodiscard]] bool readable(size_t index) const;

 private:
  std::vector<void*> sockets_;
  std::vector<short> revents_;
  std::vector<std::byte> items_;  // zmq_pollitem_t storage, rebuilt by add(); poll() allocates nothing
};

// Generates a CURVE key pair (Z85). Throws if libzmq was built without CURVE.
CurveServerKeys generate_curve_keypair();

// The keys of one cluster (pamdp keygen): the servers' pair (every bound socket) and the
// clients' pair (every connecting socket, with the servers' public key). Files in `dir`:
// server.keys (public + secret) and client.keys (public + secret + server_public), mode 0600.
struct CurveKeyring {
  CurveServerKeys server;
  CurveClientKeys client;
};
// Writes a fresh keyring; refuses to overwrite existing files.
void write_curve_keyring(const std::string& dir);
// Reads a keyring; throws std::runtime_error naming the file and what is wrong. Actors need
// only client.keys: with need_server = false a missing server.keys is not an error.
CurveKeyring load_curve_keyring(const std::string& dir, bool need_server);

// ZeroMQ authentication (ZAP) for every CURVE server socket of a Context: a connection is
// accepted only if the client's public key is one of `allowed_client_keys` (Z85); others are
// refused during the handshake (no message of theirs is ever delivered) and counted and logged.
// Runs a thread; construct it before binding, destroy it after the sockets.
class CurveAuthenticator {
 public:
  CurveAuthenticator(Context& ctx, const std::vector<std::string>& allowed_client_keys);
  ~CurveAuthenticator();
  CurveAuthenticator(const CurveAuthenticator&) = delete;
  CurveAuthenticator& operator=(const CurveAuthenticator&) = delete;
  [[nodiscard]] int64_t accepted() const;
  [[nodiscard]] int64_t refused() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pamdp::net
