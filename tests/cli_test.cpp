// The `pamdp` executable as a user meets it: help, `eval --json`, flag errors, and
// `sim trace` against a golden trace (tests/golden; refresh with tests/golden/regenerate.sh
// after an intended physics change).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "app/experiment_config.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/settings.hpp"
#include "learner/checkpoint.hpp"
#include "learner/ddpg.hpp"
#include "learner/ddpg_algorithm.hpp"

namespace {

const std::string kPamdp = PAMDP_BIN_DIR "/pamdp";
const std::string kGolden = PAMDP_TEST_DATA_DIR "/golden";

struct RunResult {
  int exit_code = -1;
  std::string output;
};

enum class Capture { kStdoutAndStderr, kStdoutOnly, kStderrOnly };

// Runs `pamdp <args>` through the shell and collects its output and exit status.
RunResult run_pamdp(const std::string& args, Capture capture = Capture::kStdoutAndStderr) {
  const char* redirect = capture == Capture::kStdoutAndStderr ? " 2>&1"
                         : capture == Capture::kStdoutOnly    ? " 2>/dev/null"
                                                              : " 2>&1 >/dev/null";
  const std::string cmd = "'" + kPamdp + "' " + args + redirect;
  RunResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) {
    ADD_FAILURE() << "popen failed for: " << cmd;
    return r;
  }
  std::array<char, 4096> buf{};
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) {
    r.output.append(buf.data(), n);
  }
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, sep)) {
    out.push_back(item);
  }
  return out;
}

// The last non-empty line of a command's output (where --json puts its object); "" if none.
std::string last_line(const std::string& output) {
  std::vector<std::string> lines = split(output, '\n');
  while (!lines.empty() && lines.back().empty()) {
    lines.pop_back();
  }
  return lines.empty() ? std::string() : lines.back();
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot read " << path;
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string quoted(const std::string& path) {
  return "'" + path + "'";
}

// A file under the test temp dir, unique per test and process (ctest runs tests in
// parallel), removed when the test ends.
class TempFile {
 public:
  TempFile(const std::string& suffix, const std::string& contents) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string test_name = info->name();  // "Suite/Param" for parameterized tests
    std::replace(test_name.begin(), test_name.end(), '/', '_');
    path_ = ::testing::TempDir() + "pamdp_cli_" + test_name + "_" + std::to_string(::getpid()) + suffix;
    std::ofstream(path_) << contents;
  }
  ~TempFile() { std::remove(path_.c_str()); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
};

TEST(Cli, HelpListsSubcommands) {
  const RunResult r = run_pamdp("--help");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("eval"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("sim"), std::string::npos) << r.output;

  const RunResult sim = run_pamdp("sim --help");
  EXPECT_EQ(sim.exit_code, 0) << sim.output;
  EXPECT_NE(sim.output.find("trace"), std::string::npos) << sim.output;
}

// The commands that train list the registered learners and every learner's own keys.
TEST(Cli, TrainHelpListsTheLearnersAndTheirKeys) {
  for (const std::string command : {"train", "learner"}) {
    const RunResult r = run_pamdp(command + " --help");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    for (const pamdp::AlgorithmRegistration& a : pamdp::algorithm_registry().all()) {
      EXPECT_NE(r.output.find("  " + a.name + " "), std::string::npos) << command << ": " << a.name;
    }
    for (const pamdp::AlgorithmKey& k : pamdp::algorithm_registry().keys()) {
      EXPECT_NE(r.output.find("  " + k.name + " = "), std::string::npos) << command << ": " << k.name;
    }
  }
}

TEST(Cli, NoSubcommandFails) {
  const RunResult r = run_pamdp("");
  EXPECT_NE(r.exit_code, 0) << r.output;
}

TEST(Cli, EvalJsonLastLineHasEveryKey) {
  const RunResult r = run_pamdp("eval --episodes 20 --json", Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string last = last_line(r.output);
  ASSERT_FALSE(last.empty());
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(last)) << "last line is not JSON: " << last;
  for (const char* key : {"episodes", "goal_rate", "avg_steps_to_goal", "avg_return", "avg_steps", "outcomes"}) {
    EXPECT_TRUE(j.contains(key)) << key << " missing from " << last;
  }
  EXPECT_EQ(j.value("episodes", -1), 20);
  int total = 0;
  for (const auto& [name, count] : j.at("outcomes").items()) {
    total += count.get<int>();
  }
  EXPECT_EQ(total, 20);
  const double rate = j.at("goal_rate").get<double>();
  EXPECT_GE(rate, 0.0);
  EXPECT_LE(rate, 1.0);
}

// An env without HFO's actions (Platform) plays --policy random over all its actions and
// parameters; the scripted offense is refused there with the ways that work.
TEST(Cli, EvalRandomPolicyPlaysAnyEnv) {
  const RunResult r = run_pamdp("eval --env platform --policy random --episodes 50 --json", Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(last_line(r.output));
  EXPECT_EQ(j.value("episodes", -1), 50);
  EXPECT_TRUE(j.at("outcomes").contains("FELL")) << r.output;
  const RunResult scripted = run_pamdp("eval --env platform --episodes 5");
  EXPECT_NE(scripted.exit_code, 0);
  EXPECT_NE(scripted.output.find("takes --checkpoint FILE, or --policy random"), std::string::npos) << scripted.output;
}

// --trace writes one CSV row per step (plus a header naming every column) and leaves the
// table and the JSON as they are without it.
TEST(Cli, EvalTraceWritesOneRowPerStep) {
  const TempFile trace(".trace.csv", "");
  const std::string& file = trace.path();
  const RunResult traced = run_pamdp("eval --episodes 4 --seed 3 --json --trace " + file, Capture::kStdoutOnly);
  const RunResult plain = run_pamdp("eval --episodes 4 --seed 3 --json", Capture::kStdoutOnly);
  ASSERT_EQ(traced.exit_code, 0) << traced.output;
  EXPECT_EQ(traced.output, plain.output);
  const nlohmann::json j = nlohmann::json::parse(last_line(traced.output));

  std::ifstream in(file);
  std::string header;
  ASSERT_TRUE(std::getline(in, header)) << file;
  const std::vector<std::string> columns = split(header, ',');
  ASSERT_GE(columns.size(), 3U + 6U + 2U + 58U) << header;
  EXPECT_EQ(columns[0], "episode");
  EXPECT_EQ(columns[2], "action");
  EXPECT_EQ(columns.back(), "obs_57");
  int rows = 0;
  int goals = 0;
  std::string line;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line, ',');
    ASSERT_EQ(cells.size(), columns.size()) << line;
    ++rows;
    goals += cells[columns.size() - 59] == "GOAL" ? 1 : 0;
  }
  EXPECT_EQ(rows, static_cast<int>(std::lround(j.at("avg_steps").get<double>() * 4)));
  EXPECT_EQ(goals, j.at("outcomes").at("GOAL").get<int>());
}

// A simulator flag given with --checkpoint changes that setting of the checkpoint's env: --start hfo
// plays the real server's start distribution, exactly as --set env.start=hfo does, and not the
// paper's starts the run was trained on; --max-steps likewise.
TEST(Cli, EvalCheckpointTakesTheSimulatorFlagsGiven) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-1v0-fast-seed1.ckpt";
  const std::string eval = "eval --checkpoint " + model + " --episodes 30 --json";
  const RunResult own = run_pamdp(eval, Capture::kStdoutOnly);
  const RunResult flag = run_pamdp(eval + " --start hfo", Capture::kStdoutOnly);
  const RunResult set = run_pamdp(eval + " --set env.start=hfo", Capture::kStdoutOnly);
  ASSERT_EQ(own.exit_code, 0) << own.output;
  ASSERT_EQ(flag.exit_code, 0) << flag.output;
  ASSERT_EQ(set.exit_code, 0) << set.output;
  EXPECT_NE(last_line(own.output), last_line(flag.output));
  EXPECT_EQ(last_line(flag.output), last_line(set.output));
  const RunResult short_episodes = run_pamdp(eval + " --max-steps 20", Capture::kStdoutOnly);
  ASSERT_EQ(short_episodes.exit_code, 0) << short_episodes.output;
  EXPECT_LE(nlohmann::json::parse(last_line(short_episodes.output)).at("avg_steps").get<double>(), 21.0);
}

// --actor target plays the checkpoint's target actor: a different network from the online one
// (so a different result on the same episodes), and still the trained agent (it scores).
TEST(Cli, EvalActorTargetPlaysTheTargetNetwork) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-1v0-fast-seed1.ckpt";
  const RunResult online = run_pamdp("eval --checkpoint " + model + " --episodes 30 --json", Capture::kStdoutOnly);
  const RunResult target =
      run_pamdp("eval --checkpoint " + model + " --episodes 30 --json --actor target", Capture::kStdoutOnly);
  ASSERT_EQ(online.exit_code, 0) << online.output;
  ASSERT_EQ(target.exit_code, 0) << target.output;
  EXPECT_NE(online.output, target.output);
  EXPECT_GE(nlohmann::json::parse(last_line(target.output)).at("goal_rate").get<double>(), 0.8) << target.output;
}

// A checkpoint with an actor average plays it by default (its run's evaluations did), says so, and
// --actor online/average pick either. Here the average is set to the target network's weights, so
// "average" must answer exactly what --actor target answers. A checkpoint without an average
// refuses --actor average, naming the key.
TEST(Cli, EvalPlaysTheActorAverageByDefaultWhenTheRunKeptOne) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-1v0-fast-seed1.ckpt";
  pamdp::app::ExperimentConfig c = pamdp::app::parse_experiment_config(pamdp::read_checkpoint_config(model), model, {});
  c.ddpg.actor_average_tau = 1e-5;
  pamdp::hfo::HfoEnv env(pamdp::hfo::sim_config(c.env.params));
  pamdp::DdpgAlgorithm learner(env.observation_size(), env.action_space(), c.ddpg, 1, pamdp::UpdateDevice::kCpu);
  pamdp::Ddpg& ddpg = learner.ddpg();
  pamdp::CheckpointMeta meta = pamdp::load_checkpoint(model, learner);
  const auto target = ddpg.target_actor().params();
  std::copy(target.begin(), target.end(), ddpg.actor_average().params().begin());
  meta.config_toml = pamdp::app::to_toml(c);
  const TempFile averaged_file(".average.ckpt", "");
  const std::string& averaged = averaged_file.path();
  pamdp::save_checkpoint(averaged, learner, meta);

  const std::string eval = "eval --episodes 20 --json --checkpoint ";
  const RunResult plain = run_pamdp(eval + averaged, Capture::kStdoutOnly);
  const RunResult told = run_pamdp(eval + averaged);
  const RunResult average = run_pamdp(eval + averaged + " --actor average", Capture::kStdoutOnly);
  const RunResult online = run_pamdp(eval + averaged + " --actor online", Capture::kStdoutOnly);
  const RunResult as_target = run_pamdp(eval + model + " --actor target", Capture::kStdoutOnly);
  for (const RunResult* r : {&plain, &told, &average, &online, &as_target}) {
    ASSERT_EQ(r->exit_code, 0) << r->output;
  }
  EXPECT_NE(told.output.find("plays its actor average"), std::string::npos) << told.output;
  EXPECT_EQ(last_line(plain.output), last_line(average.output));
  EXPECT_EQ(last_line(average.output), last_line(as_target.output));
  EXPECT_NE(last_line(average.output), last_line(online.output));

  const RunResult refused = run_pamdp(eval + model + " --actor average");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("ddpg.actor_average_tau"), std::string::npos) << refused.output;
}

// --agreement: the scripted offense plays (the table and its outcomes are the offense's own,
// as `eval --goalie` gives them on the same starts), the checkpoint's actor is asked at every step.
TEST(Cli, EvalAgreementLetsTheOffensePlayAndAsksTheCheckpoint) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-1v1-pn01-seed2-3m.ckpt";
  const RunResult r =
      run_pamdp("eval --checkpoint " + model + " --agreement --episodes 20 --seed 3 --json", Capture::kStdoutOnly);
  const RunResult offense = run_pamdp("eval --goalie --episodes 20 --seed 3 --json", Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(offense.exit_code, 0) << offense.output;
  EXPECT_NE(r.output.find("agreement of"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(last_line(r.output));
  nlohmann::json played = j;
  played.erase("agreement");
  EXPECT_EQ(played, nlohmann::json::parse(last_line(offense.output)));
  const nlohmann::json& a = j.at("agreement");
  int steps = 0;
  for (const auto& [name, action] : a.at("actions").items()) {
    steps += action.at("steps").get<int>();
    const double same = action.at("same_action").get<double>();
    EXPECT_GE(same, 0.0) << name;
    EXPECT_LE(same, 1.0) << name;
  }
  EXPECT_EQ(steps, a.at("steps").get<int>());
  EXPECT_NEAR(j.at("avg_steps").get<double>() * 20, steps, 1e-6);
  // The trained agent dashes where its teacher dashes nearly always.
  EXPECT_GT(a.at("actions").at("DASH").at("same_action").get<double>(), 0.9) << j.dump();
}

// A checkpoint trained with env.shoot_action (a second kick, SHOOT) plays with it: the committed
// striker shoots with SHOOT and scores against agent2d's goalie (.844 on 1,000 episodes of these
// starts; 40 here, so a bound well below), and its trace names SHOOT's two parameters.
TEST(Cli, EvalPlaysACheckpointWithTheShootAction) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-1v1-close-in-shoot-seed2.ckpt";
  const TempFile trace(".trace.csv", "");
  const std::string& file = trace.path();
  const RunResult r =
      run_pamdp("eval --checkpoint " + model + " --goalie --start hfo --episodes 40 --json --trace " + file,
                Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(last_line(r.output));
  EXPECT_GE(j.at("goal_rate").get<double>(), 0.6) << j.dump();
  std::ifstream in(file);
  std::string header;
  ASSERT_TRUE(std::getline(in, header)) << file;
  EXPECT_NE(header.find(",kick_power,kick_dir,shoot_power,shoot_dir,reward,"), std::string::npos) << header;
  int shots = 0;
  for (std::string line; std::getline(in, line);) {
    shots += split(line, ',').at(2) == "SHOOT" ? 1 : 0;
  }
  EXPECT_GE(shots, j.at("outcomes").at("GOAL").get<int>() / 2);
}

// --shot picks the scripted offense's aim for --policy scripted and for --agreement alike; with
// a checkpoint it needs --agreement (the offense does not play otherwise).
TEST(Cli, EvalShotAimsTheOffenseThatPlays) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-1v1-pn01-seed2-3m.ckpt";
  const RunResult asked =
      run_pamdp("eval --checkpoint " + model + " --agreement --shot bottom-post --episodes 20 --seed 3 --json",
                Capture::kStdoutOnly);
  const RunResult offense =
      run_pamdp("eval --goalie --shot bottom-post --episodes 20 --seed 3 --json", Capture::kStdoutOnly);
  ASSERT_EQ(asked.exit_code, 0) << asked.output;
  ASSERT_EQ(offense.exit_code, 0) << offense.output;
  nlohmann::json played = nlohmann::json::parse(last_line(asked.output));
  played.erase("agreement");
  EXPECT_EQ(played, nlohmann::json::parse(last_line(offense.output)));

  const RunResult refused = run_pamdp("eval --checkpoint " + model + " --shot bottom-post --episodes 1");
  EXPECT_NE(refused.exit_code, 0) << refused.output;
  EXPECT_NE(refused.output.find("add --agreement"), std::string::npos) << refused.output;
}

TEST(Cli, EvalTraceRefusesAnUnwritablePath) {
  const RunResult r = run_pamdp("eval --episodes 1 --trace /nonexistent-dir/trace.csv");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("--trace /nonexistent-dir/trace.csv"), std::string::npos) << r.output;
}

TEST(Cli, EvalIsDeterministicForAGivenSeed) {
  const RunResult a = run_pamdp("eval --episodes 10 --policy random --seed 5 --json", Capture::kStdoutOnly);
  const RunResult b = run_pamdp("eval --episodes 10 --policy random --seed 5 --json", Capture::kStdoutOnly);
  ASSERT_EQ(a.exit_code, 0) << a.output;
  EXPECT_EQ(a.output, b.output);
}

struct BadInvocation {
  std::string name;
  std::string args;
  std::vector<std::string> message_names;  // substrings the error message must contain
};

// `sim trace --goalie` sets the goalie from STATE.json and reports its command and state per
// step. Row 3 of the real goalie transitions (tests/data): the real goalie caught (direction
// 88.7726 from the body) and was moved to (49.2903, 5.7541) facing 156.152 degrees.
TEST(Cli, SimTraceSetsAndReportsTheGoalie) {
  const TempFile state(".json",
                       R"({"agent": {"x": 40.745, "y": 7.0847, "vx": 0.3374, "vy": -0.0712, "body_deg": -11.456,
                           "stamina": 6315},
                           "ball": {"x": 48.9381, "y": 5.9098, "vx": 1.9668, "vy": -0.276},
                           "goalie": {"x": 49.9714, "y": 5.453, "vx": 0, "vy": 0.1344, "body_deg": 90,
                                      "stamina": 7935}})");
  const TempFile actions(".csv", "DASH,100,0\n");
  const RunResult r =
      run_pamdp("sim trace --no-noise --goalie --init " + quoted(state.path()) + " --actions " + quoted(actions.path()),
                Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::istringstream in(r.output);
  std::string header;
  std::string first;
  std::string second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_NE(header.find(",f65,g_cmd,g_p1,g_p2,g_x,g_y,g_vx,g_vy,g_body"), std::string::npos) << header;
  const auto cells = [](const std::string& line) {
    std::vector<std::string> out;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) {
      out.push_back(c);
    }
    if (!line.empty() && line.back() == ',') {
      out.emplace_back();
    }
    return out;
  };
  const std::vector<std::string> a = cells(first);
  const std::vector<std::string> b = cells(second);
  ASSERT_EQ(a.size(), 3U + 66U + 8U) << first;
  ASSERT_EQ(b.size(), a.size()) << second;
  const size_t g = 3 + 66;
  EXPECT_EQ(a[g], "") << "no command on the first row";
  EXPECT_NEAR(std::stod(a[g + 3]), 49.9714, 1e-9);
  EXPECT_NEAR(std::stod(a[g + 4]), 5.453, 1e-9);
  EXPECT_EQ(b[1], "IN_GAME");
  EXPECT_EQ(b[g], "CATCH");
  EXPECT_NEAR(std::stod(b[g + 1]), 88.7726, 1e-2);
  EXPECT_EQ(b[g + 2], "") << "a catch has one parameter";
  EXPECT_NEAR(std::stod(b[g + 3]), 49.2903, 2e-4);
  EXPECT_NEAR(std::stod(b[g + 4]), 5.7541, 2e-4);
  EXPECT_NEAR(std::stod(b[g + 7]), 156.152, 1e-2);
}

// pamdp eval --offense-agents 2: the scripted team in one embedded 2v1 game (.93 on 1,000
// episodes); a checkpoint is one agent's and is refused with the fix.
TEST(Cli, EvalPlaysAScriptedTeam) {
  const RunResult r =
      run_pamdp("eval --offense-agents 2 --goalie --start hfo --episodes 100 --seed 2 --json", Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = last_line(r.output);
  const auto at = json.find("\"goal_rate\":");
  ASSERT_NE(at, std::string::npos) << json;
  EXPECT_GT(std::stod(json.substr(at + 12)), 0.8) << json;
  EXPECT_NE(json.find("\"episodes\":100"), std::string::npos) << json;
  const RunResult bad =
      run_pamdp("eval --offense-agents 2 --checkpoint " + quoted(PAMDP_SOURCE_DIR "/models/hfo-1v0-fast-seed1.ckpt"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("leave out --offense-agents"), std::string::npos) << bad.output;
}

// The committed 2v0 team plays as trained: both players from one network, the team's row.
TEST(Cli, EvalPlaysATeamCheckpoint) {
  const std::string model = std::string(PAMDP_SOURCE_DIR) + "/models/hfo-2v0-mpdqn-seed1.ckpt";
  const std::string trace = (std::filesystem::temp_directory_path() / "pamdp_cli_team_trace.csv").string();
  const RunResult r =
      run_pamdp("eval --checkpoint " + quoted(model) + " --episodes 100 --seed 77 --json --trace " + quoted(trace),
                Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = last_line(r.output);
  const auto at = json.find("\"goal_rate\":");
  ASSERT_NE(at, std::string::npos) << json;
  EXPECT_GT(std::stod(json.substr(at + 12)), 0.95) << json;  // .987 on 1,000 of these episodes
  std::ifstream in(trace);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("episode,step,player,action,", 0), 0U) << header;
  std::string row0;
  std::string row1;
  std::getline(in, row0);
  std::getline(in, row1);
  EXPECT_EQ(row0.rfind("0,1,0,", 0), 0U) << row0;
  EXPECT_EQ(row1.rfind("0,1,1,", 0), 0U) << row1;
  std::filesystem::remove(trace);
}

// Two offense players (issue 79): STATE.json's teammates, one action each per row separated by
// '|', player 0's features (58 + 8 for the teammate) and every player's and the ball's state at
// the end of each row. Both kick the touching ball in one cycle: player 0 (body 0) KICK 100 at
// 0 pushes (2.7, 0), player 1 (body 180, from the other side) KICK 100 at 90 pushes (0, -2.7);
// the sum is capped at 2.7, so the ball moves by (1.9091883, -1.9091883) (hfo_team_test).
TEST(Cli, SimTraceWithTeammates) {
  const TempFile state(".json", R"({"agent": {"x": 0, "y": 0, "body_deg": 0},
                                    "teammates": [{"x": 0.77, "y": 0, "body_deg": 180}],
                                    "ball": {"x": 0.385, "y": 0}})");
  const TempFile actions(".csv", "KICK,100,0|KICK,100,90\n");
  const RunResult r =
      run_pamdp("sim trace --no-noise --init " + quoted(state.path()) + " --actions " + quoted(actions.path()),
                Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<std::string> lines = split(r.output, '\n');
  ASSERT_GE(lines.size(), 3U) << r.output;
  const std::vector<std::string> header = split(lines[0], ',');
  ASSERT_EQ(header.size(), 3U + 66U + 2U * 5U + 4U) << lines[0];
  EXPECT_EQ(header[3 + 65], "f65");
  EXPECT_EQ(header[3 + 66], "p0_x");
  EXPECT_EQ(header[3 + 66 + 5], "p1_x");
  EXPECT_EQ(header.back(), "b_vy");
  const std::vector<std::string> after = split(lines[2], ',');
  ASSERT_EQ(after.size(), header.size());
  const double a = 2.7 / std::sqrt(2.0);
  EXPECT_NEAR(std::stod(after[header.size() - 4]), 0.385 + a, 1e-6);
  EXPECT_NEAR(std::stod(after[header.size() - 3]), -a, 1e-6);
  EXPECT_NEAR(std::stod(after[header.size() - 2]), a * 0.94, 1e-6);
  // A row with one action for two players is refused, naming the file and line.
  const TempFile short_row(".csv", "KICK,100,0\n");
  const RunResult bad =
      run_pamdp("sim trace --init " + quoted(state.path()) + " --actions " + quoted(short_row.path()));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find(":1: expected 2 actions separated by '|'"), std::string::npos) << bad.output;
}

// The goalie's memory keys: the same state with the goalie still frozen for 2 cycles by its
// own tackle sends no body command for two steps (the server would refuse it), and after its
// own catch ("caught") it does not catch again: it keeps its position.
TEST(Cli, SimTraceTakesTheGoaliesMemory) {
  const auto trace = [](const std::string& ball, const std::string& goalie) {
    const TempFile state(".json", R"({"agent": {"x": 40.745, "y": 7.0847, "body_deg": -11.456}, "ball": )" + ball +
                                      R"(, "goalie": )" + goalie + "}");
    const TempFile actions(".csv", "DASH,100,0\nDASH,100,0\nDASH,100,0\n");
    const RunResult r = run_pamdp(
        "sim trace --no-noise --goalie --init " + quoted(state.path()) + " --actions " + quoted(actions.path()),
        Capture::kStdoutOnly);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::vector<std::string> commands;
    std::istringstream in(r.output);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::vector<std::string> cells;
      std::stringstream ss(line);
      std::string c;
      while (std::getline(ss, c, ',')) {
        cells.push_back(c);
      }
      commands.push_back(cells.size() > 69 ? cells[69] : "");
    }
    return commands;
  };
  // A ball rolling slowly toward a goalie 5 m away, which would move at once.
  const std::string slow = R"({"x": 45, "y": 0, "vx": 0.5, "vy": 0})";
  const std::vector<std::string> free = trace(slow, R"({"x": 50, "y": 2, "body_deg": 180})");
  const std::vector<std::string> frozen = trace(slow, R"({"x": 50, "y": 2, "body_deg": 180, "tackle_cycles": 2})");
  ASSERT_EQ(free.size(), 4U);
  ASSERT_EQ(frozen.size(), 4U);
  EXPECT_NE(free[1], "NONE");
  EXPECT_EQ(frozen[1], "NONE");
  EXPECT_EQ(frozen[2], "NONE");
  EXPECT_NE(frozen[3], "NONE");
  // Row 3 of the real goalie transitions (above): it catches, unless it caught already.
  const std::string shot = R"({"x": 48.9381, "y": 5.9098, "vx": 1.9668, "vy": -0.276})";
  const std::string keeper = R"({"x": 49.9714, "y": 5.453, "vy": 0.1344, "body_deg": 90)";
  const std::vector<std::string> catches = trace(shot, keeper + "}");
  const std::vector<std::string> caught = trace(shot, keeper + R"(, "caught": true})");
  ASSERT_GE(catches.size(), 2U);
  ASSERT_GE(caught.size(), 2U);
  EXPECT_EQ(catches[1], "CATCH");
  EXPECT_NE(caught[1], "CATCH");
  EXPECT_NE(caught[1], "NONE");
}

// A field defender's memory through STATE.json (issue 83): the ball rolling ahead of it after its
// self-pass, a queued turn toward the receive point (22, 8) plays first (TURN, its body from 180
// to 159.4); without the memory it runs at the ball (DASH 100). Each row ends with the defender's
// command and state, d1_cmd ... d1_body.
TEST(Cli, SimTraceTakesAFieldDefendersMemory) {
  const auto first_command = [](const std::string& memory) {
    const TempFile state(".json", R"({"agent": {"x": 10, "y": -20}, "ball": {"x": 28.6, "y": 5, "vx": -0.8, "vy": 0},
                                      "goalie": {}, "defenders": [{"x": 30, "y": 5, "body_deg": 180)" +
                                      memory + "}]}");
    const TempFile actions(".csv", "DASH,0,0\n");
    const RunResult r = run_pamdp(
        "sim trace --no-noise --goalie --init " + quoted(state.path()) + " --actions " + quoted(actions.path()),
        Capture::kStdoutOnly);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const std::vector<std::string> lines = split(r.output, '\n');
    EXPECT_GE(lines.size(), 3U) << r.output;
    if (lines.size() < 3) {
      return std::string();
    }
    const std::vector<std::string> header = split(lines[0], ',');
    const std::vector<std::string> row = split(lines[2], ',');
    EXPECT_EQ(header[header.size() - 8], "d1_cmd");
    EXPECT_EQ(row.size(), header.size());
    return row.size() == header.size() ? row[header.size() - 8] : std::string();
  };
  EXPECT_EQ(first_command(R"(, "intention": {"kind": "dribble", "x": 22, "y": 8, "turns": 1, "dashes": 5})"), "TURN");
  EXPECT_EQ(first_command(""), "DASH");
}

// Test names and failure messages show the case's name, not its bytes.
void PrintTo(const BadInvocation& c, std::ostream* os) {
  *os << c.name;
}

class CliRejects : public ::testing::TestWithParam<BadInvocation> {};

TEST_P(CliRejects, ExitsNonZeroNamingTheProblem) {
  const RunResult r = run_pamdp(GetParam().args);
  EXPECT_NE(r.exit_code, 0) << "pamdp " << GetParam().args << " succeeded:\n" << r.output;
  for (const std::string& s : GetParam().message_names) {
    EXPECT_NE(r.output.find(s), std::string::npos) << "message does not name '" << s << "':\n" << r.output;
  }
}

INSTANTIATE_TEST_SUITE_P(
    BadFlags, CliRejects,
    ::testing::Values(BadInvocation{"NegativeEpisodes", "eval --episodes -3", {"--episodes", "-3"}},
                      BadInvocation{"ZeroEpisodes", "eval --episodes 0", {"--episodes", "0"}},
                      BadInvocation{"NonNumericEpisodes", "eval --episodes many", {"--episodes", "many"}},
                      BadInvocation{"UnknownPolicy", "eval --policy foo", {"--policy", "foo"}},
                      BadInvocation{"UnknownActor", "eval --actor mean", {"--actor", "mean"}},
                      BadInvocation{"ActorWithoutCheckpoint", "eval --actor target", {"--actor", "--checkpoint"}},
                      BadInvocation{"AgreementWithoutCheckpoint", "eval --agreement", {"--agreement", "--checkpoint"}},
                      BadInvocation{"UnknownShot", "eval --goalie --shot corner", {"--shot", "corner"}},
                      BadInvocation{"ShotWithRandomPolicy",
                                    "eval --policy random --shot bottom-post",
                                    {"--shot", "--policy scripted"}},
                      BadInvocation{"ShotWithoutGoalie", "eval --shot bottom-post", {"--shot", "--goalie"}},
                      BadInvocation{"UnknownFlag", "eval --no-such-flag", {"--no-such-flag"}},
                      BadInvocation{"UnknownStart", "eval --start nowhere", {"--start", "nowhere"}},
                      // CLI11 answers these two with "A subcommand is required", naming neither the
                      // unknown word nor the valid subcommands; only the exit status is checked.
                      BadInvocation{"UnknownSubcommand", "frobnicate", {}},
                      BadInvocation{"SimWithoutSubcommand", "sim", {}},
                      BadInvocation{"MissingTraceFiles",
                                    "sim trace --init /nonexistent/state.json --actions /nonexistent/a.csv",
                                    {"/nonexistent/state.json"}}),
    [](const ::testing::TestParamInfo<BadInvocation>& info) { return info.param.name; });

// Reads a trace CSV into its header and rows of cells.
struct Csv {
  std::string header;
  std::vector<std::vector<std::string>> rows;
};

Csv parse_csv(const std::string& text) {
  Csv csv;
  std::vector<std::string> lines = split(text, '\n');
  if (lines.empty()) {
    return csv;
  }
  csv.header = lines[0];
  for (size_t i = 1; i < lines.size(); ++i) {
    if (!lines[i].empty()) {
      csv.rows.push_back(split(lines[i], ','));
    }
  }
  return csv;
}

TEST(Cli, SimTraceMatchesGoldenTrace) {
  // Keep these flags in step with tests/golden/regenerate.sh.
  const RunResult r = run_pamdp("sim trace --init " + quoted(kGolden + "/kick_to_goal.state.json") + " --actions " +
                                    quoted(kGolden + "/kick_to_goal.actions.csv") + " --no-noise",
                                Capture::kStdoutOnly);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Csv got = parse_csv(r.output);
  const Csv want = parse_csv(read_text(kGolden + "/kick_to_goal.trace.csv"));
  ASSERT_FALSE(want.rows.empty()) << "golden trace is empty; run tests/golden/regenerate.sh";

  const std::string hint = " (if the physics changed on purpose, run tests/golden/regenerate.sh and review the diff)";
  ASSERT_EQ(got.header, want.header);
  ASSERT_EQ(got.rows.size(), want.rows.size()) << "number of steps differs" << hint;
  const std::vector<std::string> columns = split(want.header, ',');
  constexpr double kTolerance = 1e-6;
  int mismatches = 0;
  for (size_t i = 0; i < want.rows.size(); ++i) {
    const auto& g = got.rows[i];
    const auto& w = want.rows[i];
    ASSERT_EQ(g.size(), columns.size()) << "row " << i;
    ASSERT_EQ(w.size(), columns.size()) << "golden row " << i;
    EXPECT_EQ(g[0], w[0]) << "step column, row " << i;
    EXPECT_EQ(g[1], w[1]) << "status column, row " << i << hint;
    for (size_t c = 2; c < columns.size(); ++c) {
      const double gv = std::stod(g[c]);
      const double wv = std::stod(w[c]);
      if (!(std::fabs(gv - wv) <= kTolerance) && ++mismatches <= 10) {
        ADD_FAILURE() << "step " << w[0] << " column " << columns[c] << ": got " << g[c] << ", golden " << w[c] << hint;
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
}

struct MalformedInput {
  std::string name;
  bool is_state;  // the bad file is STATE.json (else ACTIONS.csv)
  std::string contents;
  std::vector<std::string> message_names;  // besides the file path
};

// Test names and failure messages show the case's name, not its bytes.
void PrintTo(const MalformedInput& c, std::ostream* os) {
  *os << c.name;
}

class CliRejectsMalformedInput : public ::testing::TestWithParam<MalformedInput> {};

TEST_P(CliRejectsMalformedInput, NamesFileAndProblem) {
  const MalformedInput& c = GetParam();
  const TempFile bad(c.is_state ? ".json" : ".csv", c.contents);
  const std::string state = c.is_state ? bad.path() : kGolden + "/kick_to_goal.state.json";
  const std::string actions = c.is_state ? kGolden + "/kick_to_goal.actions.csv" : bad.path();
  const RunResult r = run_pamdp("sim trace --no-noise --init " + quoted(state) + " --actions " + quoted(actions));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(bad.path()), std::string::npos) << "message does not name the file:\n" << r.output;
  for (const std::string& s : c.message_names) {
    EXPECT_NE(r.output.find(s), std::string::npos) << "message does not name '" << s << "':\n" << r.output;
  }
  EXPECT_EQ(r.output.find("step,status"), std::string::npos) << "a trace was printed despite the error";
}

INSTANTIATE_TEST_SUITE_P(
    BadFiles, CliRejectsMalformedInput,
    ::testing::Values(
        MalformedInput{"StateSyntaxError",
                       true,
                       "{\n  \"agent\": {\"x\": 1, \"y\": 2},\n  \"ball\": {\"x\": 3 \"y\": 4}\n}\n",
                       {"line 3"}},
        MalformedInput{"StateMissingKey", true, "{\"agent\": {\"x\": 1}, \"ball\": {\"x\": 3, \"y\": 4}}", {"agent.y"}},
        MalformedInput{"StateUnknownKey",
                       true,
                       "{\"agent\": {\"x\": 1, \"y\": 2, \"z\": 0}, \"ball\": {\"x\": 3, \"y\": 4}}",
                       {"agent.z"}},
        MalformedInput{"StateNotANumber",
                       true,
                       "{\"agent\": {\"x\": \"one\", \"y\": 2}, \"ball\": {\"x\": 3, \"y\": 4}}",
                       {"agent.x"}},
        MalformedInput{"StateGoalieUnknownKey",
                       true,
                       "{\"agent\": {\"x\": 1, \"y\": 2}, \"ball\": {\"x\": 3, \"y\": 4}, \"goalie\": {\"z\": 0}}",
                       {"goalie.z"}},
        MalformedInput{
            "StateGoalieFrozenTooLong",
            true,
            "{\"agent\": {\"x\": 1, \"y\": 2}, \"ball\": {\"x\": 3, \"y\": 4}, \"goalie\": {\"tackle_cycles\": 11}}",
            {"goalie.tackle_cycles", "[0, 10]"}},
        MalformedInput{"StateGoalieCaughtNotABoolean",
                       true,
                       "{\"agent\": {\"x\": 1, \"y\": 2}, \"ball\": {\"x\": 3, \"y\": 4}, \"goalie\": {\"caught\": 1}}",
                       {"goalie.caught"}},
        MalformedInput{"StateGoalieWithoutGoalieFlag",
                       true,
                       "{\"agent\": {\"x\": 1, \"y\": 2}, \"ball\": {\"x\": 3, \"y\": 4}, \"goalie\": {\"x\": 50}}",
                       {"goalie", "--goalie"}},
        MalformedInput{"ActionsUnknownAction", false, "DASH,100,0\n# comment\nJUMP,1\n", {":3:", "JUMP"}},
        MalformedInput{"ActionsWrongArity", false, "DASH,100,0\n\nTURN,10\nKICK,100\n", {":4:", "KICK,power,dir"}},
        MalformedInput{"ActionsNotANumber", false, "DASH,fast,0\n", {":1:", "fast"}}),
    [](const ::testing::TestParamInfo<MalformedInput>& info) { return info.param.name; });

// Every error a user can cause (issue 81): exit status 2 (pamdp --help's "Exit status") and one
// line on stderr, `pamdp: error: …`, that names the problem and the fix, with no usage text.
struct UserError {
  std::string name;
  std::string args;
  std::vector<std::string> message_names;  // substrings the line must contain
  std::vector<std::string> absent = {};    // substrings it must not (a misleading diagnosis)
};

void PrintTo(const UserError& c, std::ostream* os) {
  *os << c.name;
}

// `pamdp <args>` with its stderr only.
RunResult run_pamdp_stderr(const std::string& args) {
  return run_pamdp(args, Capture::kStderrOnly);
}

void expect_one_error_line(const RunResult& r, const std::vector<std::string>& names,
                           const std::vector<std::string>& absent = {}) {
  EXPECT_EQ(r.exit_code, 2) << r.output;
  std::vector<std::string> lines;
  for (const std::string& line : split(r.output, '\n')) {
    if (!line.empty()) {
      lines.push_back(line);
    }
  }
  ASSERT_EQ(lines.size(), 1U) << "stderr is not one line:\n" << r.output;
  EXPECT_EQ(lines[0].rfind("pamdp: error: ", 0), 0U) << lines[0];
  for (const std::string& s : names) {
    EXPECT_NE(lines[0].find(s), std::string::npos) << "the line does not name '" << s << "':\n" << lines[0];
  }
  for (const std::string& s : absent) {
    EXPECT_EQ(lines[0].find(s), std::string::npos) << "the line names '" << s << "':\n" << lines[0];
  }
}

class CliUserErrors : public ::testing::TestWithParam<UserError> {};

TEST_P(CliUserErrors, OneLineNamingTheFixAndExitTwo) {
  const RunResult r = run_pamdp_stderr(GetParam().args);
  expect_one_error_line(r, GetParam().message_names, GetParam().absent);
}

const std::string kReachStop = quoted(PAMDP_SOURCE_DIR "/deploy/configs/reach_stop.toml");
const std::string kUnusedRun = quoted(::testing::TempDir() + "pamdp_cli_unused_run");

INSTANTIATE_TEST_SUITE_P(
    Issue81, CliUserErrors,
    ::testing::Values(
        UserError{
            "EpisodesOutOfRange", "eval --episodes -1", {"--episodes", "[1, 100000000]", "got -1", "eval --help"}},
        UserError{"MissingCheckpoint",
                  "eval --checkpoint /nonexistent/agent.ckpt",
                  {"--checkpoint", "/nonexistent/agent.ckpt", "models/*.ckpt"}},
        UserError{"PlotMissingDirectory", "plot /nonexistent/run", {"/nonexistent/run", "run directory"}},
        UserError{"JoinWithoutScheme",
                  "actor --join 127.0.0.1:5999",
                  {"--join", "tcp://127.0.0.1:5999"},
                  {"CURVE", "beyond"}},
        UserError{"ReplayJoinWithoutScheme", "replay --join 127.0.0.1:5999", {"--join", "tcp://127.0.0.1:5999"}},
        UserError{"SetNamesTheCommandLine",
                  "train --config " + kReachStop + " --set ddpg.gamma=2 --run-dir " + kUnusedRun,
                  {"--set ddpg.gamma=2", "[0, 1]"},
                  {"reach_stop.toml"}},
        UserError{"SetUnknownKeyNamesTheCommandLine",
                  "train --config " + kReachStop + " --set ddpg.gama=0.9 --run-dir " + kUnusedRun,
                  {"--set ddpg.gama=0.9", "gamma"},
                  {"reach_stop.toml"}},
        UserError{
            "LearnerBindWithoutScheme",
            "learner --config " + kReachStop + " --set cluster.learner_bind=127.0.0.1:5555 --run-dir " + kUnusedRun,
            {"cluster.learner_bind", "tcp://"},
            {"CURVE"}},
        UserError{"LogLevelUnknown", "train --log-level loud", {"--log-level", "loud"}},
        UserError{"UnknownFlag", "eval --no-such-flag", {"--no-such-flag", "pamdp eval --help"}},
        UserError{"NoSubcommand", "", {"valid: actor", "eval", "train"}},
        UserError{"SimWithoutSubcommand", "sim", {"pamdp sim", "trace"}},
        UserError{"UnknownSubcommand", "frobnicate", {"frobnicate", "valid:"}},
        UserError{"MissingTraceState",
                  "sim trace --init /nonexistent/state.json --actions /nonexistent/a.csv",
                  {"--init", "/nonexistent/state.json"}},
        UserError{"ResumeWithoutARun", "train --resume /nonexistent/run", {"/nonexistent/run", "--resume"}}),
    [](const ::testing::TestParamInfo<UserError>& info) { return info.param.name; });

// A run directory under the test temp dir, removed when the test ends.
class TempRun {
 public:
  explicit TempRun(const std::string& name)
      : path_(::testing::TempDir() + "pamdp_cli_" + name + "_" + std::to_string(::getpid())) {
    std::filesystem::remove_all(path_);
  }
  ~TempRun() { std::filesystem::remove_all(path_); }
  TempRun(const TempRun&) = delete;
  TempRun& operator=(const TempRun&) = delete;
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A learner (or shard) whose port is taken names the key (or flag) that moves it.
TEST(CliUserErrors, PortInUseNamesTheConfigKey) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  ASSERT_EQ(::listen(fd, 1), 0);
  socklen_t len = sizeof(addr);
  ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  const std::string port = std::to_string(ntohs(addr.sin_port));
  const TempRun run("busy");
  const RunResult r = run_pamdp_stderr("learner --config " + kReachStop + " --run-dir " + quoted(run.path()) +
                                       " --set cluster.learner_bind=tcp://127.0.0.1:" + port +
                                       " --set cluster.weights_bind=tcp://127.0.0.1:0 --metrics-port 0");
  const RunResult shard = run_pamdp_stderr(
      "replay --join tcp://127.0.0.1:1 --join-timeout 1 --insert-bind tcp://127.0.0.1:" + port + " --metrics-port 0");
  ::close(fd);
  expect_one_error_line(r, {port, "in use", "--set cluster.learner_bind=tcp://127.0.0.1:PORT"});
  expect_one_error_line(shard, {port, "in use", "--insert-bind tcp://127.0.0.1:PORT"});
}

// A tiny run of the toy task (seconds), for the tests below.
const std::string kTinyRun =
    " --set train.max_updates=300 --set replay.warmup=100 --set train.eval_every_updates=0 "
    "--set train.eval_episodes=5 --set ddpg.hidden=[16,16]";

// --resume with a replay memory of another shape (replay.capacity changed by --set) names the fix.
TEST(CliUserErrors, ResumeWithAnotherReplayShapeNamesTheFix) {
  const TempRun run("reshape");
  const RunResult made =
      run_pamdp("train --quiet --config " + kReachStop + kTinyRun + " --run-dir " + quoted(run.path()));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const std::string config = read_text(run.path() + "/config.toml");
  const RunResult r = run_pamdp_stderr("train --resume " + quoted(run.path()) + " --set replay.capacity=5000");
  expect_one_error_line(r, {"replay.bin", "replay.capacity", "without the --set"});
  // Refused before the run directory is touched: the fix it names (resume without the --set) works.
  EXPECT_EQ(read_text(run.path() + "/config.toml"), config);
  const RunResult resumed = run_pamdp("train --quiet --resume " + quoted(run.path()) + " --set train.max_updates=400");
  EXPECT_EQ(resumed.exit_code, 0) << resumed.output;
}

// --log-level comes after `train` as after `actor`; --quiet drops the [info] lines, an explicit
// --log-level wins over it, and a plain run has them (so the checks below can fail).
TEST(CliUserErrors, LogLevelAfterTrainAndQuiet) {
  const auto train = [](const std::string& name, const std::string& flags) {
    const TempRun run(name);
    return run_pamdp("train --config " + kReachStop + kTinyRun + " --run-dir " + quoted(run.path()) + " " + flags);
  };
  const RunResult plain = train("plain", "");
  const RunResult warn = train("warn", "--log-level warn");
  const RunResult quiet = train("quiet", "--quiet");
  const RunResult quiet_debug = train("quiet_debug", "--quiet --log-level debug");
  for (const RunResult* r : {&plain, &warn, &quiet, &quiet_debug}) {
    ASSERT_EQ(r->exit_code, 0) << r->output;
    EXPECT_NE(r->output.find("done: 300 updates"), std::string::npos) << r->output;
  }
  EXPECT_NE(plain.output.find("[info]"), std::string::npos) << plain.output;
  EXPECT_EQ(warn.output.find("[info]"), std::string::npos) << warn.output;
  EXPECT_EQ(quiet.output.find("[info]"), std::string::npos) << quiet.output;
  EXPECT_EQ(quiet.output.find("updates/s"), std::string::npos) << "--quiet printed progress lines:\n" << quiet.output;
  EXPECT_NE(quiet_debug.output.find("[info]"), std::string::npos) << quiet_debug.output;
}

// The toy run's summary (issue 81): it stops at exactly train.max_updates, logs its final
// evaluation once, and says nothing of steps to success when nothing succeeded.
TEST(CliUserErrors, ToyRunSummary) {
  const TempRun run("toy");
  const RunResult r = run_pamdp("train --config " + kReachStop + " --run-dir " + quoted(run.path()) +
                                " --set train.max_updates=2000 --set train.eval_every_updates=1000 "
                                "--set train.eval_episodes=20 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("done: 2000 updates"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(last_line(r.output));
  EXPECT_EQ(j["updates"], 2000);
  int at_end = 0;
  int rows_at_end = 0;
  for (const std::string& line : split(r.output, '\n')) {
    at_end += line.find("greedy evaluation at 2000 updates") != std::string::npos ? 1 : 0;
    rows_at_end += line.find("] updates 2000 |") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(at_end, 1) << r.output;
  EXPECT_EQ(rows_at_end, 1) << r.output;
  const double success = j["eval"]["goal_rate"];
  EXPECT_EQ(r.output.find("avg steps to success") != std::string::npos, success > 0.0) << r.output;
}

}  // namespace
