#include "app/run_logs.hpp"

#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/files.hpp"
#include "core/log.hpp"

namespace pamdp::app {
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

// Opens `path` for appending with `header` as its first line. A file that exists with another
// header (an older format) is moved aside rather than mixed with rows of this format.
std::ofstream open_csv(const fs::path& path, const std::string& header) {
  bool fresh = !fs::exists(path) || fs::file_size(path) == 0;
  if (!fresh) {
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    if (first != header) {
      const fs::path aside = path.string() + ".old-format";
      fs::rename(path, aside);
      log::warn("{} has another column layout; moved it to {} and started a new one", path.string(), aside.string());
      fresh = true;
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
  static const std::vector<std::string> columns = {"episode", "wall_seconds", "updates", "actor",
                                                   "return",  "steps",        "outcome", "weights_version"};
  return columns;
}

RunLogs::RunLogs(const fs::path& dir, std::vector<std::string> extra_metric_columns)
    : extras_(std::move(extra_metric_columns)) {
  std::vector<std::string> columns = metric_columns();
  columns.insert(columns.end(), extras_.begin(), extras_.end());
  metrics_ = open_csv(dir / "metrics.csv", join(columns));
  episodes_ = open_csv(dir / "episodes.csv", join(episode_columns()));
}

void RunLogs::metrics(const MetricsRow& r, std::span<const double> extras) {
  if (extras.size() != extras_.size()) {
    throw std::logic_error("RunLogs::metrics: wrong number of extra columns");
  }
  metrics_ << r.wall_seconds << ',' << r.updates << ',' << r.env_steps << ',' << r.episodes << ',';
  if (r.epsilon) {
    metrics_ << *r.epsilon;
  }
  metrics_ << ',' << r.success_rate_100 << ',' << r.mean_return_100 << ',' << r.mean_steps_100 << ',' << r.critic_loss
           << ',' << r.q_mean << ',' << r.updates_per_s << ',' << r.env_steps_per_s << ',';
  if (r.eval) {
    metrics_ << r.eval->goal_rate << ',' << r.eval->avg_steps_to_goal << ',' << r.eval->avg_return;
  } else {
    metrics_ << ",,";
  }
  for (const double v : extras) {
    metrics_ << ',' << v;
  }
  metrics_ << '\n';
  flush();
}

void RunLogs::episode(const EpisodeRow& r) {
  episodes_ << r.episode << ',' << r.wall_seconds << ',' << r.updates << ',' << r.actor << ',' << r.ret << ','
            << r.steps << ',' << r.outcome << ',' << r.weights_version << '\n';
}

void RunLogs::flush() {
  metrics_.flush();
  episodes_.flush();
}

BestEval::BestEval(fs::path file) : file_(std::move(file)) {
  std::ifstream in(file_);
  EvalResult r;
  if (in >> r.goal_rate >> r.avg_steps_to_goal >> r.avg_return) {
    best_ = r;
  }
}

bool BestEval::beats_best(const EvalResult& r) const {
  if (!best_) {
    return true;
  }
  const EvalResult& b = *best_;
  if (r.goal_rate != b.goal_rate) {
    return r.goal_rate > b.goal_rate;
  }
  if (r.goal_rate > 0.0 && r.avg_steps_to_goal != b.avg_steps_to_goal) {
    return r.avg_steps_to_goal < b.avg_steps_to_goal;
  }
  return r.avg_return > b.avg_return;
}

bool BestEval::offer(const EvalResult& r, int64_t updates, const std::function<EvalResult()>& confirm,
                     EvalResult* kept) {
  if (!beats_best(r)) {
    return false;
  }
  const EvalResult result = confirm ? confirm() : r;
  if (kept != nullptr) {
    *kept = result;
  }
  if (confirm && !beats_best(result)) {
    return false;
  }
  best_ = result;
  std::ostringstream text;
  text.precision(17);
  text << result.goal_rate << ' ' << result.avg_steps_to_goal << ' ' << result.avg_return << ' ' << updates << ' '
       << result.episodes << '\n'
       << "# success rate, avg steps to success, avg return, updates, episodes of the best greedy evaluation "
          "(best.ckpt)\n";
  const std::string s = text.str();
  write_file_atomically(file_.string(), s.data(), s.size());
  return true;
}

}  // namespace pamdp::app
