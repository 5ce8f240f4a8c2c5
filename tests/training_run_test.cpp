// The run lifecycle (learner/training_run.hpp) that `pamdp train` and `pamdp learner` share:
// counters and rows, the evaluation schedule with best.ckpt, checkpoints, and the two ways a
// resumed run treats the episode rows written after its checkpoint.
#include "learner/training_run.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "envs/toy/reach_stop.hpp"
#include "learner/ddpg_algorithm.hpp"
#include "replay/replay_buffer.hpp"

namespace pamdp {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("pamdp-training-run-" + name + "-" + std::to_string(getpid()));
  fs::remove_all(dir);
  return dir;
}

DdpgConfig tiny_config() {
  DdpgConfig c;
  c.hidden = {8};
  c.batch_size = 4;
  return c;
}

RunSpec spec_in(const fs::path& dir, bool keeps) {
  RunSpec spec;
  spec.dir = dir;
  spec.role = "test";
  spec.config_toml = "seed = 7\n";
  spec.seed = 7;
  spec.loop.eval_every_updates = 5;
  spec.loop.eval_episodes = 3;
  spec.loop.checkpoint_every_seconds = 0.0;
  spec.exploration.epsilon_start = 1.0;
  spec.exploration.epsilon_end = 0.0;
  spec.exploration.epsilon_anneal_updates = 10;
  spec.keeps_episodes_after_checkpoint = keeps;
  return spec;
}

// A sampler that hands out one zero batch: steps the update counter.
struct ZeroSampler final : Sampler {
  BatchBuffers batch;
  Sample sample;
  ZeroSampler(int obs, int width) : batch(obs, width, 4) { sample.batch.emplace(view_of(batch, 4)); }
  const Sample* next() override { return &sample; }
};

struct Learner {
  toy::ReachStopEnv env;
  toy::ReachStopEnv eval_env;
  DdpgAlgorithm ddpg{env.observation_size(), env.action_space(), tiny_config(), 5, UpdateDevice::kCpu};
  ZeroSampler sampler{env.observation_size(), env.action_space().output_width()};

  void update(TrainingRun& run, int n) {
    for (int i = 0; i < n; ++i) {
      ASSERT_TRUE(run.update(sampler));
    }
  }
};

size_t lines_in(const fs::path& file) {
  std::ifstream in(file);
  size_t n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
  }
  return n;
}

TEST(TrainingRun, CountsEpisodesAndWritesRowsWithTheRatesByHand) {
  const fs::path dir = fresh_dir("rows");
  Learner l;
  TrainingRun run(spec_in(dir, false), l.ddpg, l.env, l.eval_env);
  run.start(false);
  EXPECT_TRUE(fs::exists(dir / "config.toml"));
  run.record_env_steps(3);
  run.record_episode({toy::ReachStopEnv::kSuccess, 1.5, 3, 0, 0, false});
  run.record_env_steps(5);
  run.record_episode({toy::ReachStopEnv::kOutOfTime, -1.0, 5, 0, 0, false});
  run.record_env_steps(2);
  run.record_episode({toy::ReachStopEnv::kSuccess, 9.0, 2, 0, 0, true});  // a demonstration
  l.update(run, 4);
  const MetricsRow row = run.next_metrics_row();
  EXPECT_EQ(row.episodes, 3);
  EXPECT_EQ(row.env_steps, 10);
  EXPECT_EQ(row.updates, 4);
  // The agent's two episodes only: one success of two, mean return (1.5 - 1) / 2, steps 4.
  EXPECT_DOUBLE_EQ(row.success_rate_100, 0.5);
  EXPECT_DOUBLE_EQ(row.mean_return_100, 0.25);
  EXPECT_DOUBLE_EQ(row.mean_steps_100, 4.0);
  ASSERT_TRUE(row.epsilon.has_value());
  EXPECT_DOUBLE_EQ(*row.epsilon, 0.6);  // 1 - 4/10
  EXPECT_FALSE(row.eval.has_value());
  run.logs().metrics(row);
  run.finish();
  EXPECT_EQ(lines_in(dir / "episodes.csv"), 4U);  // header + 3
  EXPECT_EQ(lines_in(dir / "metrics.csv"), 2U);
  EXPECT_TRUE(fs::exists(dir / "checkpoint.ckpt"));
  fs::remove_all(dir);
}

TEST(TrainingRun, EvaluatesEveryNUpdatesAndKeepsTheBest) {
  const fs::path dir = fresh_dir("eval");
  Learner l;
  TrainingRun run(spec_in(dir, false), l.ddpg, l.env, l.eval_env);
  int evals = 0;
  run.on_eval = [&](const EvalResult& r) {
    ++evals;
    EXPECT_EQ(r.episodes, 3);
  };
  run.start(false);
  l.update(run, 4);
  EXPECT_FALSE(run.evaluation_due());
  EXPECT_FALSE(run.evaluate_if_due());
  l.update(run, 1);
  EXPECT_TRUE(run.evaluation_due());
  EXPECT_TRUE(run.evaluate_if_due());
  EXPECT_FALSE(run.evaluation_due());  // next at 10
  EXPECT_EQ(evals, 1);
  EXPECT_TRUE(fs::exists(dir / "best.ckpt"));  // the first evaluation is always the best so far
  EXPECT_TRUE(fs::exists(dir / "best_eval.txt"));
  EXPECT_TRUE(run.next_metrics_row().eval.has_value());
  l.update(run, 7);  // 12: one evaluation is due, however many points were passed
  EXPECT_TRUE(run.evaluate_if_due());
  EXPECT_FALSE(run.evaluate_if_due());
  EXPECT_EQ(evals, 2);
  fs::remove_all(dir);
}

// Writes a run with a checkpoint after two episodes and a third episode after it.
void run_past_a_checkpoint(const fs::path& dir, Learner& l) {
  TrainingRun run(spec_in(dir, false), l.ddpg, l.env, l.eval_env);
  int saves = 0;
  run.before_checkpoint = [&] { ++saves; };
  run.on_save = [](CheckpointMeta& m) { m.weights_version = 42; };
  run.start(false);
  for (int i = 0; i < 2; ++i) {
    run.record_env_steps(4);
    run.record_episode({toy::ReachStopEnv::kSuccess, 1.0, 4, 1, 3, false});
  }
  l.update(run, 3);
  run.save();
  EXPECT_EQ(saves, 1);
  run.record_env_steps(6);
  run.record_episode({toy::ReachStopEnv::kWrongStop, -1.0, 6, 1, 3, false});
  run.logs().flush();
}

// train.recheck_best: the run keeps best.ckpt's policy loaded to replay it, from the file each
// time best.ckpt is written, and again when a run resumes.
TEST(TrainingRun, RecheckBestKeepsBestCkptsPolicyLoaded) {
  const fs::path dir = fresh_dir("recheck");
  Learner l;
  RunSpec spec = spec_in(dir, false);
  spec.loop.recheck_best = true;
  spec.loop.confirm_episodes = 4;
  {
    TrainingRun run(spec, l.ddpg, l.env, l.eval_env);
    EXPECT_THROW(run.start(false), std::logic_error);  // the caller forgot make_incumbent
  }
  int built = 0;
  Algorithm* incumbent = nullptr;
  const auto make = [&]() -> std::unique_ptr<Algorithm> {
    ++built;
    auto a = std::make_unique<DdpgAlgorithm>(l.env.observation_size(), l.env.action_space(), tiny_config(), 99,
                                             UpdateDevice::kCpu);
    incumbent = a.get();
    return a;
  };
  const std::vector<float> obs(static_cast<size_t>(l.env.observation_size()), 0.25F);
  const auto output_of = [&obs](Algorithm& a) {
    std::vector<float> out(static_cast<size_t>(a.output_width()));
    a.act(obs, out, a.evaluated_copy());
    return out;
  };
  {
    TrainingRun run(spec, l.ddpg, l.env, l.eval_env);
    run.make_incumbent = make;
    run.start(false);
    EXPECT_EQ(built, 0);
    l.update(run, 5);
    ASSERT_TRUE(run.evaluate_if_due());  // the first evaluation is the best so far: best.ckpt
    EXPECT_EQ(built, 1);
    ASSERT_NE(incumbent, nullptr);
    EXPECT_EQ(output_of(*incumbent), output_of(l.ddpg));  // the run's policy, as written
    run.save();
  }
  TrainingRun resumed(spec, l.ddpg, l.env, l.eval_env);
  resumed.make_incumbent = make;
  resumed.start(true);
  EXPECT_EQ(built, 2);  // best.ckpt read back
  EXPECT_EQ(output_of(*incumbent), output_of(l.ddpg));
  fs::remove_all(dir);
}

TEST(TrainingRun, AReplayingResumeDropsTheEpisodesAfterItsCheckpoint) {
  const fs::path dir = fresh_dir("replay");
  Learner l;
  run_past_a_checkpoint(dir, l);
  Learner again;
  TrainingRun resumed(spec_in(dir, false), again.ddpg, again.env, again.eval_env);
  const CheckpointMeta meta = resumed.start(true);
  EXPECT_EQ(meta.weights_version, 42);
  EXPECT_EQ(resumed.updates(), 3);
  EXPECT_EQ(resumed.episodes(), 2);
  EXPECT_EQ(resumed.env_steps(), 8);
  EXPECT_EQ(resumed.recent().size(), 2U);
  EXPECT_DOUBLE_EQ(resumed.recent().success_rate(), 1.0);
  resumed.logs().flush();
  EXPECT_EQ(lines_in(dir / "episodes.csv"), 3U);  // header + the two before the checkpoint
  fs::remove_all(dir);
}

TEST(TrainingRun, AKeepingResumeCountsTheEpisodesAfterItsCheckpoint) {
  const fs::path dir = fresh_dir("keep");
  Learner l;
  run_past_a_checkpoint(dir, l);
  Learner again;
  TrainingRun resumed(spec_in(dir, true), again.ddpg, again.env, again.eval_env);
  resumed.start(true);
  EXPECT_EQ(resumed.episodes(), 3);
  EXPECT_EQ(resumed.env_steps(), 14);
  EXPECT_EQ(resumed.recent().size(), 3U);
  EXPECT_NEAR(resumed.recent().success_rate(), 2.0 / 3.0, 1e-12);
  resumed.record_env_steps(1);
  resumed.record_episode({toy::ReachStopEnv::kSuccess, 1.0, 1, 2, 4, false});
  resumed.logs().flush();
  EXPECT_EQ(lines_in(dir / "episodes.csv"), 5U);  // numbered on: 1, 2, 3, then 4
  std::ifstream in(dir / "episodes.csv");
  std::string line, last;
  while (std::getline(in, line)) {
    last = line;
  }
  EXPECT_EQ(last.substr(0, 2), "4,");
  fs::remove_all(dir);
}

std::string text_of(const fs::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(TrainingRun, AResumeThatChangesTheConfigRecordsItAndKeepsTheOneBefore) {
  const fs::path dir = fresh_dir("config");
  Learner l;
  run_past_a_checkpoint(dir, l);  // checkpoint at 3 updates, config "seed = 7\n"
  ASSERT_EQ(text_of(dir / "config.toml"), "seed = 7\n");
  {
    Learner same;
    TrainingRun resumed(spec_in(dir, false), same.ddpg, same.env, same.eval_env);
    resumed.start(true);
    EXPECT_EQ(text_of(dir / "config.toml"), "seed = 7\n");
    EXPECT_FALSE(fs::exists(dir / "config-before-3.toml"));  // nothing changed, nothing kept
  }
  Learner again;
  RunSpec changed = spec_in(dir, false);
  changed.config_toml = "seed = 7\n\n[train]\nmax_updates = 99\n";
  TrainingRun resumed(changed, again.ddpg, again.env, again.eval_env);
  resumed.start(true);
  EXPECT_EQ(text_of(dir / "config.toml"), changed.config_toml);
  EXPECT_EQ(text_of(dir / "config-before-3.toml"), "seed = 7\n");
  fs::remove_all(dir);
}

TEST(TrainingRun, AResumeWithoutACheckpointNamesTheFile) {
  const fs::path dir = fresh_dir("none");
  Learner l;
  TrainingRun run(spec_in(dir, false), l.ddpg, l.env, l.eval_env);
  try {
    run.start(true);
    FAIL() << "resumed without a checkpoint";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("checkpoint.ckpt"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pamdp
