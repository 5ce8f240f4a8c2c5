#include "learner/run_logs.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/files.hpp"
#include "core/log.hpp"

namespace pamdp {
namespace fs = std::filesystem;

namespace {

std::string join(const std::vector<std::string>& columns) {
  std::string line;
  for (const std::string& c : columns) {
    if (!line.empty()) {
      line += ',';
    }
    line += c;
  }
  return line;
}

// Rows whose integer in column `column` is at most `limit` (a resumed run's counters).
struct KeepUpTo {
  size_t column = 0;
  int64_t limit = 0;
};

// The integer at the start of field `column` of a CSV row without quoting; nullopt when the row
// is shorter or the field is not a number (a row cut off by a kill).
std::optional<int64_t> field_as_integer(const std::string& row, size_t column) {
  size_t begin = 0;
  for (size_t i = 0; i < column; ++i) {
    begin = row.find(',', begin);
    if (begin == std::string::npos) {
      return std::nullopt;
    }
    ++begin;
  }
  int64_t value = 0;
  const char* first = row.data() + begin;
  const char* last = row.data() + row.size();
  const auto [end, ec] = std::from_chars(first, last, value);
  if (ec != std::errc() || (end != last && *end != ',')) {
    return std::nullopt;
  }
  return value;
}

// Rewrites `path` (header first) without the rows past `keep` or of the wrong width; returns how
// many rows were dropped.
size_t drop_rows_past(const fs::path& path, const std::string& header, const KeepUpTo& keep) {
  std::ifstream in(path);
  std::string kept = header + '\n';
  std::string row;
  std::getline(in, row);  // the header, checked by the caller
  const auto fields = [](const std::string& line) { return std::count(line.begin(), line.end(), ',') + 1; };
  const auto width = fields(header);
  size_t dropped = 0;
  while (std::getline(in, row)) {
    const std::optional<int64_t> v = field_as_integer(row, keep.column);
    if (v && *v <= keep.limit && fields(row) == width) {
      kept += row;
      kept += '\n';
    } else {
      ++dropped;
    }
  }
  in.close();
  if (dropped > 0) {
    write_file_atomically(path.string(), kept.data(), kept.size());
  }
  return dropped;
}

// Cuts `path` back to just after its last newline and returns how many bytes went. A kill can
// leave the last row unfinished, even one that lacks only its newline: a row appended after it
// would run into it, and the file would hold two rows on one line.
std::uintmax_t drop_unfinished_row(const fs::path& path) {
  const std::uintmax_t size = fs::file_size(path);
  std::ifstream in(path, std::ios::binary);
  constexpr std::uintmax_t kChunk = 4096;
  std::string chunk;
  for (std::uintmax_t end = size; end > 0;) {
    const std::uintmax_t begin = end > kChunk ? end - kChunk : 0;
    chunk.resize(end - begin);
    in.seekg(static_cast<std::streamoff>(begin));
    if (!in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()))) {
      throw std::runtime_error("cannot read '" + path.string() + "': check the run directory's permissions");
    }
    const size_t newline = chunk.rfind('\n');
    if (newline != std::string::npos) {
      const std::uintmax_t keep = begin + newline + 1;
      if (keep < size) {
        fs::resize_file(path, keep);
      }
      return size - keep;
    }
    end = begin;
  }
  fs::resize_file(path, 0);
  return size;
}

// Writes the rows gathered in `pending` with one write, so that the file only ever grows by whole
// rows (a reader of a live run never sees half a row), and empties `pending`.
void write_rows(std::ostringstream& pending, std::ofstream& out) {
  const std::string_view rows = pending.view();
  if (rows.empty()) {
    return;
  }
  out.write(rows.data(), static_cast<std::streamsize>(rows.size()));
  out.flush();
  pending.str(std::string());
}

// Opens `path` for appending with `header` as its first line. A file that exists with another
// header (an older format) is moved aside rather than mixed with rows of this format; with
// `keep`, the rows past it are dropped first.
std::ofstream open_csv(const fs::path& path, const std::string& header, std::optional<KeepUpTo> keep) {
  bool fresh = !fs::exists(path) || fs::file_size(path) == 0;
  if (!fresh) {
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    in.close();
    if (first != header) {
      const fs::path aside = path.string() + ".old-format";
      fs::rename(path, aside);
      log::warn("{} has another column layout; moved it to {} and started a new one", path.string(), aside.string());
      fresh = true;
    } else if (const std::uintmax_t cut = drop_unfinished_row(path); fs::file_size(path) == 0) {
      fresh = true;  // not even the header was whole
    } else if (cut > 0) {
      log::info("{}: removed an unfinished last row ({} bytes) that a killed run left", path.string(), cut);
    }
    if (!fresh && keep) {
      const size_t dropped = drop_rows_past(path, header, *keep);
      if (dropped > 0) {
        log::info("{}: dropped {} rows written after the checkpoint (the resumed run writes them again)", path.string(),
                  dropped);
      }
    }
  }
  std::ofstream out(path, std::ios::app);
  if (!out) {
    throw std::runtime_error("cannot write '" + path.string() + "': check that the run directory is writable");
  }
  if (fresh) {
    out << header << '\n';
  }
  return out;
}

}  // namespace

const std::vector<std::string>& RunLogs::metric_columns() {
  static const std::vector<std::string> columns = {"wall_seconds",      "updates",
                                                   "env_steps",         "episodes",
                                                   "epsilon",           "success_rate_100",
                                                   "mean_return_100",   "mean_steps_100",
                                                   "critic_loss",       "q_mean",
                                                   "updates_per_s",     "env_steps_per_s",
                                                   "eval_success_rate", "eval_avg_steps_to_success",
                                                   "eval_avg_return"};
  return columns;
}

const std::vector<std::string>& RunLogs::episode_columns() {
  static const std::vector<std::string> columns = {"episode", "wall_seconds", "updates",         "actor", "return",
                                                   "steps",   "outcome",      "weights_version", "policy"};
  return columns;
}

RunLogs::RunLogs(const fs::path& dir, std::vector<std::string> extra_metric_columns,
                 std::optional<ResumePoint> resume_at)
    : extras_(std::move(extra_metric_columns)) {
  std::vector<std::string> columns = metric_columns();
  columns.insert(columns.end(), extras_.begin(), extras_.end());
  std::optional<KeepUpTo> metrics_keep;
  std::optional<KeepUpTo> episodes_keep;
  if (resume_at) {
    metrics_keep = KeepUpTo{1, resume_at->updates};  // the "updates" column
    // The "episode" column; without a limit only a row cut off by the kill goes.
    episodes_keep = KeepUpTo{0, resume_at->episodes.value_or(std::numeric_limits<int64_t>::max())};
  }
  metrics_file_ = open_csv(dir / "metrics.csv", join(columns), metrics_keep);
  episodes_file_ = open_csv(dir / "episodes.csv", join(episode_columns()), episodes_keep);
}

void RunLogs::metrics(const MetricsRow& r, std::span<const double> extras) {
  if (extras.size() != extras_.size()) {
    throw std::logic_error("RunLogs::metrics: wrong number of extra columns");
  }
  metrics_pending_ << r.wall_seconds << ',' << r.updates << ',' << r.env_steps << ',' << r.episodes << ',';
  if (r.epsilon) {
    metrics_pending_ << *r.epsilon;
  }
  metrics_pending_ << ',' << r.success_rate_100 << ',' << r.mean_return_100 << ',' << r.mean_steps_100 << ','
                   << r.critic_loss << ',' << r.q_mean << ',' << r.updates_per_s << ',' << r.env_steps_per_s << ',';
  if (r.eval) {
    metrics_pending_ << r.eval->goal_rate << ',' << r.eval->avg_steps_to_goal << ',' << r.eval->avg_return;
  } else {
    metrics_pending_ << ",,";
  }
  for (const double v : extras) {
    metrics_pending_ << ',' << v;
  }
  metrics_pending_ << '\n';
  flush();
}

void RunLogs::episode(const EpisodeRow& r) {
  episodes_pending_ << r.episode << ',' << r.wall_seconds << ',' << r.updates << ',' << r.actor << ',' << r.ret << ','
                    << r.steps << ',' << r.outcome << ',' << r.weights_version << ','
                    << (r.scripted ? "scripted" : "agent") << '\n';
  if (episodes_pending_.tellp() >= kEpisodeBytesPerWrite) {
    write_rows(episodes_pending_, episodes_file_);
  }
}

void RunLogs::flush() {
  write_rows(metrics_pending_, metrics_file_);
  write_rows(episodes_pending_, episodes_file_);
}

RunLogs::~RunLogs() {
  flush();
}

void for_each_logged_episode(const fs::path& dir, const std::function<void(const LoggedEpisode&)>& visit) {
  std::ifstream in(dir / "episodes.csv");
  std::string row;
  if (!std::getline(in, row)) {
    return;
  }
  std::vector<std::string> f;
  LoggedEpisode e;
  while (std::getline(in, row)) {
    // episode, wall_seconds, updates, actor, return, steps, outcome, weights_version, policy
    f.clear();
    std::stringstream fields(row);
    for (std::string x; std::getline(fields, x, ',');) {
      f.push_back(std::move(x));
    }
    if (f.size() != RunLogs::episode_columns().size()) {
      continue;
    }
    const auto number = [](const std::string& text, auto& value) {
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
      return ec == std::errc() && end == text.data() + text.size();
    };
    if (!number(f[0], e.episode) || !number(f[1], e.wall_seconds) || !number(f[4], e.ret) || !number(f[5], e.steps) ||
        !number(f[7], e.weights_version) || f[6].empty() || (f[8] != "agent" && f[8] != "scripted")) {
      continue;
    }
    e.scripted = f[8] == "scripted";
    e.outcome = std::move(f[6]);
    visit(e);
  }
}

BestEval::BestEval(fs::path file, std::string role, double steps_limit)
    : file_(std::move(file)), role_(std::move(role)), steps_limit_(steps_limit) {
  std::ifstream in(file_);
  EvalResult r;
  if (in >> r.goal_rate >> r.avg_steps_to_goal >> r.avg_return) {
    int64_t updates = 0;
    int episodes = 0;
    if (in >> updates >> episodes) {  // both written since the file had a comment line
      best_updates_ = updates;
      r.episodes = episodes;
    }
    best_ = r;
  }
}

bool BestEval::beats(const EvalResult& r, const EvalResult& b) const {
  if (steps_limit_ > 0.0) {
    const auto within = [this](const EvalResult& e) {
      return e.goal_rate > 0.0 && e.avg_steps_to_goal <= steps_limit_;
    };
    if (within(r) != within(b)) {
      return within(r);
    }
  }
  if (r.goal_rate != b.goal_rate) {
    return r.goal_rate > b.goal_rate;
  }
  if (r.goal_rate > 0.0 && r.avg_steps_to_goal != b.avg_steps_to_goal) {
    return r.avg_steps_to_goal < b.avg_steps_to_goal;
  }
  return r.avg_return > b.avg_return;
}

EvalResult pooled(const EvalResult& a, const EvalResult& b) {
  if (a.episodes <= 0) {
    return b;
  }
  const double na = a.episodes;
  const double nb = b.episodes;
  const double goals_a = a.goal_rate * na;
  const double goals_b = b.goal_rate * nb;
  EvalResult p;
  p.episodes = a.episodes + b.episodes;
  p.goal_rate = (goals_a + goals_b) / (na + nb);
  p.avg_steps_to_goal = goals_a + goals_b > 0.0
                            ? (a.avg_steps_to_goal * goals_a + b.avg_steps_to_goal * goals_b) / (goals_a + goals_b)
                            : 0.0;
  p.avg_return = (a.avg_return * na + b.avg_return * nb) / (na + nb);
  p.avg_steps = (a.avg_steps * na + b.avg_steps * nb) / (na + nb);
  return p;
}

void BestEval::write() const {
  const EvalResult& b = *best_;
  std::ostringstream text;
  text.precision(17);
  text << b.goal_rate << ' ' << b.avg_steps_to_goal << ' ' << b.avg_return << ' ' << best_updates_ << ' ' << b.episodes
       << '\n'
       << "# success rate, avg steps to success, avg return, updates, episodes of the best greedy evaluation "
          "(best.ckpt)\n";
  const std::string s = text.str();
  write_file_atomically(file_.string(), s.data(), s.size());
}

bool BestEval::offer(const EvalResult& r, int64_t updates, const std::function<EvalResult()>& confirm, EvalResult* kept,
                     const std::function<EvalResult()>& recheck) {
  if (!beats_best(r)) {
    return false;
  }
  // A screen without a single success is not worth a confirmation (1,000 episodes that run to
  // the time limit, early in every run): it can only be compared by return, and the first
  // screen with successes replaces it anyway.
  const bool confirming = confirm && r.goal_rate > 0.0;
  const EvalResult result = confirming ? confirm() : r;
  if (kept != nullptr) {
    *kept = result;
  }
  if (confirming) {
    bool better = beats_best(result);
    std::string against;
    // The kept policy on the challenger's starts: only a kept figure with successes is worth
    // replaying (as above, one without would run every episode to the time limit).
    if (better && recheck && best_->goal_rate > 0.0) {
      const EvalResult incumbent = recheck();
      better = beats(result, incumbent);
      char text[160];
      std::snprintf(text, sizeof text, ", best.ckpt (from %lld updates) %.3f / %.1f on the same starts",
                    static_cast<long long>(best_updates_), incumbent.goal_rate, incumbent.avg_steps_to_goal);
      against = text;
      if (!better) {
        best_ = pooled(*best_, incumbent);
        write();
        std::snprintf(text, sizeof text, ", %.3f / %.1f over its %d episodes", best_->goal_rate,
                      best_->avg_steps_to_goal, best_->episodes);
        against += text;
      }
    }
    log::info("{}: candidate best at {} updates: {:.3f} on {} episodes, confirmed {:.3f} / {:.1f} steps on {}{}: {}",
              role_, updates, r.goal_rate, r.episodes, result.goal_rate, result.avg_steps_to_goal, result.episodes,
              against, better ? "new best.ckpt" : "kept the old one");
    if (!better) {
      return false;
    }
  }
  best_ = result;
  best_updates_ = updates;
  write();
  return true;
}

}  // namespace pamdp
