// The HTTP seam of the metrics: serves a Registry's text exposition at GET /metrics, and fetches
// such a page (pamdp monitor). Only core/metrics_http.cpp includes cpp-httplib.
//
// MetricsHttpServer binds in its constructor (port 0 = a free port, read back with port()) and
// answers on a thread of its own (plus one worker); each scrape renders the registry on that
// thread. Connections are closed after every answer, so a scraper holding a connection open
// never keeps another from being served. Destroy it before the registry.
// Errors: a bind that fails (port in use, an address not on this machine) throws
// std::runtime_error naming the address and the fix.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "core/metrics.hpp"

namespace pamdp::metrics {

class MetricsHttpServer {
 public:
  // bind: an address of this machine ("127.0.0.1", "0.0.0.0", "::"); a wildcard is advertised in
  // url() as advertise_host (empty: this machine's host name).
  MetricsHttpServer(const Registry& registry, const std::string& bind, int port,
                    const std::string& advertise_host = "");
  ~MetricsHttpServer();
  MetricsHttpServer(const MetricsHttpServer&) = delete;
  MetricsHttpServer& operator=(const MetricsHttpServer&) = delete;

  [[nodiscard]] int port() const;
  // http://HOST:PORT/metrics, as other machines (or this one) reach it.
  [[nodiscard]] const std::string& url() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// GET `url` (http://host:port/path). Returns the body of a 200 answer; otherwise nullopt with the
// reason in *error (when given). Waits at most about timeout_ms to connect and as long to read.
std::optional<std::string> http_get(const std::string& url, int timeout_ms, std::string* error = nullptr);

// The host part of an advertised URL for a bound address: wildcards become advertise_host (or
// this machine's host name when that is empty); IPv6 literals get brackets.
std::string url_host(const std::string& bind, const std::string& advertise_host);

}  // namespace pamdp::metrics
