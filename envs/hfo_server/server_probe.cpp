#include "envs/hfo_server/server_probe.hpp"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <stdexcept>
#include <thread>

namespace pamdp::hfo_server {

ServerProbe probe_server(const std::string& host, int port, double timeout_s) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (const int rc = getaddrinfo(host.c_str(), service.c_str(), &hints, &found); rc != 0) {
    throw std::runtime_error("hfo-server: cannot resolve env.server_host '" + host + "': " + gai_strerror(rc));
  }
  const int fd = socket(found->ai_family, found->ai_socktype, found->ai_protocol);
  const bool connected = fd >= 0 && ::connect(fd, found->ai_addr, found->ai_addrlen) == 0;
  freeaddrinfo(found);
  if (!connected) {
    if (fd >= 0) {
      close(fd);
    }
    throw std::runtime_error("hfo-server: cannot open a UDP socket to " + host + ":" + service);
  }
  static constexpr char kProbe[] = "(pamdp_probe)";
  const auto start = std::chrono::steady_clock::now();
  const auto deadline =
      start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(timeout_s));
  ServerProbe result;
  for (int attempt = 0; !result.answered && std::chrono::steady_clock::now() < deadline; ++attempt) {
    const auto next = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    (void)send(fd, kProbe, sizeof(kProbe), 0);
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 500) > 0) {
      std::array<char, 256> reply{};
      result.answered = recv(fd, reply.data(), reply.size(), 0) > 0;  // refused (ICMP) reads as -1
      result.answered_at_once = result.answered && attempt == 0;
    }
    if (!result.answered) {
      std::this_thread::sleep_until(std::min(next, deadline));
    }
  }
  close(fd);
  result.waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::string how_to_start(const HfoServerConfig& c, const std::string& hfo_root) {
  return "start one first, e.g. /usr/bin/python3 " + hfo_root + "/bin/HFO --offense-agents 1" +
         (c.opponents > 0 ? " --defense-npcs " + std::to_string(c.opponents) : std::string()) +
         " --fullstate --headless --no-logging --frames-per-trial " + std::to_string(c.max_steps) + " --port " +
         std::to_string(c.port) +
         " --seed S (python3: bin/HFO's '#!/usr/bin/env python' finds no 'python' on Debian 12), and connect after "
         "its line 'Waiting for player-controlled agent' (one server per env, ports at least 3 apart; "
         "docs/hfo-server.md)";
}

std::string no_server_message(const HfoServerConfig& c, const std::string& hfo_root) {
  return "hfo-server: no HFO server answers at " + c.host + ":" + std::to_string(c.port) + " (waited " +
         std::to_string(c.connect_timeout_s) + " s, env.server_connect_timeout_s); " + how_to_start(c, hfo_root);
}

}  // namespace pamdp::hfo_server
