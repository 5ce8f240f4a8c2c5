// Stands in for hfo_server_env.cpp in builds without HFO: the env name stays a valid config
// choice, and making one says how to get it.
#include <stdexcept>

#include "envs/hfo_server/hfo_server_env.hpp"

namespace pamdp::hfo_server {

bool built_with_hfo() {
  return false;
}

std::unique_ptr<Env> make_hfo_server_env(const HfoServerConfig& /*config*/) {
  throw std::runtime_error(
      "env 'hfo-server' is not built in: rebuild with -DHFO_ROOT=/path/to/HFO (an HFO build with src/HFO.hpp "
      "and lib/libhfo.so; see docs/hfo-server.md)");
}

}  // namespace pamdp::hfo_server
