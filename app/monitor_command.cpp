// `pamdp monitor`: a live terminal view of a whole cluster from the processes' /metrics pages.
// The URLs come from the learner (--join: a MetricsUrlsRequest on its join socket, asked again
// every few seconds so that new actors appear) or from the command line. Every refresh scrapes all
// of them in parallel; rates are counter deltas between two scrapes. Plain ANSI escape codes, so it
// works over ssh; raw keyboard mode (termios) only when stdin is a terminal, restored on exit.
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "app/cli_checks.hpp"
#include "app/commands.hpp"
#include "core/metrics.hpp"
#include "core/metrics_http.hpp"
#include "core/transport.hpp"
#include "core/wire.hpp"

namespace pamdp::app {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr size_t kHistory = 60;  // sparkline points (one per refresh)
// A peer silent this long is marked (pamdp_peer_silence_seconds). Peers send heartbeats every
// cluster.heartbeat_ms (1 s by default), so with one refresh a second a peer that falls silent is
// marked within about 4 s.
constexpr double kSilentSeconds = 3.0;

std::atomic<bool> g_quit{false};
extern "C" void on_monitor_signal(int /*sig*/) {
  g_quit.store(true);
}

struct MonitorOptions {
  std::string join;
  std::vector<std::string> urls;
  std::string curve_keys;
  bool once = false;
  bool json = false;
  double interval_s = 1.0;
  int timeout_ms = 800;
};

// Asks the learner for the cluster's metrics URLs over its join socket.
class UrlSource {
 public:
  UrlSource(net::Context& ctx, const MonitorOptions& o) : socket_(ctx, net::SocketType::kDealer) {
    socket_.set_max_message_bytes(4 << 20);
    socket_.set_linger_ms(0);
    if (!o.curve_keys.empty()) {
      socket_.make_curve_client(net::load_curve_keyring(o.curve_keys, /*need_server=*/false).client);
    }
    socket_.connect(o.join);
  }
  // nullopt if the learner did not answer within timeout_ms.
  std::optional<std::vector<std::string>> fetch(int timeout_ms) {
    wire::build_metrics_urls_request(fbb_);
    if (!socket_.send(wire::bytes_of(fbb_), timeout_ms)) {
      return std::nullopt;
    }
    const auto until = Clock::now() + std::chrono::milliseconds(timeout_ms);
    while (Clock::now() < until && !g_quit.load()) {
      if (!socket_.recv(msg_, 50) || socket_.too_big(msg_)) {
        continue;
      }
      const wire::Envelope* env = wire::open_envelope(msg_.bytes());
      if (env == nullptr || env->payload_type() != wire::Payload::MetricsUrls) {
        continue;  // a stale answer or something else: keep waiting
      }
      std::vector<std::string> urls;
      if (const auto* list = env->payload_as_MetricsUrls()->urls()) {
        for (const flatbuffers::String* u : *list) {
          if (u != nullptr && u->size() > 0) {
            urls.push_back(u->str());
          }
        }
      }
      return urls;
    }
    return std::nullopt;
  }

 private:
  net::Socket socket_;
  net::Message msg_;
  flatbuffers::FlatBufferBuilder fbb_{256};
};

struct Target {
  std::string url;
  std::string role = "?";
  std::string name;
  bool up = false;
  std::string error;
  std::map<std::string, double> now;   // "name{labels}" -> value, newest scrape
  std::map<std::string, double> prev;  // the scrape before
  Clock::time_point at{}, prev_at{};

  [[nodiscard]] double get(const std::string& key) const {
    const auto it = now.find(key);
    return it == now.end() ? kNaN : it->second;
  }
  [[nodiscard]] bool has(const std::string& key) const { return now.count(key) != 0; }
  // Per second between the last two scrapes; NaN without two scrapes; 0 after a counter reset.
  [[nodiscard]] double rate(const std::string& key) const {
    const auto a = prev.find(key);
    const auto b = now.find(key);
    const double dt = std::chrono::duration<double>(at - prev_at).count();
    if (a == prev.end() || b == now.end() || dt <= 0.0) {
      return kNaN;
    }
    return b->second >= a->second ? (b->second - a->second) / dt : 0.0;
  }
};

std::string key_of(const metrics::Sample& s) {
  std::string k = s.name;
  for (const auto& [l, v] : s.labels) {
    k += (k.size() == s.name.size() ? "{" : ",") + l + "=\"" + v + "\"";
  }
  return s.labels.empty() ? k : k + "}";
}

void scrape(std::vector<Target>& targets, int timeout_ms) {
  std::vector<std::future<std::pair<std::optional<std::string>, std::string>>> pending;
  pending.reserve(targets.size());
  for (const Target& t : targets) {
    pending.push_back(std::async(std::launch::async, [url = t.url, timeout_ms] {
      std::string error;
      auto body = metrics::http_get(url, timeout_ms, &error);
      return std::make_pair(std::move(body), std::move(error));
    }));
  }
  for (size_t i = 0; i < targets.size(); ++i) {
    Target& t = targets[i];
    auto [body, error] = pending[i].get();
    t.prev = std::move(t.now);
    t.prev_at = t.at;
    t.now.clear();
    t.at = Clock::now();
    t.up = body.has_value();
    t.error = error;
    if (!body) {
      t.prev.clear();
      continue;
    }
    for (const metrics::Sample& s : metrics::parse_exposition(*body)) {
      if (s.name == "pamdp_process_info") {
        if (const std::string* r = s.label("role")) {
          t.role = *r;
        }
        if (const std::string* n = s.label("name")) {
          t.name = *n;
        }
      }
      t.now[key_of(s)] = s.value;
    }
  }
}

// Sums over targets, skipping NaN (a target that lacks the metric).
template <typename F>
double sum_of(const std::vector<Target>& ts, F f) {
  double total = 0.0;
  bool any = false;
  for (const Target& t : ts) {
    const double v = f(t);
    if (t.up && !std::isnan(v)) {
      total += v;
      any = true;
    }
  }
  return any ? total : kNaN;
}

// The first up target of these roles that has `key`, in the order given.
double first_of(const std::vector<Target>& ts, std::initializer_list<const char*> roles, const std::string& key) {
  for (const char* role : roles) {
    for (const Target& t : ts) {
      if (t.up && t.role == role && t.has(key)) {
        return t.get(key);
      }
    }
  }
  return kNaN;
}

struct View {
  nlohmann::json json;
  std::vector<std::string> lines;
};

std::string num(double v, int decimals = 0) {
  if (std::isnan(v)) {
    return "-";
  }
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  // Thousands separators in the integer part.
  std::string s(buf);
  const size_t dot = s.find('.');
  size_t end = dot == std::string::npos ? s.size() : dot;
  const size_t begin = (s[0] == '-') ? 1 : 0;
  for (size_t i = end; i > begin + 3; i -= 3) {
    s.insert(i - 3, ",");
  }
  return s;
}

std::string sig(double v) {
  if (std::isnan(v)) {
    return "-";
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

std::string sparkline(const std::vector<double>& h) {
  static const char* const kBars[] = {"▁", "▂", "▃", "▄", "▅", "▆", "▇", "█"};
  double lo = INFINITY;
  double hi = -INFINITY;
  for (const double v : h) {
    if (!std::isnan(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  std::string out;
  for (const double v : h) {
    if (std::isnan(v)) {
      out += " ";
      continue;
    }
    const int level = hi > lo ? static_cast<int>(std::lround((v - lo) / (hi - lo) * 7.0)) : 3;
    out += kBars[std::clamp(level, 0, 7)];
  }
  return out;
}

nlohmann::json jnum(double v) {
  return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v);
}

// Calls f(target, peer, value) for each series `metric{peer="PEER"}` of each target that is up.
template <typename F>
void for_each_peer_series(const std::vector<Target>& ts, const std::string& metric, F f) {
  const std::string prefix = metric + "{peer=\"";
  for (const Target& t : ts) {
    if (!t.up) {
      continue;
    }
    for (const auto& [key, value] : t.now) {
      if (key.rfind(prefix, 0) == 0) {
        f(t, key.substr(prefix.size(), key.size() - prefix.size() - 2), value);
      }
    }
  }
}

View build_view(const std::vector<Target>& ts, std::vector<double>& return_history, std::vector<double>& goal_history) {
  std::map<std::string, int> roles;
  int up = 0;
  for (const Target& t : ts) {
    if (t.up) {
      ++up;
      ++roles[t.role];
    }
  }
  const double steps_ps = sum_of(ts, [](const Target& t) { return t.rate("pamdp_env_steps_total"); });
  const double inserts_ps =
      sum_of(ts, [](const Target& t) { return t.rate("pamdp_replay_transitions_inserted_total"); });
  const double samples_ps =
      sum_of(ts, [](const Target& t) { return t.rate("pamdp_replay_transitions_sampled_total"); });
  const double updates_ps = sum_of(ts, [](const Target& t) { return t.rate("pamdp_updates_total"); });
  const double replay_size = sum_of(ts, [](const Target& t) { return t.get("pamdp_replay_size_transitions"); });
  const double replay_cap = sum_of(ts, [](const Target& t) { return t.get("pamdp_replay_capacity_transitions"); });
  const double fill = replay_cap > 0.0 ? replay_size / replay_cap : kNaN;
  const double held = sum_of(ts, [](const Target& t) { return t.get("pamdp_replay_inserts_held"); });
  const double bad = sum_of(ts, [](const Target& t) { return t.get("pamdp_bad_messages_total"); });
  const int actors_alive = roles.count("actor") != 0 ? roles["actor"] : 0;
  const double learner_actors = first_of(ts, {"learner"}, "pamdp_learner_peers_connected{role=\"actor\"}");

  // Episodes: the learner sees every actor's; a single-process run counts its own.
  double episodes = first_of(ts, {"learner"}, "pamdp_cluster_episodes_total");
  double goal_rate = first_of(ts, {"learner"}, "pamdp_cluster_goal_rate_100");
  double mean_return = first_of(ts, {"learner"}, "pamdp_cluster_episode_return_mean_100");
  if (std::isnan(episodes)) {
    episodes = first_of(ts, {"train"}, "pamdp_episodes_total");
    goal_rate = first_of(ts, {"train"}, "pamdp_goal_rate_100");
    mean_return = first_of(ts, {"train"}, "pamdp_episode_return_mean_100");
  }
  const double updates = first_of(ts, {"learner", "train"}, "pamdp_updates_total");
  const double loss = first_of(ts, {"learner", "train"}, "pamdp_critic_loss");
  const double q = first_of(ts, {"learner", "train"}, "pamdp_q_mean");
  const double at_bound = first_of(ts, {"learner", "train"}, "pamdp_actor_params_at_bound_ratio");
  double eps = first_of(ts, {"learner"}, "pamdp_learner_epsilon");
  if (std::isnan(eps)) {
    eps = first_of(ts, {"train", "actor"}, "pamdp_epsilon");
  }
  const double version = first_of(ts, {"learner"}, "pamdp_learner_weights_version");
  double age_max = kNaN;
  double age_sum = 0.0;
  int age_n = 0;
  for (const Target& t : ts) {
    const double a = t.get("pamdp_actor_weights_age_updates");
    if (t.up && !std::isnan(a)) {
      age_max = std::isnan(age_max) ? a : std::max(age_max, a);
      age_sum += a;
      ++age_n;
    }
  }
  const double age_mean = age_n > 0 ? age_sum / age_n : kNaN;

  return_history.push_back(mean_return);
  goal_history.push_back(goal_rate);
  if (return_history.size() > kHistory) {
    return_history.erase(return_history.begin());
    goal_history.erase(goal_history.begin());
  }

  View v;
  nlohmann::json& j = v.json;
  j["targets"] = ts.size();
  j["up"] = up;
  j["roles"] = roles;
  j["env_steps_per_s"] = jnum(steps_ps);
  j["inserts_per_s"] = jnum(inserts_ps);
  j["samples_per_s"] = jnum(samples_ps);
  j["updates_per_s"] = jnum(updates_ps);
  j["actors_alive"] = actors_alive;
  j["learner_actors_connected"] = jnum(learner_actors);
  j["replay_size"] = jnum(replay_size);
  j["replay_capacity"] = jnum(replay_cap);
  j["replay_fill"] = jnum(fill);
  j["replay_shards_rate_limited"] = jnum(held);
  j["updates"] = jnum(updates);
  j["episodes"] = jnum(episodes);
  j["goal_rate_100"] = jnum(goal_rate);
  j["mean_return_100"] = jnum(mean_return);
  j["critic_loss"] = jnum(loss);
  j["q_mean"] = jnum(q);
  j["params_at_bound"] = jnum(at_bound);
  j["epsilon"] = jnum(eps);
  j["weights_version"] = jnum(version);
  j["weights_age_max"] = jnum(age_max);
  j["weights_age_mean"] = jnum(age_mean);
  j["bad_messages"] = jnum(bad);
  nlohmann::json history = nlohmann::json::array();
  for (const double h : return_history) {
    history.push_back(jnum(h));
  }
  j["mean_return_history"] = history;
  nlohmann::json list = nlohmann::json::array();
  for (const Target& t : ts) {
    list.push_back({{"url", t.url}, {"role", t.role}, {"name", t.name}, {"up", t.up}, {"error", t.error}});
  }
  j["target_list"] = list;

  std::string role_list;
  for (const auto& [r, n] : roles) {
    role_list += (role_list.empty() ? "" : ", ") + r + " " + std::to_string(n);
  }
  // Silent links, as the learner sees its peers and as each process sees the learner. (A shard's
  // view of an actor is left out: a shard holding inserts back reads nothing for a while.)
  nlohmann::json silent = nlohmann::json::array();
  std::string silent_list;
  for_each_peer_series(ts, "pamdp_peer_silence_seconds", [&](const Target& t, const std::string& peer, double value) {
    if (value < kSilentSeconds || (t.role != "learner" && peer != "learner")) {
      return;
    }
    silent.push_back({{"observer", t.role + ":" + t.name}, {"peer", peer}, {"silence_s", value}});
    if (silent.size() <= 6) {
      silent_list += (silent_list.empty() ? "" : ", ") + t.role + " -> " + peer + " " + num(value, 1) + " s";
    }
  });
  j["silent_peers"] = silent;
  // Frames refused for size, by whom and from whom (pamdp_peer_frames_refused_for_size_total).
  nlohmann::json oversized = nlohmann::json::array();
  std::string oversized_list;
  for_each_peer_series(ts, "pamdp_peer_frames_refused_for_size_total",
                       [&](const Target& t, const std::string& peer, double value) {
                         if (value <= 0.0) {
                           return;
                         }
                         oversized.push_back({{"observer", t.role + ":" + t.name}, {"peer", peer}, {"frames", value}});
                         if (oversized.size() <= 4) {
                           oversized_list.append(oversized_list.empty() ? "" : ", ").append(peer).append(" -> ");
                           oversized_list.append(t.role).append(" ").append(num(value));
                         }
                       });
  j["oversized_frames"] = oversized;

  auto& L = v.lines;
  L.push_back("pamdp monitor: " + std::to_string(up) + "/" + std::to_string(ts.size()) + " targets up (" + role_list +
              ")");
  L.push_back("");
  L.push_back("throughput  env steps/s " + num(steps_ps) + " | inserts/s " + num(inserts_ps) + " | samples/s " +
              num(samples_ps) + " | updates/s " + num(updates_ps, 1));
  L.push_back("actors      " + std::to_string(actors_alive) + " alive (learner sees " + num(learner_actors) +
              ") | epsilon " + sig(eps) + " | weights v" + num(version) + ", age max " + num(age_max) + " mean " +
              num(age_mean, 1) + " updates");
  L.push_back("replay      " + num(replay_size) + " / " + num(replay_cap) + " transitions (" + num(fill * 100.0, 1) +
              " %) | shards holding inserts back " + num(held));
  L.push_back("learning    updates " + num(updates) + " | critic loss " + sig(loss) + " | mean Q " + sig(q) +
              " | params at bound " + num(at_bound * 100.0, 1) + " %");
  L.push_back("episodes    " + num(episodes) + " | goal rate (last 100) " + sig(goal_rate) +
              " | mean return (last 100) " + sig(mean_return) + " | bad messages " + num(bad));
  std::string links =
      silent.empty() ? std::string("no silent peer") : "SILENT " + std::to_string(silent.size()) + ": " + silent_list;
  if (!oversized.empty()) {
    links.append(" | frames refused for size: ").append(oversized_list);
  }
  L.push_back("links       " + links);
  L.push_back("return      " + sparkline(return_history));
  L.push_back("goal rate   " + sparkline(goal_history));
  L.push_back("");
  for (const Target& t : ts) {
    std::string line = "  " + t.role + std::string(t.role.size() < 8 ? 8 - t.role.size() : 1, ' ') + t.url;
    if (!t.up) {
      line += "  DOWN (" + t.error + ")";
    } else if (t.role == "actor") {
      line += "  steps/s " + num(t.rate("pamdp_env_steps_total")) + " | eps " + sig(t.get("pamdp_epsilon")) +
              " | age " + num(t.get("pamdp_actor_weights_age_updates"));
    } else if (t.role == "replay") {
      line += "  inserts/s " + num(t.rate("pamdp_replay_transitions_inserted_total")) + " | samples/s " +
              num(t.rate("pamdp_replay_transitions_sampled_total")) + " | fill " +
              num(t.get("pamdp_replay_fill_ratio") * 100.0, 1) + " %";
    } else {
      line += "  updates/s " + num(t.rate("pamdp_updates_total"), 1);
    }
    L.push_back(line);
  }
  return v;
}

// Raw keyboard input for the live view: no echo, no line buffering; Ctrl-C still signals.
class TerminalGuard {
 public:
  TerminalGuard() {
    if (isatty(STDIN_FILENO) != 0 && tcgetattr(STDIN_FILENO, &saved_) == 0) {
      termios raw = saved_;
      raw.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));
      raw.c_cc[VMIN] = 0;
      raw.c_cc[VTIME] = 0;
      raw_ = tcsetattr(STDIN_FILENO, TCSANOW, &raw) == 0;
    }
    std::fputs("\x1b[?1049h\x1b[?25l", stdout);  // alternate screen, hidden cursor
    std::fflush(stdout);
  }
  ~TerminalGuard() {
    std::fputs("\x1b[?25h\x1b[?1049l", stdout);
    std::fflush(stdout);
    if (raw_) {
      tcsetattr(STDIN_FILENO, TCSANOW, &saved_);
    }
  }
  TerminalGuard(const TerminalGuard&) = delete;
  TerminalGuard& operator=(const TerminalGuard&) = delete;
  [[nodiscard]] bool raw() const { return raw_; }

 private:
  termios saved_{};
  bool raw_ = false;
};

// Waits up to ms for a key; true if 'q' was pressed (or a quit signal came).
bool wait_for_quit(bool read_keys, int ms) {
  const auto until = Clock::now() + std::chrono::milliseconds(ms);
  while (!g_quit.load()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count();
    if (left <= 0) {
      return false;
    }
    if (!read_keys) {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::min<int64_t>(left, 50)));
      continue;
    }
    pollfd p{STDIN_FILENO, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(std::min<int64_t>(left, 50))) > 0) {
      char c = 0;
      if (::read(STDIN_FILENO, &c, 1) == 1 && (c == 'q' || c == 'Q')) {
        return true;
      }
    }
  }
  return true;
}

void run_monitor(const MonitorOptions& o) {
  if (o.join.empty() == o.urls.empty()) {
    throw std::runtime_error(
        "pamdp monitor needs either --join tcp://LEARNER:PORT or a list of metrics URLs "
        "(http://HOST:PORT/metrics, e.g. from a run directory's metrics_urls.txt)");
  }
  g_quit.store(false);
  std::signal(SIGINT, on_monitor_signal);
  std::signal(SIGTERM, on_monitor_signal);
  const int interval_ms = static_cast<int>(o.interval_s * 1000.0);

  net::Context ctx;
  std::unique_ptr<UrlSource> source;
  std::vector<std::string> urls = o.urls;
  if (!o.join.empty()) {
    source = std::make_unique<UrlSource>(ctx, o);
    std::optional<std::vector<std::string>> got;
    for (int attempt = 0; attempt < 5 && !got && !g_quit.load(); ++attempt) {
      got = source->fetch(1000);
    }
    if (!got) {
      throw std::runtime_error("no answer from the learner at " + o.join +
                               " (is `pamdp learner` running there, and reachable?)");
    }
    urls = *got;
  }
  std::vector<Target> targets;
  auto set_urls = [&](const std::vector<std::string>& list) {
    std::vector<Target> next;
    for (const std::string& u : list) {
      auto it = std::find_if(targets.begin(), targets.end(), [&](const Target& t) { return t.url == u; });
      if (it != targets.end()) {
        next.push_back(std::move(*it));
      } else {
        next.emplace_back().url = u;
      }
    }
    targets = std::move(next);
  };
  set_urls(urls);
  std::vector<double> return_history;
  std::vector<double> goal_history;

  if (o.once) {
    // Two scrapes an interval apart, so that rates have a delta.
    scrape(targets, o.timeout_ms);
    wait_for_quit(false, interval_ms);
    scrape(targets, o.timeout_ms);
    const View v = build_view(targets, return_history, goal_history);
    if (o.json) {
      std::printf("%s\n", v.json.dump().c_str());
    } else {
      for (const std::string& line : v.lines) {
        std::printf("%s\n", line.c_str());
      }
    }
    return;
  }

  std::optional<TerminalGuard> terminal;
  if (!o.json) {
    terminal.emplace();
  }
  const bool read_keys = terminal && terminal->raw();
  auto last_urls = Clock::now();
  scrape(targets, o.timeout_ms);
  while (!wait_for_quit(read_keys, interval_ms)) {
    if (source && Clock::now() - last_urls >= std::chrono::seconds(5)) {
      last_urls = Clock::now();
      if (auto got = source->fetch(o.timeout_ms)) {
        set_urls(*got);
      }
    }
    scrape(targets, o.timeout_ms);
    const View v = build_view(targets, return_history, goal_history);
    if (o.json) {
      std::printf("%s\n", v.json.dump().c_str());
    } else {
      std::string frame = "\x1b[H";
      for (const std::string& line : v.lines) {
        frame += line + "\x1b[K\n";
      }
      frame += "\x1b[K\nq or Ctrl-C quits\x1b[J";
      std::fputs(frame.c_str(), stdout);
    }
    std::fflush(stdout);
  }
}

}  // namespace

void register_monitor(CLI::App& app) {
  auto o = std::make_shared<MonitorOptions>();
  CLI::App* cmd = app.add_subcommand(
      "monitor", "live view of a cluster's metrics: pamdp monitor --join tcp://LEARNER:PORT, or pamdp monitor URL...");
  cmd->add_option("--join", o->join, "the learner's join endpoint; it lists every process's metrics URL")
      ->check(zmq_endpoint());
  cmd->add_option("urls", o->urls, "metrics URLs (http://HOST:PORT/metrics), instead of --join");
  cmd->add_option("--curve-keys", o->curve_keys, "directory with client.keys (pamdp keygen), for a CURVE cluster");
  cmd->add_flag("--once", o->once, "print one frame (two scrapes an interval apart) without escape codes and exit");
  cmd->add_flag("--json", o->json, "print the frame as one JSON object per line (with --once: one line)");
  cmd->add_option("--interval", o->interval_s, "seconds between refreshes")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  cmd->add_option("--timeout-ms", o->timeout_ms, "HTTP timeout per scrape")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  cmd->callback([o] { run_monitor(*o); });
}

}  // namespace pamdp::app
