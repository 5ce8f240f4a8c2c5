// `pamdp plot RUN_DIR… [--out FILE.png]`: the paper's learning-curve panels (goal rate and mean
// return against episodes, mean Q, critic loss) for one or several runs overlaid, drawn by
// gnuplot from the runs' metrics.csv (learner/run_logs.hpp). Columns are found by name, so runs
// written by `pamdp train` and by `pamdp learner` (and by older versions) mix.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/cli_checks.hpp"
#include "app/commands.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"

namespace pamdp::app {
namespace {
namespace fs = std::filesystem;

struct PlotOptions {
  std::vector<std::string> runs;
  std::string out;
  std::string x = "episodes";
  int width = 1400;
  int height = 900;
};

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    cells.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') {
    cells.emplace_back();
  }
  return cells;
}

// One run's curves, as columns of numbers (NaN where a cell is empty).
struct RunCurves {
  std::string label;
  std::vector<std::vector<double>> columns;  // x, success, return, q, loss, eval success (at evaluations only)
  std::string setup;                         // "env hfo, ddpg, seed 1" from its config.toml; "" if unreadable
  std::string task;                          // "env hfo, ddpg": the same without the seed
  uint64_t seed = 0;
  bool goal = false;  // its env's success is a goal (GOAL): "goal rate", else "success rate"
};

// The run's env, learner and seed from its config.toml, and whether its success is a goal.
void read_setup(const std::string& dir, RunCurves& run) {
  try {
    const ExperimentConfig c = load_experiment_config((fs::path(dir) / "config.toml").string(), {});
    run.task = "env " + c.env.name + ", " + c.train.algorithm;
    run.seed = c.seed;
    run.setup = run.task + ", seed " + std::to_string(c.seed);
    const std::unique_ptr<Env> env = make_env(c.env);
    run.goal = env->success_status() >= 0 && env->status_name(env->success_status()) == "GOAL";
  } catch (const std::exception&) {
    // An older run's config, or an env this build or machine cannot make (an HFO server): the
    // curves still draw, under a plainer title.
  }
}

RunCurves read_run(const std::string& dir, const std::string& x_name) {
  const fs::path csv = fs::path(dir) / "metrics.csv";
  std::ifstream in(csv);
  if (!in) {
    throw std::runtime_error("no metrics.csv in '" + dir +
                             "': give the run directory of a pamdp train or pamdp learner run");
  }
  std::string line;
  if (!std::getline(in, line)) {
    throw std::runtime_error("'" + csv.string() + "' is empty: the run has not logged a metrics row yet");
  }
  const std::vector<std::string> header = split_csv_line(line);
  auto find = [&](const std::string& name, bool required) -> int {
    for (size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) {
        return static_cast<int>(i);
      }
    }
    if (required) {
      throw std::runtime_error("'" + csv.string() + "' has no column '" + name +
                               "': it is not a metrics file written by pamdp train or pamdp learner");
    }
    return -1;
  };
  const std::string x_column = x_name == "hours" ? "wall_seconds" : x_name;
  const std::vector<int> index = {find(x_column, true),          find("success_rate_100", true),
                                  find("mean_return_100", true), find("q_mean", true),
                                  find("critic_loss", true),     find("eval_success_rate", false)};
  RunCurves run;
  run.label = fs::path(dir).lexically_normal().filename().string();
  if (run.label.empty() || run.label == ".") {
    run.label = fs::path(dir).lexically_normal().parent_path().filename().string();
  }
  run.columns.resize(index.size());
  // Every row carries the latest evaluation: a point is drawn where a new one appears (the row
  // written right after it), not on every row that repeats it.
  const int eval_return = find("eval_avg_return", false);
  std::string last_eval;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split_csv_line(line);
    for (size_t c = 0; c < index.size(); ++c) {
      double v = NAN;
      if (index[c] >= 0 && static_cast<size_t>(index[c]) < cells.size() && !cells[index[c]].empty()) {
        v = std::strtod(cells[index[c]].c_str(), nullptr);
      }
      if (c == 0 && x_name == "hours") {
        v /= 3600.0;
      }
      if (c == index.size() - 1 && index[c] >= 0) {
        std::string eval = static_cast<size_t>(index[c]) < cells.size() ? cells[index[c]] : "";
        if (eval_return >= 0 && static_cast<size_t>(eval_return) < cells.size()) {
          eval += "," + cells[eval_return];
        }
        if (eval == last_eval) {
          v = NAN;
        }
        last_eval = eval;
      }
      run.columns[c].push_back(v);
    }
  }
  read_setup(dir, run);
  if (run.columns[0].empty()) {
    throw std::runtime_error("'" + csv.string() + "' has a header but no rows yet: let the run log for a while");
  }
  return run;
}

std::string quoted(const std::string& s) {
  std::string q = "'";
  for (const char c : s) {
    q += c == '\'' ? std::string("''") : std::string(1, c);
  }
  return q + "'";
}

void run_plot(const PlotOptions& o) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    throw std::runtime_error(
        "pamdp plot draws with gnuplot, which is not installed: apt-get install gnuplot-nox "
        "(deploy/install-deps.sh installs it)");
  }
  std::vector<RunCurves> runs;
  runs.reserve(o.runs.size());
  for (const std::string& dir : o.runs) {
    runs.push_back(read_run(dir, o.x));
  }
  std::string out = o.out;
  if (out.empty()) {
    out = runs.size() == 1 ? (fs::path(o.runs[0]) / "curves.png").string() : "curves.png";
  }

  const fs::path tmp = fs::temp_directory_path() / ("pamdp-plot-" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{tmp};

  bool any_eval = false;
  for (size_t r = 0; r < runs.size(); ++r) {
    std::ofstream data(tmp / ("run" + std::to_string(r) + ".dat"));
    const auto& cols = runs[r].columns;
    for (size_t i = 0; i < cols[0].size(); ++i) {
      for (size_t c = 0; c < cols.size(); ++c) {
        const double v = cols[c][i];
        if (c == cols.size() - 1 && std::isfinite(v)) {
          any_eval = true;
        }
        data << (c ? " " : "") << (std::isfinite(v) ? std::to_string(v) : std::string("?"));
      }
      data << '\n';
    }
  }

  const std::string x_label = o.x == "hours" ? "wall-clock (hours)" : o.x;
  // "goal rate" where every run's success is a goal (HFO, goal, platform), else "success rate".
  bool goal = true;
  for (const RunCurves& r : runs) {
    goal = goal && r.goal;
  }
  const std::string rate = goal ? "goal rate" : "success rate";
  // The title: what was trained. One run: its directory, env, learner and seed; several of one
  // task (env and learner): the task and the seeds, which fits a line however many; else each.
  std::string title;
  bool one_task = runs.size() > 1;
  std::set<uint64_t> seeds;
  for (const RunCurves& r : runs) {
    one_task = one_task && !r.task.empty() && r.task == runs.front().task && seeds.insert(r.seed).second;
  }
  if (one_task) {
    title = runs.front().task + ": " + std::to_string(runs.size()) + " runs, seeds ";
    for (size_t r = 0; r < runs.size(); ++r) {
      title += (r ? ", " : "") + std::to_string(runs[r].seed);
    }
  } else {
    for (const RunCurves& r : runs) {
      title += (title.empty() ? "" : "   |   ") + r.label + (r.setup.empty() ? "" : " (" + r.setup + ")");
    }
  }
  std::ostringstream g;
  g << "set terminal pngcairo size " << o.width << ',' << o.height << " font 'sans,10' noenhanced\n"
    << "set output " << quoted(out) << "\n"
    << "set datafile missing '?'\n"
    << "set grid\nset xlabel " << quoted(x_label)
    << "\n"
    // Episodes, updates and hours all count from the run's start: the axis starts there too,
    // not where the first metrics row was logged.
    << "set xrange [0:*]\n"
    << "set multiplot layout 2,2 title " << quoted(title) << " font 'sans,12'\n";
  auto panel = [&](const std::string& panel_title, const std::string& y_label, int column, const std::string& extra,
                   bool with_eval) {
    // The rate rises from the bottom left to the top right: its legend goes top left, and names
    // every run's colour for the other panels too, which need none of their own.
    // With several runs the legend goes bottom right, where the rising curves leave room.
    const std::string key = !with_eval         ? "unset key\n"
                            : runs.size() == 1 ? "set key top left opaque box\n"
                                               : "set key bottom right opaque box\n";
    g << "set title " << quoted(panel_title) << "\nset ylabel " << quoted(y_label) << "\n" << key << extra << "plot ";
    for (size_t r = 0; r < runs.size(); ++r) {
      const std::string file = quoted((tmp / ("run" + std::to_string(r) + ".dat")).string());
      const std::string name = runs.size() == 1 ? std::string("training, last 100 episodes") : runs[r].label;
      g << (r ? ", " : "") << file << " using 1:" << column << " with lines lw 2 lc " << r + 1 << " title "
        << quoted(name);
      if (with_eval && any_eval) {
        // One legend entry for the evaluation points: their colour is their run's line.
        g << ", " << file << " using 1:6 with points pt 7 ps 1.6 lc " << r + 1 << " title "
          << (r == 0 ? quoted(runs.size() == 1 ? std::string("greedy evaluation")
                                               : std::string("greedy evaluations (points, in each run's colour)"))
                     : std::string("''"));
      }
    }
    g << "\nunset logscale y\nset autoscale y\n";
  };
  panel(rate + (any_eval ? " (lines: last 100 training episodes; points: greedy evaluations)"
                         : " (last 100 training episodes)"),
        rate, 2, "set yrange [0:1.05]\n", true);
  panel("mean episode return (last 100 episodes)", "return", 3, "", false);
  panel("mean Q (sampled batch)", "Q", 4, "", false);
  panel("critic loss", "loss", 5, "set logscale y\nset format y '%g'\n", false);
  g << "unset multiplot\n";
  const fs::path script = tmp / "plot.gp";
  std::ofstream(script) << g.str();
  const std::string cmd = "gnuplot " + quoted(script.string()) + " 2>&1";
  const int rc = std::system(cmd.c_str());
  if (rc != 0) {
    throw std::runtime_error("gnuplot failed (exit " + std::to_string(rc) + ") writing '" + out +
                             "': check that the directory exists and is writable");
  }
  // What the picture says, for a reader of the terminal and for tests: its title and its rate.
  std::printf("wrote %s (%zu run%s): %s; %s%s\n", out.c_str(), runs.size(), runs.size() == 1 ? "" : "s", title.c_str(),
              rate.c_str(), any_eval ? " with greedy evaluations" : "");
}

}  // namespace

void register_plot(CLI::App& app) {
  auto o = std::make_shared<PlotOptions>();
  CLI::App* cmd = app.add_subcommand(
      "plot", "draw learning curves (goal or success rate, return, mean Q, critic loss) of run directories into a PNG");
  cmd->add_option("runs", o->runs, "run directories (written by pamdp train or pamdp learner); several are overlaid")
      ->required()
      ->check(existing_directory("give the run directory of a pamdp train or pamdp learner run (runs/... by "
                                 "default; it holds metrics.csv)"));
  cmd->add_option("--out", o->out, "PNG to write (default RUN_DIR/curves.png for one run, ./curves.png for several)");
  cmd->add_option("--x", o->x, "x axis")->check(CLI::IsMember({"episodes", "updates", "hours"}))->capture_default_str();
  cmd->add_option("--width", o->width, "image width in pixels")->check(CLI::Range(200, 10000))->capture_default_str();
  cmd->add_option("--height", o->height, "image height in pixels")
      ->check(CLI::Range(200, 10000))
      ->capture_default_str();
  cmd->callback([o] { run_plot(*o); });
}

}  // namespace pamdp::app
