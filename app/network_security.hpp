// Secure by default (docs/protocol.md, "Security"): the check every cluster role makes at
// start-up, before it binds or connects, that no cluster socket talks to the network without
// CURVE unless the operator said so (cluster.insecure = true, or --insecure for `pamdp replay`
// and `pamdp actor`), and the gauge and warning that say so when they did.
#pragma once

#include <string>
#include <vector>

#include "core/metrics.hpp"

namespace pamdp::app {

// One cluster endpoint a role binds or connects, with the option that set it (for the error).
struct ClusterEndpoint {
  std::string option;  // e.g. "cluster.learner_bind", "--insert-bind", "--join"
  std::string endpoint;
};

// How a role turns on CURVE and insecure mode, for the error text.
struct SecurityOptions {
  std::string role;          // "learner", "replay", "actor"
  std::string curve_fix;     // e.g. "--set cluster.curve=true --set cluster.curve_keys_dir=keys"
  std::string insecure_fix;  // e.g. "--set cluster.insecure=true"
  std::string loopback_fix;  // e.g. "bind tcp://127.0.0.1:PORT" (what keeps it on this machine)
  std::string risk = "anyone who can reach it could join the cluster, insert transitions or read the weights";
};

// Throws std::runtime_error naming the first endpoint that is not loopback and the fixes (pamdp
// keygen plus CURVE, or insecure on a trusted private network), unless `curve` or `insecure` is
// set. Returns true when the process runs insecure (insecure set, CURVE off): the caller then
// calls warn_insecure(). Cost: string compares, start-up only.
bool check_network_exposure(const SecurityOptions& o, const std::vector<ClusterEndpoint>& endpoints, bool curve,
                            bool insecure);

// An advertise host that is not loopback while every bind is: peers on other machines could not
// connect. Throws std::runtime_error naming both and the fix.
void check_advertise_host(const SecurityOptions& o, const std::string& advertise_option,
                          const std::string& advertise_host, const std::vector<ClusterEndpoint>& binds);

// Logs the one warning of an insecure process and registers pamdp_security_insecure (1 when
// insecure, else 0) in its registry.
void export_security_mode(metrics::Registry& r, const SecurityOptions& o, bool insecure,
                          const std::vector<ClusterEndpoint>& endpoints);

}  // namespace pamdp::app
