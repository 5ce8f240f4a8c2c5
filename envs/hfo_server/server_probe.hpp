// Waiting for an HFO server before HFO's client library joins it. Built in every build (plain
// UDP, no HFO), so the waiting and its error are tested everywhere.
//
// Why the adapter probes first: HFO's client (HFOEnvironment::connectToServer) has no error
// return. With no server it sends its (init), waits librcsc's server_wait_seconds (5 s), prints
// "waited 5 seconds. server down??" and "[ConnectToServer] Server Down!" and calls exit(1).
// With a server that is still starting it does worse: bin/HFO's trainer fills the NPC slots
// 1-10 one at a time before it waits for the agent (unum 11); an agent that joins meanwhile takes
// a low unum, the trainer disconnects it as one of its NPCs, the client exits the same way, and
// the server is left waiting for an agent that never comes (measured: docs/hfo-server.md).
#pragma once

#include <string>

#include "envs/hfo_server/hfo_server_env.hpp"

namespace pamdp::hfo_server {

struct ServerProbe {
  bool answered = false;
  bool answered_at_once = false;  // the first datagram was answered: the server was already up
  double waited_s = 0.0;
};

// Sends a datagram rcssserver answers on its player port ("(error unknown_command)", without
// joining its game) to host:port every 0.5 s until it answers or `timeout_s` seconds pass.
// Throws std::runtime_error for a host that does not resolve. Blocks; opens one socket.
ServerProbe probe_server(const std::string& host, int port, double timeout_s);

// How to start the server `c` expects, with HFO built at `hfo_root` (one line, for errors).
std::string how_to_start(const HfoServerConfig& c, const std::string& hfo_root);

// The error when no server answered within c.connect_timeout_s: names host:port, the wait, the
// key that sets it and how to start a server.
std::string no_server_message(const HfoServerConfig& c, const std::string& hfo_root);

}  // namespace pamdp::hfo_server
