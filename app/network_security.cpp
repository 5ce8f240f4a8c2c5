#include "app/network_security.hpp"

#include <stdexcept>

#include "core/log.hpp"
#include "core/transport.hpp"

namespace pamdp::app {

bool check_network_exposure(const SecurityOptions& o, const std::vector<ClusterEndpoint>& endpoints, bool curve,
                            bool insecure) {
  if (curve) {
    if (insecure) {
      log::info("{}: CURVE is on, so the insecure setting has no effect", o.role);
    }
    return false;
  }
  for (const ClusterEndpoint& e : endpoints) {
    if (net::is_loopback_endpoint(e.endpoint) || insecure) {
      continue;
    }
    throw std::runtime_error(o.role + ": " + e.option + " " + e.endpoint +
                             " reaches beyond this machine and CURVE is off, so " + o.risk +
                             ". Either turn on CURVE (run `pamdp keygen --dir keys` once, then " + o.curve_fix +
                             "), or, on a trusted private network only, say so with " + o.insecure_fix + "; or " +
                             o.loopback_fix + " to stay on this machine");
  }
  return insecure;
}

void check_advertise_host(const SecurityOptions& o, const std::string& advertise_option,
                          const std::string& advertise_host, const std::vector<ClusterEndpoint>& binds) {
  if (net::is_loopback_endpoint("tcp://" + advertise_host + ":1")) {
    return;
  }
  std::string list;
  for (const ClusterEndpoint& b : binds) {
    if (!net::is_loopback_endpoint(b.endpoint)) {
      return;
    }
    list += list.empty() ? "" : ", ";
    list += b.option + " " + b.endpoint;
  }
  throw std::runtime_error(o.role + ": " + advertise_option + " " + advertise_host +
                           " tells other machines where to connect, but every cluster socket binds loopback only (" +
                           list +
                           "; the default since issue 33), so they could not. Bind an address they can reach "
                           "(e.g. tcp://" +
                           advertise_host + ":PORT or tcp://*:PORT) and turn on CURVE (" + o.curve_fix +
                           ") or, on a trusted private network, " + o.insecure_fix);
}

void export_security_mode(metrics::Registry& r, const SecurityOptions& o, bool insecure,
                          const std::vector<ClusterEndpoint>& endpoints) {
  r.gauge("pamdp_security_insecure",
          "1 when this process runs its cluster sockets without CURVE on the network because insecure mode was "
          "asked for (cluster.insecure / --insecure)")
      .set(insecure ? 1.0 : 0.0);
  if (!insecure) {
    return;
  }
  std::string list;
  for (const ClusterEndpoint& e : endpoints) {
    list += list.empty() ? "" : ", ";
    list += e.endpoint;
  }
  log::warn(
      "{}: INSECURE: CURVE is off and insecure mode is on ({}): {} accept(s) unauthenticated, unencrypted peers; "
      "anyone on this network can insert transitions, join as a shard or read the weights. Use this on a trusted "
      "private network only; `pamdp keygen` and CURVE remove the risk",
      o.role, o.insecure_fix, list);
}

}  // namespace pamdp::app
