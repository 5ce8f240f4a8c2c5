#include "core/metrics_http.hpp"

#include <httplib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <thread>

namespace pamdp::metrics {
namespace {

bool is_wildcard(const std::string& host) {
  return host.empty() || host == "*" || host == "0.0.0.0" || host == "::" || host == "[::]";
}

std::string strip_brackets(const std::string& host) {
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    return host.substr(1, host.size() - 2);
  }
  return host;
}

}  // namespace

std::string url_host(const std::string& bind, const std::string& advertise_host) {
  std::string host = strip_brackets(bind);
  if (is_wildcard(host)) {
    host = advertise_host;
    if (host.empty()) {
      char name[256] = {};
      host = gethostname(name, sizeof(name) - 1) == 0 && name[0] != '\0' ? name : "localhost";
    }
    host = strip_brackets(host);
  }
  return host.find(':') != std::string::npos ? "[" + host + "]" : host;
}

struct MetricsHttpServer::Impl {
  httplib::Server server;
  std::thread thread;
  int port = 0;
  std::string url;
};

MetricsHttpServer::MetricsHttpServer(const Registry& registry, const std::string& bind, int port,
                                     const std::string& advertise_host)
    : impl_(std::make_unique<Impl>()) {
  if (port < 0 || port > 65535) {
    throw std::runtime_error("metrics: port " + std::to_string(port) + " is not within 0..65535");
  }
  httplib::Server& s = impl_->server;
  // Two workers: a scrape never waits behind another, and an idle process keeps few threads.
  s.new_task_queue = [] { return new httplib::ThreadPool(2); };
  s.set_keep_alive_max_count(1);
  // cpp-httplib's default sets SO_REUSEPORT, which lets a second process bind a port in use and
  // share its scrapes; SO_REUSEADDR alone makes that an error and still allows quick restarts.
  s.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  s.set_read_timeout(std::chrono::seconds(5));
  s.set_write_timeout(std::chrono::seconds(5));
  s.Get("/metrics", [&registry](const httplib::Request&, httplib::Response& res) {
    res.set_content(registry.render(), "text/plain; version=0.0.4; charset=utf-8");
  });
  s.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content("pamdp: metrics at /metrics (Prometheus text format 0.0.4)\n", "text/plain");
  });
  const std::string host = is_wildcard(strip_brackets(bind)) && strip_brackets(bind).find(':') == std::string::npos
                               ? std::string("0.0.0.0")
                               : strip_brackets(bind);
  if (port == 0) {
    impl_->port = s.bind_to_any_port(host);
  } else {
    impl_->port = s.bind_to_port(host, port) ? port : -1;
  }
  if (impl_->port <= 0) {
    throw std::runtime_error("metrics: cannot serve HTTP on " + host + ":" + std::to_string(port) +
                             " (port in use, or an address not on this machine); choose another with "
                             "--metrics-port / --metrics-bind or [metrics] port / bind (port 0 = any free port)");
  }
  impl_->url = "http://" + url_host(bind, advertise_host) + ":" + std::to_string(impl_->port) + "/metrics";
  impl_->thread = std::thread([this] { impl_->server.listen_after_bind(); });
}

MetricsHttpServer::~MetricsHttpServer() {
  // stop() only takes effect once the accept loop runs; the socket is bound and listening
  // already, so that happens at once after the thread starts.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (!impl_->server.is_running() && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  impl_->server.stop();
  if (impl_->thread.joinable()) {
    impl_->thread.join();
  }
}

int MetricsHttpServer::port() const {
  return impl_->port;
}

const std::string& MetricsHttpServer::url() const {
  return impl_->url;
}

std::optional<std::string> http_get(const std::string& url, int timeout_ms, std::string* error) {
  auto fail = [&](std::string why) -> std::optional<std::string> {
    if (error != nullptr) {
      *error = std::move(why);
    }
    return std::nullopt;
  };
  const std::string scheme = "http://";
  if (url.rfind(scheme, 0) != 0) {
    return fail("not an http:// URL");
  }
  const size_t slash = url.find('/', scheme.size());
  const std::string origin = slash == std::string::npos ? url : url.substr(0, slash);
  const std::string path = slash == std::string::npos ? "/" : url.substr(slash);
  httplib::Client client(origin);
  const auto timeout = std::chrono::milliseconds(std::max(1, timeout_ms));
  client.set_connection_timeout(timeout);
  client.set_read_timeout(timeout);
  client.set_keep_alive(false);
  const httplib::Result res = client.Get(path);
  if (!res) {
    return fail(httplib::to_string(res.error()));
  }
  if (res->status != 200) {
    return fail("HTTP status " + std::to_string(res->status));
  }
  return res->body;
}

}  // namespace pamdp::metrics
