// The envs this build offers, each registered next to its own code as OpenSpiel's
// REGISTER_SPIEL_GAME and EnvPool's REGISTER do: its name, the env.* config keys it reads with
// their defaults and valid values, a factory, and the few facts about it that the commands ask.
// Nothing outside an env's folder names it.
//
// Registration: every env folder defines `void register_<folder>_env(EnvRegistry&)` and is listed
// in PAMDP_ENVS in envs/CMakeLists.txt; the build generates env_registry(), which calls them in
// that order. Chosen over static registrar objects for two reasons: a static library leaves out an
// object file that nothing references, registrar and all, so an env would silently go missing from
// some binaries; and listings (`pamdp --help`, errors) follow the build file's order, not the
// link order.
//
// Thread-safety: env_registry() is built on first use (thread-safe) and read-only after.
// An EnvRegistry being filled is not thread-safe.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "envs/env.hpp"

namespace pamdp {

// One setting's value: env.goalie = true, env.server_port = 6000, env.start = "paper". A choice
// is held as its name.
using EnvValue = std::variant<bool, int64_t, std::string>;

// An env's settings, by key without the "env." prefix. Reading a key that is absent, or holds
// another type, is misuse: std::logic_error naming the key.
class EnvParams {
 public:
  [[nodiscard]] bool boolean(std::string_view key) const;
  [[nodiscard]] int64_t integer(std::string_view key) const;
  [[nodiscard]] const std::string& text(std::string_view key) const;  // text and choice keys
  void set(const std::string& key, EnvValue value);  // adds or replaces; validated where the config is read
  [[nodiscard]] bool contains(std::string_view key) const { return values_.find(key) != values_.end(); }
  // For the config reader: the value of a key that exists.
  [[nodiscard]] EnvValue& at(std::string_view key);
  [[nodiscard]] const std::map<std::string, EnvValue, std::less<>>& values() const { return values_; }
  bool operator==(const EnvParams&) const = default;

 private:
  std::map<std::string, EnvValue, std::less<>> values_;
};

// One env.* config key an env reads, its default and its valid values.
struct EnvKey {
  enum class Type { kBoolean, kInteger, kText, kTextOrEmpty, kChoice };
  std::string name;  // without "env."
  Type type = Type::kBoolean;
  EnvValue default_value;
  int64_t lo = 0;                    // kInteger: the valid range, inclusive
  int64_t hi = 0;                    //
  std::vector<std::string> choices;  // kChoice: the valid names, in listing order

  static EnvKey boolean(std::string name, bool default_value);
  static EnvKey integer(std::string name, int64_t default_value, int64_t lo, int64_t hi);
  static EnvKey text(std::string name, std::string default_value);  // non-empty
  static EnvKey text_or_empty(std::string name, std::string default_value);
  static EnvKey choice(std::string name, std::string default_value, std::vector<std::string> choices);
  bool operator==(const EnvKey&) const = default;
};

struct EnvRegistration {
  std::string name;         // env.name
  std::string description;  // one line, for listings
  // The env.* keys it reads. A key two envs read ("goalie") must be declared alike by both.
  std::vector<EnvKey> keys;
  // A new env for `params`. Throws std::runtime_error when this build or machine cannot make it.
  std::function<std::unique_ptr<Env>(const EnvParams&)> make;
  // Its observation width, without making it (an hfo-server env needs no server, nor a build
  // with HFO, for this).
  std::function<int(const EnvParams&)> observation_size;

  // Optional facts for the commands; left empty where they do not apply.
  // Whether it gives the embedded HFO simulator's features, which the scripted offense reads.
  std::function<bool(const EnvParams&)> gives_embedded_hfo_features;
  // Switches `params` to the embedded HFO features and returns the setting it changed
  // ("env.server_encoding = embedded"), so a policy trained in-process plays it.
  std::function<std::string(EnvParams&)> use_embedded_hfo_features;
  // The settings of the env that greedy evaluations beside training play (`pamdp train`,
  // `pamdp learner`; `evaluating`: train.eval_episodes > 0). Throws std::runtime_error saying
  // what to set. Empty: the training env's.
  std::function<EnvParams(const EnvParams&, bool evaluating)> eval_params;
  // Where it plays, for start-up lines (" at localhost:6000"). Empty: in-process; an env that
  // plays elsewhere keeps a connection that making it anew would drop.
  std::function<std::string(const EnvParams&)> location;
  // A hand-made policy for its parameters in these settings (core/action_space.hpp), which a
  // learner may start from (pdqn.passthrough), or nullopt.
  std::function<std::optional<ParameterPrior>(const EnvParams&)> parameter_prior;
  // Its action space is HFO's (DASH, TURN, KICK, TACKLE), which `pamdp eval`'s scripted and
  // random policies play.
  bool hfo_actions = false;
  // The actions that can act only where one of its features is on (> 0), by action name and
  // feature index: elsewhere they are no-ops. exploration.gated_actions names those a learner
  // should neither take nor value there (core/action_space.hpp, ActionGate).
  std::vector<std::pair<std::string, int>> action_gates;
  // A bound on every |observation value|.
  float observation_bound = 1.0F;
  // How many of it one process may play at once (`pamdp actor --envs`); 0 = any number.
  int max_per_process = 0;
  // Why, when max_per_process is set, and what to do instead.
  std::string max_per_process_note;
};

class EnvRegistry {
 public:
  // Throws std::logic_error for a name registered before, a registration without make or
  // observation_size, or a key declared differently by an env registered before.
  void add(EnvRegistration registration);

  // Throws std::runtime_error "env.name 'x' is unknown (valid: a, b, c)".
  [[nodiscard]] const EnvRegistration& find(std::string_view name) const;
  [[nodiscard]] const EnvRegistration* find_if(std::string_view name) const;
  [[nodiscard]] const std::vector<EnvRegistration>& all() const { return envs_; }
  [[nodiscard]] std::vector<std::string> names() const;  // in registration order
  [[nodiscard]] std::string names_joined() const;        // "a, b, c"
  // Every key any env reads, each once, in registration order. The config file accepts and
  // writes all of them whatever env.name is, so that run directories read back unchanged.
  [[nodiscard]] const std::vector<EnvKey>& keys() const { return keys_; }
  // Every key's default.
  [[nodiscard]] EnvParams defaults() const;
  // Whether env `name` reads `key`.
  [[nodiscard]] bool reads(std::string_view name, std::string_view key) const;

 private:
  std::vector<EnvRegistration> envs_;
  std::vector<EnvKey> keys_;
};

// The envs of this build (PAMDP_ENVS in envs/CMakeLists.txt). Defined in the generated
// builtin_envs.cpp of the pamdp_env_registry library, which a caller links.
const EnvRegistry& env_registry();

}  // namespace pamdp
