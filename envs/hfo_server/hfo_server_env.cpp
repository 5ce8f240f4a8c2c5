// HfoServerEnv over HFO's client library. Compiled only with -DHFO_ROOT (PAMDP_HFO_ROOT is that
// path); hfo_server_unavailable.cpp stands in for it otherwise.
#include "envs/hfo_server/hfo_server_env.hpp"

#include <HFO.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <thread>
#include <vector>

#include "envs/hfo/features.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/soccer_sim.hpp"
#include "envs/hfo_server/feature_encoding.hpp"
#include "envs/hfo_server/server_action.hpp"
#include "envs/hfo_server/server_probe.hpp"

namespace pamdp::hfo_server {
namespace {

// HFO's status codes are the embedded env's (reference §4); the adapter passes them through.
static_assert(static_cast<int>(::hfo::IN_GAME) == hfo::kInGame);
static_assert(static_cast<int>(::hfo::GOAL) == hfo::kGoal);
static_assert(static_cast<int>(::hfo::CAPTURED_BY_DEFENSE) == hfo::kCapturedByDefense);
static_assert(static_cast<int>(::hfo::OUT_OF_BOUNDS) == hfo::kOutOfBounds);
static_assert(static_cast<int>(::hfo::OUT_OF_TIME) == hfo::kOutOfTime);

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "HfoServerEnv: %s\n", what);
  std::abort();
}

std::string address(const HfoServerConfig& c) {
  return c.host + ":" + std::to_string(c.port);
}

// HFO's client library calls exit(1) when it cannot start (it has no error return). While a
// connection is being made, this says which server and what to do before the process ends.
// Per thread: the players of one team env (LockstepTeamEnv) connect at once, each on its own.
thread_local char g_connecting_to[512] = {};
extern "C" void explain_exit_while_connecting() {
  if (g_connecting_to[0] != '\0') {
    std::fprintf(stderr,
                 "hfo-server: HFO's client library gave up connecting to %s (its message above). Connect only "
                 "after bin/HFO has printed 'Waiting for player-controlled agent' (an agent that joins earlier takes "
                 "an NPC's place, the trainer disconnects it and the game never starts), and to a server whose agent "
                 "slot is free; the players of one process (env.server_agents > 1) join env.server_join_interval_ms "
                 "apart, so on a busy machine raise it. That server cannot be used any more: stop its bin/HFO and "
                 "start a fresh one.\n",
                 g_connecting_to);
  }
}

// Waits for the server to answer (up to c.connect_timeout_s), and if it was only starting, for
// its trainer to fill the NPC slots (server_probe.hpp says what joining earlier does).
void wait_for_server(const HfoServerConfig& c) {
  const ServerProbe probe = probe_server(c.host, c.port, c.connect_timeout_s);
  if (!probe.answered) {
    throw std::runtime_error(no_server_message(c, PAMDP_HFO_ROOT));
  }
  if (!probe.answered_at_once) {
    std::fprintf(stderr, "hfo-server: %s answered after %.1f s; giving its trainer %.0f s to fill its NPC slots\n",
                 address(c).c_str(), probe.waited_s, kTrainerFillS);
    std::this_thread::sleep_for(std::chrono::duration<double>(kTrainerFillS));
  }
}

class HfoServerEnv final : public Env {
 public:
  explicit HfoServerEnv(HfoServerConfig config)
      : c_(std::move(config)),
        native_size_(e3_feature_count(c_.teammates, c_.opponents)),
        embedded_(static_cast<size_t>(hfo::feature_count(1 + c_.teammates + c_.opponents))) {}

  ~HfoServerEnv() override {
    if (client_ != nullptr) {
      // Leave the game cleanly ("(bye)"); HFO's trainer then ends the server's session.
      client_->act(::hfo::QUIT);
      (void)client_->step();
    }
  }

  [[nodiscard]] std::string_view name() const override { return "hfo-server"; }
  [[nodiscard]] const ActionSpace& action_space() const override { return hfo::hfo_action_space(c_.shoot_action); }
  [[nodiscard]] int observation_size() const override { return hfo_server::observation_size(c_); }
  [[nodiscard]] int max_episode_steps() const override { return c_.max_steps + 1; }
  [[nodiscard]] std::string_view status_name(int status) const override { return hfo::status_name(status); }
  [[nodiscard]] std::span<const int> outcomes() const override { return hfo::kStatuses; }
  [[nodiscard]] int success_status() const override { return hfo::kGoal; }
  [[nodiscard]] std::span<const EnvCounter> counters() const override {
    counters_ = {{{"kick_power_clamped", clamps_.kick_power},
                  {"dash_power_clamped", clamps_.dash_power},
                  {"direction_wrapped", clamps_.direction}}};
    return counters_;
  }

  // The server's --seed governs its episodes; a seed cannot be sent to it.
  void reset(uint64_t /*seed*/, std::span<float> obs) override { reset(obs); }

  void reset(std::span<float> obs) override {
    if (client_ == nullptr) {
      connect();
    } else if (!at_episode_start_) {
      finish_server_episode();
    }
    at_episode_start_ = true;
    episode_over_ = false;
    steps_ = 0;
    reward_.reset();
    write_observation(obs);
  }

  StepResult step(const ParamAction& action, std::span<float> obs) override {
    if (client_ == nullptr || episode_over_) {
      misuse("step() before reset() or after a terminal status; call reset() first");
    }
    if (action.params.size() < static_cast<size_t>(action_space().num_params())) {
      misuse("step(): the parameter vector must hold the 6 HFO parameters (8 with env.shoot_action)");
    }
    if (action.id < hfo::kDash || action.id >= action_space().num_actions()) {
      misuse("step(): action id out of range (0 DASH, 1 TURN, 2 TACKLE, 3 KICK; 4 SHOOT with env.shoot_action)");
    }
    const ServerCommandArgs a = server_command_args(action, clamps_);
    switch (action.id) {
      case hfo::kDash: client_->act(::hfo::DASH, a.p1, a.p2); break;
      case hfo::kTurn: client_->act(::hfo::TURN, a.p1); break;
      case hfo::kTackle: client_->act(::hfo::TACKLE, a.p1); break;
      default: client_->act(::hfo::KICK, a.p1, a.p2); break;  // KICK, and SHOOT (a kick of its own)
    }
    int status = server_step();
    ++steps_;
    // A terminal status arrives with the next episode's first state (HFO's client already played
    // its three NOOPs), which reset() then returns.
    at_episode_start_ = status != hfo::kInGame;
    if (status == hfo::kInGame && steps_ >= max_episode_steps()) {
      status = hfo::kOutOfTime;  // the server's trial goes on; reset() plays it out
    }
    episode_over_ = status != hfo::kInGame;
    write_observation(obs);
    return {reward_(embedded_, status), status};
  }

 private:
  void connect() {
    const std::string config_dir =
        c_.config_dir.empty() ? std::string(PAMDP_HFO_ROOT "/bin/teams/base/config/formations-dt") : c_.config_dir;
    if (!std::filesystem::is_directory(config_dir)) {
      throw std::runtime_error("hfo-server: env.server_config_dir '" + config_dir +
                               "' is not a directory; point it at HFO's bin/teams/base/config/formations-dt");
    }
    wait_for_server(c_);
    if (c_.join_delay_ms > 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(c_.join_delay_ms));
    }
    static const bool registered = std::atexit(explain_exit_while_connecting) == 0;
    (void)registered;
    std::snprintf(g_connecting_to, sizeof(g_connecting_to), "%s", address(c_).c_str());
    client_ = std::make_unique<::hfo::HFOEnvironment>();
    client_->connectToServer(::hfo::LOW_LEVEL_FEATURE_SET, config_dir, c_.port, c_.host, c_.team,
                             /*play_goalie=*/false);
    g_connecting_to[0] = '\0';
    std::fprintf(stderr, "hfo-server: joined %s as unum %d\n", address(c_).c_str(), client_->getUnum());
    const int teammates = client_->getNumTeammates();
    const int opponents = client_->getNumOpponents();
    const auto features = static_cast<int>(client_->getState().size());
    if (teammates != c_.teammates || opponents != c_.opponents || features != native_size_) {
      throw std::runtime_error("hfo-server: the server at " + address(c_) + " runs " + std::to_string(teammates) +
                               " teammate(s) and " + std::to_string(opponents) + " opponent(s) (" +
                               std::to_string(features) + " features); this env expects " +
                               std::to_string(c_.teammates) + " and " + std::to_string(c_.opponents) +
                               " (env.offense_agents = N for a server started with --offense-agents N, env.goalie "
                               "= true for one with --defense-npcs 1)");
    }
    // The state at connection is the one before kick-off; the server places ball and players for
    // the first episode in the first cycle of play. Two NOOPs make the first observation, like
    // every later episode's (HFO's client NOOPs after a terminal status), two cycles into it.
    for (int i = 0; i < 2; ++i) {
      client_->act(::hfo::NOOP);
      (void)server_step();
    }
  }

  int server_step() {
    const ::hfo::status_t s = client_->step();
    if (s == ::hfo::SERVER_DOWN) {
      throw std::runtime_error("hfo-server: the HFO server at " + address(c_) +
                               " went down (SERVER_DOWN): it stops when its game ends or its process dies; " +
                               how_to_start(c_, PAMDP_HFO_ROOT));
    }
    return static_cast<int>(s);
  }

  // Plays NOOPs until the server ends its current episode.
  void finish_server_episode() {
    for (int n = 0; n < 100 * (c_.max_steps + 200); ++n) {
      client_->act(::hfo::NOOP);
      if (server_step() != hfo::kInGame) {
        return;
      }
    }
    throw std::runtime_error("hfo-server: the server at " + address(c_) +
                             " did not end its episode while the agent waited; is its --untouched-time set?");
  }

  void write_observation(std::span<float> obs) {
    const std::vector<float>& state = client_->getState();
    if (static_cast<int>(state.size()) != native_size_) {
      throw std::runtime_error("hfo-server: the server sent " + std::to_string(state.size()) + " features, expected " +
                               std::to_string(native_size_));
    }
    e3_to_embedded(state, c_.teammates, c_.opponents, embedded_);
    if (c_.encoding == Encoding::kNative) {
      std::copy(state.begin(), state.end(), obs.begin());
    } else {
      std::copy(embedded_.begin(), embedded_.end(), obs.begin());
    }
  }

  HfoServerConfig c_;
  int native_size_;
  std::unique_ptr<::hfo::HFOEnvironment> client_;
  std::vector<float> embedded_;  // the 58-feature view: the reward's input in both encodings
  hfo::ShapedReward reward_;
  ActionClampCounts clamps_;
  mutable std::array<EnvCounter, 3> counters_{};
  int steps_ = 0;
  bool at_episode_start_ = false;
  bool episode_over_ = false;
};

}  // namespace

bool built_with_hfo() {
  return true;
}

std::unique_ptr<Env> make_hfo_server_env(const HfoServerConfig& config) {
  return std::make_unique<HfoServerEnv>(config);
}

}  // namespace pamdp::hfo_server
