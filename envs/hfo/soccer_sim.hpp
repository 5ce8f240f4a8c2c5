// SoccerSim: an in-process re-implementation of the RoboCup 2D server physics and the HFO
// referee for Half Field Offense, as specified in shared/hfo-reference.md (§1, §2, §5).
//
// It owns no socket and no global state: construct as many as you like, one per thread.
// Every call below is O(players) and allocates nothing. players()[0 .. offense_agents - 1]
// are the learned offense players (HFO's --offense-agents N), each commanded through the
// *_player calls; the single-agent calls (dash, turn, ...) command players()[0], the agent
// the 1v0 and 1v1 features describe. With SoccerSimConfig::goalie, players()[goalie_index()]
// (= offense_agents) is the NPC goalie of envs/hfo/goalie.hpp: it decides from the state at
// the start of every step() and its command goes through the same client and server handling
// as the agents' (dash, turn), plus the goalie's catch. Commands of several players in one
// cycle add up as the server's do: two kicks push the ball with the sum of their accelerations.
//
// Units: metres, metres per cycle, degrees for every angle in this API (the server works in
// radians internally; commands and features use degrees).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>

#include "core/rng.hpp"
#include "envs/hfo/geometry.hpp"

namespace pamdp::hfo {

// HFO status codes (reference §4).
enum Status : int {
  kInGame = 0,
  kGoal = 1,
  kCapturedByDefense = 2,
  kOutOfBounds = 3,
  kOutOfTime = 4,
};
const char* status_name(int status);
// Every status code, kInGame first (Env::outcomes() of the HFO envs).
inline constexpr std::array<int, 5> kStatuses{kInGame, kGoal, kCapturedByDefense, kOutOfBounds, kOutOfTime};

// Start-state distribution of the ball and the agent (reference §5.1).
enum class StartDistribution {
  kPaper,    // E1 trainer (the paper's runs): ball x U[5.23, 15.75]; agent clamp x [-0.1, 52.5], |y| <= 34
  kDec2015,  // E2 server referee from Dec 2015: ball x U[0, 10.5]; agent clamp x [-0.1, 21], |y| <= 27.2
  kHfo,      // E3 current HFO defaults: ball x U[0, 10.5]; agent clamp x [-0.1, 52.5], |y| <= 27.2
};

// What the agent's body angle is at an episode start (reference §5.1).
enum class BodyAtReset {
  kCarry,    // kept from the previous episode (real HFO); 0 in the first episode
  kZero,     // always facing the goal
  kUniform,  // drawn U[-180, 180) from the episode's seed
};

// Episode termination rules (reference §5.2 and §5.3).
enum class Referee {
  kServer,   // HFORef inside rcssserver (E2/E3): goal line crossing, OOB one cycle late
  kTrainer,  // the paper-era Python trainer (E1): current-position tests, no end in 5 cycles
};

struct SoccerSimConfig {
  bool noise = true;  // movement, turn, kick and tackle noise (tackle success is always drawn)
  StartDistribution start = StartDistribution::kPaper;
  BodyAtReset body_at_reset = BodyAtReset::kCarry;
  Referee referee = Referee::kServer;
  int max_steps = 500;        // --frames-per-trial used by dqn-hfo
  int untouched_limit = 100;  // cycles the ball may stay untouched
  bool goalie = false;        // an NPC goalie defends the goal (1v1): players()[1], 66 features
  // agent2d's field defenders beside the goalie (HFO's --defense-npcs K gives K - 1; needs the
  // goalie): players()[goalie_index() + 1 ...], each an opponent block of 8 features. 0-2.
  // Their decisions: defender.hpp.
  int field_defenders = 0;
  // Learned offense players, HFO's --offense-agents (1-4): players()[0 .. offense_agents - 1].
  int offense_agents = 1;
  // A curriculum over training (not HFO's; issue 80): a start drawn from `start` has the ball and
  // the players moved toward the goal's centre, to start_curriculum_from of their distance at
  // update 0, rising linearly to the whole distance at start_curriculum_updates
  // (set_training_updates). 0 = off.
  int64_t start_curriculum_updates = 0;
  double start_curriculum_from = 0.25;
};

inline constexpr int kMaxOffenseAgents = 4;
inline constexpr int kMaxFieldDefenders = 2;
// Where HFO puts agent2d's field defenders at every reset (HFORef::resetField): x U[0.4, 0.5] of
// the pitch length, y U[-0.4, 0.4] of its width.
inline constexpr double kDefenderStartMinX = 0.4 * 2.0 * kPitchHalfLength;
inline constexpr double kDefenderStartMaxY = 0.4 * 2.0 * kPitchHalfWidth;
// Index of the NPC goalie in SoccerState::players when SoccerSimConfig::goalie is on and there
// is one offense agent; in general SoccerSim::goalie_index() (= offense_agents).
inline constexpr int kGoalieIndex = 1;
// Where HFO puts the goalie at every reset (reference §5.1), facing the field.
inline constexpr Vec2 kGoalieStart{kPitchHalfLength, 0.0};
inline constexpr double kGoalieStartBodyDeg = 180.0;
// Cycles between HFO's reset and its client's first observation (two NOOPs). With a goalie
// they are played at every reset_episode(): the goalie moves in them.
inline constexpr int kCyclesBeforeFirstObservation = 2;

enum class Team : uint8_t { kOffense, kDefense };

struct PlayerState {
  Vec2 pos;
  Vec2 vel;               // observed (post-decay) velocity
  double body_deg = 0.0;  // global body angle, in (-180, 180]
  double stamina = kStaminaMax;
  double effort = 1.0;
  double recovery = 1.0;
  double capacity = kStaminaCapacity;
  int tackle_cycles = 0;  // > 0 while frozen after a tackle
  int catch_ban = 0;      // goalie: > 0 while a new catch is refused (catch_ban_cycle)
  // Goalie's own memory (librcsc SelfObject::catchTime): cycles since its last catch command,
  // kNoCatchYet when it has not sent one this episode.
  int since_catch = kNoCatchYet;
  static constexpr int kNoCatchYet = 1000;
  // Goalie's own memory: it caught the ball this episode and heard the referee's
  // goalie_catch_ball, so it plays the set play until the reset (goalie_world.hpp, catch_mode).
  bool caught = false;
  // A field defender's own memory: agent2d's queued intention (PlayerAgent holds one at a time).
  // kDribble (IntentionNormalDribble): after its self-pass kick it plays queued turns, then
  // dashes, toward the receive point, one a cycle while the queue holds. kTurnToForward
  // (Bhv_ChainAction's IntentionTurnTo): after a kick that keeps the ball, it turns toward the
  // face point the next cycle. `target` is in the global frame; last_cycle is the state's cycle
  // when the defender last played from (or set) the intention.
  struct Intention {
    enum class Kind : uint8_t { kNone, kDribble, kTurnToForward };
    Kind kind = Kind::kNone;
    Vec2 target;
    int turns = 0;
    int dashes = 0;
    int last_cycle = -1;
  };
  Intention intention;
  // A field defender's Strategy::get_normal_dash_power memory: the recover mode (on below half
  // the maximum stamina, off above 0.7 of it), in which it dashes to its home position at the
  // power it recovers less 25.
  bool recover_mode = false;
  bool collided_ball = false;
  bool collided_player = false;
  bool collided_post = false;
  Team team = Team::kOffense;
  bool goalie = false;
};

struct BallState {
  Vec2 pos;
  Vec2 vel;  // observed (post-decay) velocity
};

// Everything the physics and the referee need to continue an episode.
struct SoccerState {
  static constexpr int kMaxPlayers = 8;  // 4 offense agents, the goalie, room for defenders
  std::array<PlayerState, kMaxPlayers> players{};
  int num_players = 1;
  BallState ball;
  int cycle = 0;             // cycles since the episode started
  int untouched = 0;         // referee's untouched-ball counter
  Vec2 prev_ball;            // ball position at the previous referee check
  int defense_hold = 0;      // consecutive checks a defender was on the ball
  int trainer_hold = 0;      // E1: consecutive cycles one player held the ball
  bool ball_caught = false;  // the goalie caught the ball this episode (ends it under the E1 trainer)
};

class SoccerSim {
 public:
  explicit SoccerSim(const SoccerSimConfig& config, uint64_t seed = 0);

  // Starts an episode with a start state drawn from the configured distribution.
  void reset_episode();
  void reseed(uint64_t seed) { rng_.reseed(seed); }
  // The learner's updates, for the start curriculum (SoccerSimConfig::start_curriculum_updates):
  // the next reset_episode() moves its start toward the goal by the scale this gives. Until
  // called, and with the curriculum off, starts are the distribution's own.
  void set_training_updates(int64_t updates);
  // The scale the next start is drawn with: 1 = the distribution's own.
  [[nodiscard]] double start_scale() const { return start_scale_; }

  // Replaces the state (tests, traces). Referee counters restart at this state; with a goalie
  // configured, the goalie is put back at its start (kGoalieStart, at rest, full stamina).
  // `offense` holds one state per offense agent (config().offense_agents of them; throws
  // std::invalid_argument otherwise); the single-agent form needs offense_agents = 1.
  void set_state(std::span<const PlayerState> offense, const BallState& ball);
  void set_state(const PlayerState& agent, const BallState& ball);
  // Replaces the goalie's state after set_state (traces); its team and role are kept.
  void set_goalie(const PlayerState& goalie);
  // Replaces field defender k's state after set_state (0 .. field_defenders - 1); its team is kept.
  void set_defender(int k, const PlayerState& defender);
  [[nodiscard]] const SoccerState& state() const { return state_; }
  SoccerState& mutable_state() { return state_; }
  [[nodiscard]] const PlayerState& agent() const { return state_.players[0]; }
  [[nodiscard]] const SoccerSimConfig& config() const { return config_; }
  [[nodiscard]] int offense_agents() const { return config_.offense_agents; }
  // Index of the goalie in state().players (meaningful with config().goalie).
  [[nodiscard]] int goalie_index() const { return config_.offense_agents; }
  // Index of field defender k (0 .. config().field_defenders - 1); its unum in agent2d's
  // formation is k + 2.
  [[nodiscard]] int defender_index(int k) const { return config_.offense_agents + 1 + k; }

  // Agent commands, as the HFO agent issues them through librcsc (client-side clamping,
  // wrapping, gating and compensation, then the server's handling). At most one per cycle;
  // each returns false if the command was not sent or was refused (frozen, ball not kickable).
  bool dash(double power, double dir_deg);
  bool turn(double dir_deg);
  bool tackle(double dir_deg);
  bool kick(double power, double dir_deg);
  // The same for offense agent `player` (0 .. offense_agents - 1; a bad index is a programming
  // error and stops the process). Each agent sends at most one of these per cycle.
  bool dash_player(int player, double power, double dir_deg);
  bool turn_player(int player, double dir_deg);
  bool tackle_player(int player, double dir_deg);
  bool kick_player(int player, double power, double dir_deg);

  // The goalie's catch (rcssserver Player::goalieCatch with the defaults of geometry.hpp, in
  // HFO mode): refused unless `player` is a goalie whose catch ban is over; sets the ban;
  // succeeds if the ball centre lies in the catchable rectangle (kCatchableAreaLength along
  // body + dir_deg, kCatchableAreaWidth across). HFO gives no free kick and does not hold the
  // ball: the server moves the goalie toward the ball until they touch (ball_size +
  // player_size from it), turns it to face the ball and stops it, and the ball flies on; the
  // referee ends the episode only once the ball is within the goalie's kickable area.
  // Returns success.
  bool goalie_catch(int player, double dir_deg);

  // The command the goalie sent in the last step(), in the server's units (traces).
  struct GoalieCommandLog {
    uint8_t kind = 0;  // agent2d::Command::Kind
    double p1 = 0.0;
    double p2 = 0.0;
    bool foul = false;  // a foul tackle ((tackle DIR on))
  };
  [[nodiscard]] const GoalieCommandLog& last_goalie_command() const { return last_goalie_command_; }
  // The command field defender k sent in the last step() (a foul tackle has foul set).
  [[nodiscard]] const GoalieCommandLog& last_defender_command(int k) const {
    return last_defender_command_[static_cast<size_t>(k)];
  }

  // A body command exactly as the server received it from `player`'s client (recorded logs,
  // the goalie): DASH power dir, TURN moment, KICK power dir, TACKLE dir, CATCH dir; no client
  // processing. Returns false if the server refuses it. A tackle's success is the server's
  // random draw even with noise off, so a replay may give the logged outcome (`tackle_succeeds`);
  // without it the draw is made as in play. A tackle the geometry rules out still fails.
  bool command_as_received(int player, const char* kind, double p1, double p2,
                           std::optional<bool> tackle_succeeds = std::nullopt);

  // Advances one server cycle (movement, collisions, referee, stamina) and returns the status.
  int step();

  // Client kickable rule (reference §2.7): distance agent-ball <= 1.03.
  [[nodiscard]] bool agent_kickable() const { return kickable(0); }
  [[nodiscard]] bool kickable(int player) const;

 private:
  void check_offense_player(int player) const;
  bool send_dash(int i, double power, double dir_deg);
  bool send_turn(int i, double dir_deg);
  bool send_kick(int i, double power, double dir_deg);
  bool kick_player_server(int i, double power, double dir_deg);
  bool server_dash(int i, double power, double dir_deg);
  bool server_turn(int i, double moment);
  bool server_tackle(int i, double dir_deg, std::optional<bool> succeeds = std::nullopt, bool foul = false);
  // The goalie senses the cycle's state before any command of the cycle changes it (a turn
  // takes effect when the server receives it): decided once, at the first command or step().
  void sense_goalie();
  void play_goalie();
  void play_defenders();
  void play_npc_command(int i, const GoalieCommandLog& c);
  void move_object(Vec2& pos, Vec2& vel, Vec2& accel, double size, double decay, double accel_max, double speed_max,
                   double rand, bool* hit_post);
  void collide_objects();
  int referee_server();
  int referee_trainer();
  void update_stamina(PlayerState& p);
  Vec2 noise_vector(double max_radius);

  SoccerSimConfig config_;
  SoccerState state_;
  std::array<Vec2, SoccerState::kMaxPlayers> player_accel_{};
  Vec2 ball_accel_;
  Rng rng_;
  bool first_episode_ = true;
  double start_scale_ = 1.0;  // set_training_updates
  GoalieCommandLog last_goalie_command_;
  GoalieCommandLog pending_goalie_command_;
  bool goalie_sensed_ = false;
  std::array<GoalieCommandLog, kMaxFieldDefenders> last_defender_command_{};
  std::array<GoalieCommandLog, kMaxFieldDefenders> pending_defender_command_{};
};

}  // namespace pamdp::hfo
