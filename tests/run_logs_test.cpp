// The run directory's CSV files (learner/run_logs), the best-evaluation keeper, the progress bar's
// formatting, and `pamdp plot` on a real run directory written by `pamdp train`.
#include "learner/run_logs.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "app/progress.hpp"

namespace pamdp::app {
namespace {
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("pamdp_runlogs_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> lines_of(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    lines.push_back(line);
  }
  return lines;
}

TEST(RunLogs, WritesHeadersOnceAndRowsInColumnOrder) {
  const fs::path dir = fresh_dir("rows");
  {
    RunLogs logs(dir, {"shards"});
    MetricsRow row;
    row.wall_seconds = 1.5;
    row.updates = 100;
    row.env_steps = 120;
    row.episodes = 3;
    row.epsilon = 0.5;
    row.success_rate_100 = 0.25;
    row.mean_return_100 = 2.0;
    row.mean_steps_100 = 40.0;
    row.critic_loss = 0.125;
    row.q_mean = 0.75;
    row.updates_per_s = 10.0;
    row.env_steps_per_s = 12.0;
    const double extras[] = {2.0};
    logs.metrics(row, extras);
    EpisodeRow ep{7, 1.25, 90, 3, 1.5, 55, "GOAL", 42};
    logs.episode(ep);
    logs.episode(EpisodeRow{8, 2.5, 95, 0, 10.0, 60, "GOAL", 0, /*scripted=*/true});
    logs.flush();
  }
  {
    RunLogs again(dir, {"shards"});  // a resumed run appends without a second header
    MetricsRow row;
    EvalResult e;
    e.goal_rate = 0.5;
    e.avg_steps_to_goal = 70.0;
    e.avg_return = 3.0;
    row.eval = e;
    const double extras[] = {1.0};
    again.metrics(row, extras);
  }
  const auto m = lines_of(dir / "metrics.csv");
  ASSERT_EQ(m.size(), 3U);
  EXPECT_EQ(m[0],
            "wall_seconds,updates,env_steps,episodes,epsilon,success_rate_100,mean_return_100,mean_steps_100,"
            "critic_loss,q_mean,updates_per_s,env_steps_per_s,eval_success_rate,eval_avg_steps_to_success,"
            "eval_avg_return,shards");
  EXPECT_EQ(m[1], "1.5,100,120,3,0.5,0.25,2,40,0.125,0.75,10,12,,,,2");
  EXPECT_EQ(m[2], "0,0,0,0,,0,0,0,0,0,0,0,0.5,70,3,1");  // no epsilon: an empty cell
  const auto e = lines_of(dir / "episodes.csv");
  ASSERT_EQ(e.size(), 3U);
  EXPECT_EQ(e[0], "episode,wall_seconds,updates,actor,return,steps,outcome,weights_version,policy");
  EXPECT_EQ(e[1], "7,1.25,90,3,1.5,55,GOAL,42,agent");
  EXPECT_EQ(e[2], "8,2.5,95,0,10,60,GOAL,0,scripted");
  fs::remove_all(dir);
}

// A killed `pamdp train` logged past its last checkpoint; the resumed run replays that stretch and
// logs it again, so the rows after the checkpoint go (and so does a row cut off mid-line).
TEST(RunLogs, AResumedRunDropsTheRowsWrittenAfterItsCheckpoint) {
  const fs::path dir = fresh_dir("resume");
  {
    RunLogs logs(dir);
    for (const int64_t updates : {100, 200, 300, 400}) {
      MetricsRow row;
      row.updates = updates;
      row.episodes = updates / 10;
      logs.metrics(row);
    }
    for (int64_t episode = 1; episode <= 5; ++episode) {
      logs.episode(EpisodeRow{episode, 0.5, episode * 10, 0, 1.0, 20, "GOAL", 0});
    }
    logs.flush();
  }
  std::ofstream(dir / "episodes.csv", std::ios::app) << "3,0.5,3";  // a kill mid-row
  {
    RunLogs resumed(dir, {}, ResumePoint{250, 3});
    MetricsRow row;
    row.updates = 260;
    resumed.metrics(row);
    resumed.episode(EpisodeRow{4, 0.5, 40, 0, 1.0, 20, "GOAL", 0});
    resumed.flush();
  }
  const auto m = lines_of(dir / "metrics.csv");
  ASSERT_EQ(m.size(), 4U);  // header, 100, 200, then the resumed run's 260
  EXPECT_EQ(m[1].substr(0, 6), "0,100,");
  EXPECT_EQ(m[2].substr(0, 6), "0,200,");
  EXPECT_EQ(m[3].substr(0, 6), "0,260,");
  const auto e = lines_of(dir / "episodes.csv");
  ASSERT_EQ(e.size(), 5U);  // header, episodes 1-3, the resumed run's 4
  for (size_t i = 1; i < e.size(); ++i) {
    EXPECT_EQ(e[i].substr(0, 2), std::to_string(i) + ",") << e[i];
  }
  EXPECT_EQ(e[4], "4,0.5,40,0,1,20,GOAL,0,agent");

  {
    RunLogs plain(dir);  // without a resume point nothing is dropped
  }
  EXPECT_EQ(lines_of(dir / "metrics.csv").size(), 4U);
  fs::remove_all(dir);
}

// `pamdp learner --resume`: the updates after the checkpoint are redone, the episodes the actors
// played meanwhile are not, so only metrics rows go.
TEST(RunLogs, AResumeWithoutAnEpisodeCountKeepsEveryEpisodeRow) {
  const fs::path dir = fresh_dir("resume-learner");
  {
    RunLogs logs(dir);
    for (const int64_t updates : {100, 200, 300}) {
      MetricsRow row;
      row.updates = updates;
      logs.metrics(row);
    }
    for (int64_t episode = 1; episode <= 5; ++episode) {
      logs.episode(EpisodeRow{episode, 0.5, episode * 60, 0, 1.0, 20, "GOAL", 1});
    }
  }
  std::ofstream(dir / "episodes.csv", std::ios::app) << "6,0.5,3";  // a kill mid-row
  { RunLogs resumed(dir, {}, ResumePoint{150, std::nullopt}); }
  EXPECT_EQ(lines_of(dir / "metrics.csv").size(), 2U);  // header, 100
  EXPECT_EQ(lines_of(dir / "episodes.csv").size(), 6U);
  std::vector<int64_t> numbers;
  for_each_logged_episode(dir, [&](const LoggedEpisode& e) { numbers.push_back(e.episode); });
  EXPECT_EQ(numbers, (std::vector<int64_t>{1, 2, 3, 4, 5}));
  fs::remove_all(dir);
}

// A kill leaves episodes.csv cut at any byte of its last row. For every cut, `pamdp learner
// --resume` (keep every whole row, number on after the last one that parses, append) must leave
// a file numbered 1, 2, 3, ... with one row per line.
TEST(RunLogs, EveryCutOfTheLastRowResumesWithOneRowPerNumber) {
  const fs::path dir = fresh_dir("cut");
  const EpisodeRow last{6, 12.25, 360, 1, -0.5, 20, "OUT_OF_TIME", 17};
  std::ostringstream whole;
  {
    RunLogs logs(dir);
    for (int64_t episode = 1; episode <= 6; ++episode) {
      EpisodeRow row = last;
      row.episode = episode;
      logs.episode(row);
    }
  }
  const std::string full = [&] {
    std::ifstream in(dir / "episodes.csv");
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }();
  const size_t row_begin = full.rfind('\n', full.size() - 2) + 1;
  for (size_t cut = row_begin; cut <= full.size(); ++cut) {
    SCOPED_TRACE("episodes.csv cut to \"" + full.substr(row_begin, cut - row_begin) + "\"");
    std::ofstream(dir / "episodes.csv", std::ios::trunc) << full.substr(0, cut);
    {
      RunLogs resumed(dir, {}, ResumePoint{100, std::nullopt});
      int64_t count = 0;
      for_each_logged_episode(dir, [&](const LoggedEpisode& e) { count = std::max(count, e.episode); });
      for (int i = 0; i < 2; ++i) {
        EpisodeRow row = last;
        row.episode = ++count;
        resumed.episode(row);
      }
    }
    const auto e = lines_of(dir / "episodes.csv");
    ASSERT_GE(e.size(), 8U);
    for (size_t i = 1; i < e.size(); ++i) {
      EXPECT_EQ(e[i].substr(0, e[i].find(',')), std::to_string(i)) << e[i];
      EXPECT_EQ(std::count(e[i].begin(), e[i].end(), ','), 8) << e[i];
    }
  }
  fs::remove_all(dir);
}

// A reader of a live run (tests, `tail -f`, scripts) sees episodes.csv grow by whole rows only.
TEST(RunLogs, EpisodesGrowByWholeRows) {
  const fs::path dir = fresh_dir("whole");
  const fs::path file = dir / "episodes.csv";
  const auto last_byte = [&] {
    std::ifstream in(file, std::ios::binary);
    in.seekg(-1, std::ios::end);
    return static_cast<char>(in.get());
  };
  {
    RunLogs logs(dir);
    const uintmax_t header = fs::file_size(file);
    uintmax_t size = header;
    for (int64_t episode = 1; episode <= 5000; ++episode) {
      logs.episode(EpisodeRow{episode, 1234.5678, episode * 97, 3, -0.123456, 17, "OUT_OF_TIME", 4242});
      if (fs::file_size(file) != size) {
        size = fs::file_size(file);
        ASSERT_EQ(last_byte(), '\n') << "after episode " << episode;
      }
    }
    EXPECT_GT(size, header);  // 5,000 rows do not wait for flush()
  }
  EXPECT_EQ(lines_of(dir / "episodes.csv").size(), 5001U);  // the rest at destruction
  fs::remove_all(dir);
}

TEST(RunLogs, AResumedRunReadsBackItsLastEpisodes) {
  const fs::path dir = fresh_dir("last");
  // Every row that parses, in file order.
  const auto read_back = [&dir] {
    std::vector<LoggedEpisode> rows;
    for_each_logged_episode(dir, [&rows](const LoggedEpisode& e) { rows.push_back(e); });
    return rows;
  };
  EXPECT_TRUE(read_back().empty());  // no file yet
  {
    RunLogs logs(dir);
    for (int64_t episode = 1; episode <= 150; ++episode) {
      const bool goal = episode % 3 == 0;
      const bool scripted = episode % 2 == 0;
      logs.episode(EpisodeRow{episode, 0.5, episode * 10, 0, goal ? 10.5 : -0.25, episode,
                              goal ? "GOAL" : "OUT_OF_TIME", static_cast<uint64_t>(scripted ? 0 : episode * 10),
                              scripted});
    }
    logs.flush();
  }
  std::ofstream(dir / "episodes.csv", std::ios::app) << "151,0.5,1510,0,1";  // a kill mid-row
  const std::vector<LoggedEpisode> all = read_back();
  ASSERT_EQ(all.size(), 150U);                                        // the cut-off row is skipped
  const std::vector<LoggedEpisode> last(all.end() - 100, all.end());  // episodes 51-150
  EXPECT_EQ(last.front().steps, 51);
  EXPECT_EQ(last.front().episode, 51);
  EXPECT_DOUBLE_EQ(last.front().wall_seconds, 0.5);
  EXPECT_EQ(last.back().steps, 150);
  EXPECT_EQ(last.back().outcome, "GOAL");
  EXPECT_DOUBLE_EQ(last.back().ret, 10.5);
  EXPECT_EQ(last.back().weights_version, 0U);
  EXPECT_TRUE(last.back().scripted);
  EXPECT_FALSE(last[98].scripted);
  EXPECT_EQ(last[98].outcome, "OUT_OF_TIME");
  EXPECT_DOUBLE_EQ(last[98].ret, -0.25);
  EXPECT_EQ(last[98].weights_version, 1490U);
  fs::remove_all(dir);
}

TEST(RunLogs, MovesAsideAFileOfAnotherLayout) {
  const fs::path dir = fresh_dir("aside");
  std::ofstream(dir / "metrics.csv") << "wall_seconds,updates,old_column\n1,2,3\n";
  { RunLogs logs(dir); }
  EXPECT_TRUE(fs::exists(dir / "metrics.csv.old-format"));
  const auto m = lines_of(dir / "metrics.csv");
  ASSERT_EQ(m.size(), 1U);
  EXPECT_EQ(m[0].rfind("wall_seconds,updates,env_steps", 0), 0U);
  fs::remove_all(dir);
}

TEST(RunLogs, WrongNumberOfExtrasIsMisuse) {
  const fs::path dir = fresh_dir("extras");
  RunLogs logs(dir, {"a", "b"});
  const double one[] = {1.0};
  EXPECT_THROW(logs.metrics(MetricsRow{}, one), std::logic_error);
  fs::remove_all(dir);
}

EvalResult eval_of(double rate, double steps, double ret) {
  EvalResult r;
  r.goal_rate = rate;
  r.avg_steps_to_goal = steps;
  r.avg_return = ret;
  return r;
}

TEST(BestEval, RateThenStepsThenReturnAndItSurvivesARestart) {
  const fs::path dir = fresh_dir("best");
  const fs::path file = dir / "best_eval.txt";
  {
    BestEval best(file);
    EXPECT_TRUE(best.offer(eval_of(0.0, 0.0, 1.0), 10));   // the first always wins
    EXPECT_FALSE(best.offer(eval_of(0.0, 0.0, 0.5), 20));  // same rate, lower return
    EXPECT_TRUE(best.offer(eval_of(0.0, 0.0, 1.5), 30));   // same rate, higher return
    EXPECT_TRUE(best.offer(eval_of(0.8, 90.0, 0.0), 40));  // higher rate beats any return
    EXPECT_TRUE(best.offer(eval_of(0.8, 80.0, 0.0), 50));  // same rate, fewer steps
    EXPECT_FALSE(best.offer(eval_of(0.8, 85.0, 9.0), 60));
  }
  BestEval resumed(file);
  ASSERT_TRUE(resumed.best().has_value());
  EXPECT_DOUBLE_EQ(resumed.best()->goal_rate, 0.8);
  EXPECT_DOUBLE_EQ(resumed.best()->avg_steps_to_goal, 80.0);
  EXPECT_FALSE(resumed.offer(eval_of(0.7, 10.0, 9.0), 70));
  EXPECT_TRUE(resumed.offer(eval_of(0.9, 100.0, 0.0), 80));
  fs::remove_all(dir);
}

TEST(BestEval, ACandidateIsJudgedByItsConfirmation) {
  const fs::path dir = fresh_dir("best_confirm");
  const fs::path file = dir / "best_eval.txt";
  int confirmations = 0;
  auto confirming = [&](double rate, double steps) {
    return std::function<EvalResult()>([&confirmations, rate, steps] {
      ++confirmations;
      EvalResult r = eval_of(rate, steps, 0.0);
      r.episodes = 1000;
      return r;
    });
  };
  {
    BestEval best(file);
    EvalResult kept;
    // A screen without successes is kept as it is, without a confirmation.
    EXPECT_TRUE(best.offer(eval_of(0.0, 0.0, 2.0), 5, confirming(0.5, 75.0), &kept));
    EXPECT_EQ(confirmations, 0);
    EXPECT_DOUBLE_EQ(kept.goal_rate, 0.0);
    EXPECT_DOUBLE_EQ(best.best()->avg_return, 2.0);
    // The first candidate with successes is confirmed, and the confirmation is what is kept.
    EXPECT_TRUE(best.offer(eval_of(1.0, 70.0, 0.0), 10, confirming(0.93, 75.0), &kept));
    EXPECT_EQ(confirmations, 1);
    EXPECT_DOUBLE_EQ(kept.goal_rate, 0.93);
    EXPECT_DOUBLE_EQ(best.best()->goal_rate, 0.93);
    // A screening result below the confirmed best is not confirmed at all.
    EXPECT_FALSE(best.offer(eval_of(0.92, 60.0, 0.0), 20, confirming(0.99, 60.0), &kept));
    EXPECT_EQ(confirmations, 1);
    // A lucky screen whose confirmation is worse does not replace the best.
    EXPECT_FALSE(best.offer(eval_of(0.97, 70.0, 0.0), 30, confirming(0.91, 70.0), &kept));
    EXPECT_EQ(confirmations, 2);
    EXPECT_DOUBLE_EQ(kept.goal_rate, 0.91);
    EXPECT_DOUBLE_EQ(best.best()->goal_rate, 0.93);
    // One whose confirmation is better does.
    EXPECT_TRUE(best.offer(eval_of(0.95, 70.0, 0.0), 40, confirming(0.95, 72.0), &kept));
    EXPECT_EQ(confirmations, 3);
  }
  BestEval resumed(file);
  ASSERT_TRUE(resumed.best().has_value());
  EXPECT_DOUBLE_EQ(resumed.best()->goal_rate, 0.95);
  EXPECT_DOUBLE_EQ(resumed.best()->avg_steps_to_goal, 72.0);
  fs::remove_all(dir);
}

// train.best_steps_limit: an evaluation within the limit beats one over it whatever the rates;
// on the same side the usual order holds; the limit holds for a resumed run told it again.
TEST(BestEval, AStepsLimitPrefersResultsWithinIt) {
  const fs::path dir = fresh_dir("best_limit");
  const fs::path file = dir / "best_eval.txt";
  {
    BestEval best(file, "train", 75.0);
    EXPECT_TRUE(best.offer(eval_of(0.0, 0.0, 1.0), 10));
    EXPECT_TRUE(best.offer(eval_of(0.996, 79.6, 0.0), 20));   // successes beat none
    EXPECT_FALSE(best.offer(eval_of(0.995, 79.0, 0.0), 30));  // both over: the rate decides
    EXPECT_TRUE(best.offer(eval_of(0.985, 71.9, 0.0), 40));   // within beats over
    EXPECT_FALSE(best.offer(eval_of(1.0, 76.0, 0.0), 50));    // over loses to within
    EXPECT_TRUE(best.offer(eval_of(0.99, 74.0, 0.0), 60));    // both within: the rate decides
    EXPECT_FALSE(best.offer(eval_of(0.99, 74.5, 0.0), 70));   // then the steps
  }
  BestEval resumed(file, "train", 75.0);
  EXPECT_FALSE(resumed.offer(eval_of(0.999, 75.1, 0.0), 80));
  EXPECT_TRUE(resumed.offer(eval_of(0.991, 75.0, 0.0), 90));  // the limit itself is within
  BestEval unlimited(file);
  EXPECT_TRUE(unlimited.offer(eval_of(0.999, 75.1, 0.0), 100));  // without a limit, rate first
  fs::remove_all(dir);
}

// train.recheck_best: a confirmed challenger must also beat the kept policy played on the
// challenger's starts; a lost recheck pools the kept policy's evaluations, by hand below.
TEST(BestEval, ARecheckPlaysTheKeptPolicyOnTheChallengersStartsAndPoolsItsFigures) {
  const fs::path dir = fresh_dir("best_recheck");
  const fs::path file = dir / "best_eval.txt";
  const auto on_1000 = [](double rate, double steps, double ret) {
    EvalResult r = eval_of(rate, steps, ret);
    r.episodes = 1000;
    return r;
  };
  int rechecks = 0;
  const auto returning = [&rechecks](EvalResult r) {
    return std::function<EvalResult()>([&rechecks, r] {
      ++rechecks;
      return r;
    });
  };
  const auto confirmed = [](EvalResult r) { return std::function<EvalResult()>([r] { return r; }); };
  {
    BestEval best(file, "train", 75.0);
    // Nothing kept yet, then only a screen without successes: nothing to replay.
    EXPECT_TRUE(
        best.offer(eval_of(0.0, 0.0, 1.0), 5, confirmed(on_1000(0, 0, 0)), nullptr, returning(on_1000(1.0, 1.0, 1.0))));
    EXPECT_TRUE(best.offer(eval_of(1.0, 70.0, 0.0), 10, confirmed(on_1000(0.995, 72.0, 2.0)), nullptr,
                           returning(on_1000(1.0, 1.0, 1.0))));
    EXPECT_EQ(rechecks, 0);
    EXPECT_EQ(best.best_updates(), 10);
    // A challenger confirmed at .997 beats the kept .995, but the kept policy scores .999 on the
    // challenger's starts: kept, and its figure pools .995 and .999 on 1,000 each.
    EvalResult kept;
    EXPECT_FALSE(best.offer(eval_of(1.0, 70.0, 0.0), 20, confirmed(on_1000(0.997, 71.0, 3.0)), &kept,
                            returning(on_1000(0.999, 73.0, 4.0))));
    EXPECT_EQ(rechecks, 1);
    EXPECT_DOUBLE_EQ(kept.goal_rate, 0.997);  // what was compared: the confirmation
    ASSERT_TRUE(best.best().has_value());
    EXPECT_EQ(best.best()->episodes, 2000);
    EXPECT_NEAR(best.best()->goal_rate, 0.997, 1e-12);                                       // (995 + 999) / 2000
    EXPECT_NEAR(best.best()->avg_steps_to_goal, (72.0 * 995 + 73.0 * 999) / 1994.0, 1e-12);  // by goals
    EXPECT_NEAR(best.best()->avg_return, 3.0, 1e-12);
    EXPECT_EQ(best.best_updates(), 10);  // still the kept policy's
    // A challenger confirmed at .998 beats the pooled .997; the kept one scores .990 on its
    // starts: the challenger wins, with its own confirmation as the figure.
    EXPECT_TRUE(best.offer(eval_of(1.0, 70.0, 0.0), 30, confirmed(on_1000(0.998, 74.0, 5.0)), nullptr,
                           returning(on_1000(0.990, 70.0, 1.0))));
    EXPECT_EQ(rechecks, 2);
    EXPECT_DOUBLE_EQ(best.best()->goal_rate, 0.998);
    EXPECT_EQ(best.best()->episodes, 1000);
    // A confirmation that does not beat the kept figure is not rechecked.
    EXPECT_FALSE(best.offer(eval_of(1.0, 70.0, 0.0), 40, confirmed(on_1000(0.996, 70.0, 5.0)), nullptr,
                            returning(on_1000(0.0, 0.0, 0.0))));
    EXPECT_EQ(rechecks, 2);
    // The recheck compares as everything else does: at the same rate, fewer steps win.
    EXPECT_FALSE(best.offer(eval_of(1.0, 70.0, 0.0), 50, confirmed(on_1000(0.999, 74.9, 5.0)), nullptr,
                            returning(on_1000(0.999, 70.0, 0.0))));
    EXPECT_EQ(rechecks, 3);
    EXPECT_EQ(best.best()->episodes, 2000);
    EXPECT_NEAR(best.best()->goal_rate, (998.0 + 999.0) / 2000.0, 1e-12);
  }
  // The pooled figure, its updates and its episodes survive a restart.
  BestEval resumed(file, "train", 75.0);
  ASSERT_TRUE(resumed.best().has_value());
  EXPECT_NEAR(resumed.best()->goal_rate, (998.0 + 999.0) / 2000.0, 1e-12);
  EXPECT_EQ(resumed.best()->episodes, 2000);
  EXPECT_EQ(resumed.best_updates(), 30);
  fs::remove_all(dir);
}

// A figure without an episode count (best_eval.txt before it held one) pools as the new result.
TEST(BestEval, PoolingWithoutAnEpisodeCountTakesTheNewResult) {
  EvalResult old = eval_of(0.99, 70.0, 1.0);
  EvalResult fresh = eval_of(0.98, 72.0, 2.0);
  fresh.episodes = 1000;
  const EvalResult p = pooled(old, fresh);
  EXPECT_EQ(p.episodes, 1000);
  EXPECT_DOUBLE_EQ(p.goal_rate, 0.98);
  EXPECT_DOUBLE_EQ(p.avg_steps_to_goal, 72.0);
}

TEST(ProgressBar, FormatsDurations) {
  EXPECT_EQ(ProgressBar::format_duration(0.2), "0s");
  EXPECT_EQ(ProgressBar::format_duration(59.4), "59s");
  EXPECT_EQ(ProgressBar::format_duration(65.0), "1m05s");
  EXPECT_EQ(ProgressBar::format_duration(7800.0), "2h10m");
  EXPECT_EQ(ProgressBar::format_duration(-1.0), "?");
}

TEST(ProgressBar, DrawsNothingWhenStderrIsNotATerminal) {
  if (isatty(fileno(stderr)) == 1) {
    GTEST_SKIP() << "stderr is a terminal here";
  }
  ProgressBar bar("episodes", 10);
  EXPECT_FALSE(bar.active());
}

int run(const std::string& cmd, std::string* output) {
  FILE* pipe = ::popen((cmd + " 2>&1").c_str(), "r");
  if (pipe == nullptr) {
    return -1;
  }
  std::array<char, 4096> buf{};
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) {
    output->append(buf.data(), n);
  }
  const int status = ::pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// A real (tiny) training run, then its curves: the run directory has the files the README
// promises, a best checkpoint that `pamdp eval` accepts, and `pamdp plot` makes a PNG of it.
TEST(Plot, DrawsTheCurvesOfARealRun) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "gnuplot is not installed (deploy/install-deps.sh installs gnuplot-nox)";
  }
  const fs::path dir = fresh_dir("plot");
  const std::string pamdp = std::string(PAMDP_BIN_DIR) + "/pamdp";
  const fs::path run_dir = dir / "toy";
  std::string out;
  ASSERT_EQ(run("'" + pamdp + "' train --config '" + PAMDP_SOURCE_DIR +
                    "/deploy/configs/reach_stop.toml' --quiet --set train.max_updates=3000 "
                    "--set train.eval_every_updates=1000 --set train.log_every_seconds=0.05 --run-dir '" +
                    run_dir.string() + "'",
                &out),
            0)
      << out;
  for (const char* f :
       {"config.toml", "metrics.csv", "episodes.csv", "checkpoint.ckpt", "best.ckpt", "best_eval.txt"}) {
    EXPECT_TRUE(fs::exists(run_dir / f)) << f << " missing from the run directory";
  }
  out.clear();
  EXPECT_EQ(run("'" + pamdp + "' eval --checkpoint '" + (run_dir / "best.ckpt").string() + "' --episodes 20", &out), 0)
      << out;
  out.clear();
  const fs::path png = dir / "curves.png";
  ASSERT_EQ(
      run("'" + pamdp + "' plot '" + run_dir.string() + "' '" + run_dir.string() + "' --out '" + png.string() + "'",
          &out),
      0)
      << out;
  std::ifstream in(png, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG") << "not a PNG: " << png;
  EXPECT_GT(fs::file_size(png), 10000U);
  // Its title names the run's env, learner and seed; the toy task has no goal, so its rate is a
  // success rate; its evaluations are drawn (issue 81).
  EXPECT_NE(out.find("toy (env reach_stop, ddpg, seed 1)"), std::string::npos) << out;
  EXPECT_NE(out.find("; success rate with greedy evaluations"), std::string::npos) << out;
  EXPECT_EQ(out.find("goal rate"), std::string::npos) << out;
  // Runs of one task with different seeds: the task and the seeds, on a line of any length.
  const fs::path seed2 = dir / "seed2";
  fs::create_directories(seed2);
  fs::copy_file(run_dir / "metrics.csv", seed2 / "metrics.csv");
  {
    std::ifstream cfg(run_dir / "config.toml");
    std::ofstream copy(seed2 / "config.toml");
    std::string line;
    while (std::getline(cfg, line)) {
      copy << (line.rfind("seed = ", 0) == 0 ? std::string("seed = 2") : line) << "\n";
    }
  }
  out.clear();
  ASSERT_EQ(run("'" + pamdp + "' plot '" + run_dir.string() + "' '" + seed2.string() + "' --out '" + png.string() + "'",
                &out),
            0)
      << out;
  EXPECT_NE(out.find("env reach_stop, ddpg: 2 runs, seeds 1, 2;"), std::string::npos) << out;

  out.clear();
  EXPECT_NE(run("'" + pamdp + "' plot '" + dir.string() + "'", &out), 0);  // not a run directory
  EXPECT_NE(out.find("no metrics.csv"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(run("'" + pamdp + "' plot '" + (dir / "nowhere").string() + "'", &out), 2);  // no such directory
  EXPECT_NE(out.find("pamdp: error: runs: no directory"), std::string::npos) << out;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pamdp::app
