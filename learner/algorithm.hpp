// The seam between a learning algorithm and everything around it: the run lifecycle
// (learner/training_run.hpp), the cluster's learner (learner/learner_server.hpp), checkpoints
// (learner/checkpoint.hpp), the weights message and evaluation go through Algorithm, never
// through one algorithm's class. DDPG with its three gradient bounds (learner/ddpg_algorithm.*)
// is one implementation; docs/architecture.md lists what another one adds.
//
// What every algorithm here shares, and so what the seam assumes:
// - the policy's output for one observation is one score per discrete action, then every
//   continuous parameter (output_width() values), which ε-greedy exploration, demonstrations and
//   replay store as they are (actor/exploration.hpp);
// - an update draws a minibatch of such transitions, and optionally one of demonstrations;
// - its state is a set of named float tensors and named counters (a checkpoint), and what the
//   actors need to act is a set of named networks (the weights message), which the actor side
//   plays through the acting policy registered under the same name (actor/acting_policy.hpp).
//
// Registration: every algorithm defines `void register_<name>_algorithm(AlgorithmRegistry&)`,
// called from algorithm_registry() in learner/algorithm.cpp (one line each), for the reasons
// envs/registry.hpp gives (static libraries drop unreferenced registrar objects).
//
// Threading: one thread at a time. update() allocates nothing.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/action_space.hpp"
#include "core/network_view.hpp"

namespace pamdp {

struct DdpgConfig;

// Where updates run: kAuto takes a CUDA device when one is present (learner/update_backend.hpp).
enum class UpdateDevice { kAuto, kCpu, kCuda };

// Which copy of the acting network plays: the one training moves, the targets' soft-updated
// copy, or the evaluation average (when the algorithm keeps one).
enum class ActorCopy { kOnline, kTarget, kAverage };

// A minibatch, one sample per column. Not owned.
struct BatchView {
  Eigen::Map<const Eigen::MatrixXf> states;       // obs x B
  Eigen::Map<const Eigen::MatrixXf> actions;      // output_width x B, as stored
  Eigen::Map<const Eigen::VectorXf> rewards;      // B
  Eigen::Map<const Eigen::MatrixXf> next_states;  // obs x B
  Eigen::Map<const Eigen::VectorXf> terminal;     // B, 1 if the episode ended at this transition
  Eigen::Map<const Eigen::VectorXf> mc_returns;   // B (read only by algorithms that mix them in)
};

// One update's statistics, as the metrics rows report them. An algorithm fills what it has.
struct UpdateStats {
  float critic_loss = 0.0F;  // the value loss: (1 / 2B) sum (Q - y)^2
  float q_mean = 0.0F;
  float target_mean = 0.0F;
  float critic_grad_norm = 0.0F;  // before clipping
  float actor_grad_norm = 0.0F;
  // Continuous parameters of the batch's policy outputs at or past a bound of their range (a
  // health check of the gradient bounding; W x B compares).
  float params_at_bound_fraction = 0.0F;
  // With demonstrations: the share of them the Q-filter let through, and their cloning loss.
  float bc_accepted_fraction = 0.0F;
  float bc_loss = 0.0F;
};

// One tensor of an algorithm's state, by name ("actor", "critic_adam.m"). `widths` is set for a
// network's parameters (Mlp's flat layout; warm starts widen its first layer) and empty
// otherwise. An optional tensor may be missing from a checkpoint: the algorithm is told which
// were (Algorithm::restored).
struct StateTensor {
  std::string name;
  std::span<float> values;
  std::vector<int> widths;
  bool optional = false;
};

// One counter of an algorithm's state ("updates", "actor_adam.steps").
struct StateCounter {
  std::string name;
  int64_t* value;
};

// What the actors play: the acting policy registered under `algorithm`, built from `networks`.
struct ActingWeights {
  std::string_view algorithm;
  uint8_t bound = 0;                  // DDPG's gradient bound (2: the actors squash the output); 0 for others
  std::vector<NetworkView> networks;  // into the algorithm's host copy
};

class Algorithm {
 public:
  virtual ~Algorithm() = default;
  Algorithm() = default;
  Algorithm(const Algorithm&) = delete;
  Algorithm& operator=(const Algorithm&) = delete;

  [[nodiscard]] virtual std::string_view name() const = 0;  // its registry name: "ddpg"
  [[nodiscard]] virtual int obs_dim() const = 0;
  [[nodiscard]] virtual int output_width() const = 0;  // scores, then parameters
  [[nodiscard]] virtual int batch_size() const = 0;
  [[nodiscard]] virtual int64_t updates() const = 0;
  [[nodiscard]] virtual const char* device() const = 0;  // where updates run: "cpu", "cuda"
  // Whether update() takes demonstrations to clone (the run then keeps a table of them).
  [[nodiscard]] virtual bool clones_demonstrations() const { return false; }

  // One update on a full batch (batch_size() samples), and the demonstrations to clone when
  // clones_demonstrations(). The batch is read or copied before this returns, so the caller may
  // reuse its buffers at once; updates() counts it when this returns. Returns the statistics of
  // the newest finished update (an asynchronous device may return the previous one's).
  virtual UpdateStats update(const BatchView& batch, const BatchView* demos = nullptr) = 0;
  // Waits for every queued update; returns the newest one's statistics.
  virtual UpdateStats finish() = 0;

  // Brings the acting networks' newest parameters to the host, where act() and
  // acting_weights() read them, and moves an evaluation average (every point that reads the
  // acting networks feeds it).
  virtual void sync_acting() = 0;
  // The policy's output for one observation, as the actors compute it, from the host copy.
  virtual void act(std::span<const float> obs, std::span<float> out, ActorCopy copy = ActorCopy::kOnline) = 0;
  // The copy evaluations (and so best.ckpt) judge: the average when one is kept.
  [[nodiscard]] virtual ActorCopy evaluated_copy() const { return ActorCopy::kOnline; }
  // One line for the run's log saying what evaluations play, or empty.
  [[nodiscard]] virtual std::string evaluated_copy_note() const { return {}; }
  // The networks the actors need, from the host copy (after sync_acting()).
  virtual ActingWeights acting_weights() = 0;

  // Brings the whole state to the host (before it is read for a checkpoint).
  virtual void sync_to_host() = 0;
  // The whole state, as a checkpoint holds it; the spans point into the algorithm.
  virtual std::vector<StateTensor> state_tensors() = 0;
  virtual std::vector<StateCounter> state_counters() = 0;
  // After a checkpoint was read into state_tensors() and state_counters(): `missing` names the
  // optional tensors it lacked. Device backends reload the host state here.
  virtual void restored(const std::vector<std::string>& missing) = 0;
  // After a warm start filled the networks (tensors with widths) from another run.
  virtual void warm_started() = 0;
};

// One setting an algorithm reads beyond the ddpg.* keys, declared at its registration as a full
// config key, "<section>.<name>" ("pdqn.q_tau"). Algorithms that share a section (pdqn and mpdqn)
// declare its keys alike; the config file accepts and writes every registered key whichever
// algorithm runs, so that a run directory's config reads back unchanged.
using AlgorithmValue = std::variant<bool, double>;

struct AlgorithmKey {
  std::string name;  // "pdqn.q_tau"
  AlgorithmValue default_value;
  double lo = 0.0;  // a real key's valid range, inclusive
  double hi = 0.0;
  std::string help;  // one line: what it does, for listings and the presets

  static AlgorithmKey real(std::string name, double default_value, double lo, double hi, std::string help);
  static AlgorithmKey boolean(std::string name, bool default_value, std::string help);
  [[nodiscard]] bool is_boolean() const { return std::holds_alternative<bool>(default_value); }
  bool operator==(const AlgorithmKey&) const = default;
};

// The values of the registered algorithms' keys, by full name. Reading a key that is absent or of
// the other type is misuse: std::logic_error naming it.
class AlgorithmParams {
 public:
  [[nodiscard]] double real(std::string_view key) const;
  [[nodiscard]] bool boolean(std::string_view key) const;
  void set(const std::string& key, AlgorithmValue value);
  [[nodiscard]] AlgorithmValue& at(std::string_view key);  // for the config reader: a key that exists
  [[nodiscard]] const std::map<std::string, AlgorithmValue, std::less<>>& values() const { return values_; }
  bool operator==(const AlgorithmParams&) const = default;

 private:
  std::map<std::string, AlgorithmValue, std::less<>> values_;
};

// What a factory gets. The ddpg.* keys are the settings every learner reads (network widths,
// optimizer, discount, batch, target rate); an algorithm with more declares its own keys at
// registration and reads them from `params`.
struct AlgorithmArgs {
  int obs_dim = 0;
  const ActionSpace* space = nullptr;
  const DdpgConfig* ddpg = nullptr;
  uint64_t seed = 0;
  // Where updates run; kCpu for a learner that only acts (pamdp eval, the Python bindings).
  UpdateDevice device = UpdateDevice::kAuto;
  // Actions never taken (exploration.masked_actions, resolved): a value-based learner leaves them
  // out of its max.
  std::vector<int> masked_actions;
  // Actions that act only where a feature is on (exploration.gated_actions, resolved): a
  // value-based learner leaves them out of its max, its taken action and its parameter loss in
  // the states where they are shut.
  std::vector<ActionGate> gates;
  // The registered algorithms' own keys; null: their defaults.
  const AlgorithmParams* params = nullptr;
  // The env's hand-made parameter policy, when it has one (envs/registry.hpp): what a learner
  // that starts its parameters from one (pdqn.passthrough) starts from.
  const ParameterPrior* prior = nullptr;
};

struct AlgorithmRegistration {
  std::string name;         // train.algorithm
  std::string description;  // one line, for listings
  std::function<std::unique_ptr<Algorithm>(const AlgorithmArgs&)> make;
  std::vector<AlgorithmKey> keys;  // the settings it reads beyond ddpg.*
};

class AlgorithmRegistry {
 public:
  // Throws std::logic_error when the name is taken, or a key is declared unlike an earlier
  // registration's key of the same name.
  void add(AlgorithmRegistration registration);
  // Null when no algorithm has this name.
  [[nodiscard]] const AlgorithmRegistration* find(std::string_view name) const;
  [[nodiscard]] const std::vector<AlgorithmRegistration>& all() const { return registrations_; }
  // The names, comma-separated, for error messages.
  [[nodiscard]] std::string names() const;
  // Every key any algorithm reads, each once, in registration order, and their defaults.
  [[nodiscard]] const std::vector<AlgorithmKey>& keys() const { return keys_; }
  [[nodiscard]] AlgorithmParams defaults() const;

 private:
  std::vector<AlgorithmRegistration> registrations_;
  std::vector<AlgorithmKey> keys_;
};

// Every algorithm this build offers (built on first use; thread-safe).
const AlgorithmRegistry& algorithm_registry();

// The algorithm registered as `name`; throws std::runtime_error naming the known ones when
// there is none.
std::unique_ptr<Algorithm> make_algorithm(std::string_view name, const AlgorithmArgs& args);

}  // namespace pamdp
