// The C++ half of the Python module `pamdp` (python/pamdp/ is the other half): a single env, a
// vector env and a trained policy, each writing into NumPy arrays. Caller errors (a wrong type,
// shape or value) raise TypeError or ValueError with what was expected; nothing a caller passes
// may reach an env's misuse checks, which stop the process.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "actor/exploration.hpp"
#include "app/env_factory.hpp"
#include "app/experiment_config.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/hfo/hfo_team_env.hpp"
#include "envs/hfo/settings.hpp"
#include "learner/checkpoint.hpp"
#include "learner/ddpg.hpp"
#include "learner/greedy_policy.hpp"
#include "python/env_registry.hpp"
#include "python/field_text.hpp"
#include "python/vector_env.hpp"

namespace py = pybind11;

namespace pamdp::python {
namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using Options = std::vector<std::pair<std::string, std::string>>;

std::string type_name(py::handle h) {
  return py::str(py::type::handle_of(h).attr("__name__"));
}

// info["outcome"]: the env's name for a status, with one word for an episode that goes on
// (status 0) in every env: HFO's "IN_GAME" (the toy envs' C++ name is "IN_PROGRESS").
std::string outcome_name(const Env& env, int status) {
  return status == 0 ? std::string("IN_GAME") : std::string(env.status_name(status));
}

// What every binding needs to know about an env's statuses and actions, read once.
struct EnvFacts {
  explicit EnvFacts(const Env& env) : space(env.action_space()), obs_size(env.observation_size()) {
    int top = 0;
    for (int s : env.outcomes()) {
      top = std::max(top, s);
    }
    status_names.resize(static_cast<size_t>(top) + 1);
    for (int s : env.outcomes()) {
      status_names[static_cast<size_t>(s)] = py::str(outcome_name(env, s));
      if (env.status_name(s) == "OUT_OF_TIME") {
        timeout_status = s;
      }
    }
    std::string list;
    for (int a = 0; a < space.num_actions(); ++a) {
      list += (a == 0 ? "" : ", ") + std::to_string(a) + " " + space.actions[static_cast<size_t>(a)].name;
    }
    action_list = list;
  }

  // `env` is the env's index in a batch, -1 for a single action (messages are built only on failure).
  [[nodiscard]] int check_id(long long id, int env = -1) const {
    if (id < 0 || id >= space.num_actions()) {
      throw py::value_error((env < 0 ? std::string("action") : "actions[0][" + std::to_string(env) + "] =") + " " +
                            std::to_string(id) + " is not an action id (valid: " + action_list + ")");
    }
    return static_cast<int>(id);
  }
  void check_finite(int id, const float* shared, int env = -1) const {
    for (int i : space.actions[static_cast<size_t>(id)].param_indices) {
      if (!std::isfinite(shared[i])) {
        throw py::value_error((env < 0 ? std::string("action") : "actions of env " + std::to_string(env)) +
                              ": parameter " + space.params[static_cast<size_t>(i)].name + " of " +
                              space.actions[static_cast<size_t>(id)].name + " is " + std::to_string(shared[i]) +
                              "; parameters must be finite");
      }
    }
  }
  [[nodiscard]] std::string params_help() const {
    return "a tuple of " + std::to_string(space.num_actions()) +
           " parameter arrays, one per discrete action, or one flat float array of all " +
           std::to_string(space.num_params()) + " parameters";
  }

  ActionSpace space;
  int obs_size;
  std::vector<py::str> status_names;
  int timeout_status = -1;
  std::string action_list;
};

// `h` as a C-ordered float32 array (converting lists and other real dtypes), or a null array when
// it cannot be one. Complex values are refused rather than silently cut to their real part.
FloatArray float_array(py::handle h) {
  if (py::isinstance<py::array>(h) && py::reinterpret_borrow<py::array>(h).dtype().kind() == 'c') {
    throw py::type_error("action parameters must be real numbers, got dtype " +
                         std::string(py::str(py::reinterpret_borrow<py::array>(h).dtype())));
  }
  return FloatArray::ensure(h);
}

long long read_integer(py::handle h, const std::string& what) {
  if (PyBool_Check(h.ptr()) || PyIndex_Check(h.ptr()) == 0) {
    throw py::type_error(what + " must be an int, got " + type_name(h));
  }
  const auto index = py::reinterpret_steal<py::object>(PyNumber_Index(h.ptr()));
  if (!index) {
    throw py::error_already_set();
  }
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (overflow != 0) {
    throw py::value_error(what + " is out of range");
  }
  return v;
}

uint64_t read_seed(py::handle h) {
  const long long v = read_integer(h, "seed");
  if (v < 0) {
    throw py::value_error("seed must be >= 0, got " + std::to_string(v));
  }
  return static_cast<uint64_t>(v);
}

void check_reset_options(py::handle options) {
  if (options.is_none()) {
    return;
  }
  if (!py::isinstance<py::dict>(options)) {
    throw py::type_error("reset options must be a dict or None, got " + type_name(options));
  }
  const auto d = py::reinterpret_borrow<py::dict>(options);
  if (!d.empty()) {
    throw py::value_error("reset options: these envs take none (got '" + std::string(py::str(d.begin()->first)) +
                          "'); env settings are make()'s keyword arguments");
  }
}

// Reads one action, (id, params), into `shared` (the env's whole parameter vector). Returns the id.
int read_action(py::handle action, const EnvFacts& f, std::vector<float>& shared) {
  if (!py::isinstance<py::tuple>(action) && !py::isinstance<py::list>(action)) {
    throw py::type_error("action must be a tuple (id, params), params being " + f.params_help() + "; got " +
                         type_name(action));
  }
  const auto seq = py::reinterpret_borrow<py::sequence>(action);
  if (seq.size() != 2) {
    throw py::value_error("action must be a pair (id, params), got " + std::to_string(seq.size()) + " items");
  }
  const int id = f.check_id(read_integer(seq[0], "action[0], the discrete action id,"));
  const py::object params = seq[1];
  const std::vector<int>& owned = f.space.actions[static_cast<size_t>(id)].param_indices;
  if (py::isinstance<py::array>(params)) {
    const auto a = float_array(params);
    if (!a || a.ndim() != 1 || a.size() != f.space.num_params()) {
      throw py::value_error("action[1] as one array must hold all " + std::to_string(f.space.num_params()) +
                            " parameters (shape (" + std::to_string(f.space.num_params()) + ",))");
    }
    std::memcpy(shared.data(), a.data(), shared.size() * sizeof(float));
  } else if ((py::isinstance<py::tuple>(params) || py::isinstance<py::list>(params)) &&
             py::len(params) == static_cast<size_t>(f.space.num_actions())) {
    const auto mine = float_array(py::reinterpret_borrow<py::sequence>(params)[static_cast<size_t>(id)]);
    if (!mine || mine.size() != static_cast<py::ssize_t>(owned.size()) || mine.ndim() > 1) {
      throw py::value_error("action[1][" + std::to_string(id) + "], the parameters of " +
                            f.space.actions[static_cast<size_t>(id)].name + ", must be a float array of shape (" +
                            std::to_string(owned.size()) + ",)");
    }
    for (size_t k = 0; k < owned.size(); ++k) {
      shared[static_cast<size_t>(owned[k])] = mine.data()[k];
    }
  } else {
    throw py::type_error("action[1] must be " + f.params_help() + "; got " + type_name(params) +
                         (py::isinstance<py::sequence>(params) ? " of length " + std::to_string(py::len(params)) : ""));
  }
  f.check_finite(id, shared.data());
  return id;
}

// A batch of actions, (ids of shape (N,), params), into ids and an N x num_params matrix.
void read_actions(py::handle action, const EnvFacts& f, int n, std::vector<int>& ids, std::vector<float>& shared) {
  if (!py::isinstance<py::tuple>(action) && !py::isinstance<py::list>(action)) {
    throw py::type_error("actions must be a tuple (ids, params): ids an int array of shape (" + std::to_string(n) +
                         ",), params " + f.params_help() + " with a leading dimension of " + std::to_string(n) +
                         "; got " + type_name(action));
  }
  const auto seq = py::reinterpret_borrow<py::sequence>(action);
  if (seq.size() != 2) {
    throw py::value_error("actions must be a pair (ids, params), got " + std::to_string(seq.size()) + " items");
  }
  const py::array raw_ids = py::array::ensure(seq[0]);
  if (!raw_ids || (raw_ids.dtype().kind() != 'i' && raw_ids.dtype().kind() != 'u')) {
    throw py::type_error("actions[0], the discrete action ids, must be an int array, got " +
                         (raw_ids ? "dtype " + std::string(py::str(raw_ids.dtype())) : type_name(seq[0])));
  }
  const auto id_array = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(raw_ids);
  if (id_array.ndim() != 1 || id_array.shape(0) != n) {
    throw py::value_error("actions[0] must have shape (" + std::to_string(n) + ",) for " + std::to_string(n) + " envs");
  }
  const auto np = static_cast<size_t>(f.space.num_params());
  for (int i = 0; i < n; ++i) {
    ids[static_cast<size_t>(i)] = f.check_id(id_array.data()[i], i);
  }
  const py::object params = seq[1];
  if (py::isinstance<py::array>(params)) {
    const auto a = float_array(params);
    if (!a || a.ndim() != 2 || a.shape(0) != n || a.shape(1) != f.space.num_params()) {
      throw py::value_error("actions[1] as one array must have shape (" + std::to_string(n) + ", " +
                            std::to_string(np) + ")");
    }
    std::memcpy(shared.data(), a.data(), shared.size() * sizeof(float));
  } else if ((py::isinstance<py::tuple>(params) || py::isinstance<py::list>(params)) &&
             py::len(params) == static_cast<size_t>(f.space.num_actions())) {
    const auto per_action = py::reinterpret_borrow<py::sequence>(params);
    std::vector<FloatArray> arrays;
    arrays.reserve(static_cast<size_t>(f.space.num_actions()));
    for (int a = 0; a < f.space.num_actions(); ++a) {
      const size_t k = f.space.actions[static_cast<size_t>(a)].param_indices.size();
      auto arr = float_array(per_action[static_cast<size_t>(a)]);
      if (!arr || arr.ndim() != 2 || arr.shape(0) != n || arr.shape(1) != static_cast<py::ssize_t>(k)) {
        throw py::value_error("actions[1][" + std::to_string(a) + "], the parameters of " +
                              f.space.actions[static_cast<size_t>(a)].name + ", must be a float array of shape (" +
                              std::to_string(n) + ", " + std::to_string(k) + ")");
      }
      arrays.push_back(std::move(arr));
    }
    for (int i = 0; i < n; ++i) {
      const int id = ids[static_cast<size_t>(i)];
      const std::vector<int>& owned = f.space.actions[static_cast<size_t>(id)].param_indices;
      const float* src = arrays[static_cast<size_t>(id)].data() + static_cast<size_t>(i) * owned.size();
      float* row = shared.data() + static_cast<size_t>(i) * np;
      for (size_t k = 0; k < owned.size(); ++k) {
        row[owned[k]] = src[k];
      }
    }
  } else {
    throw py::type_error("actions[1] must be " + f.params_help() + " (each with a leading dimension of " +
                         std::to_string(n) + "); got " + type_name(params));
  }
  for (int i = 0; i < n; ++i) {
    f.check_finite(ids[static_cast<size_t>(i)], shared.data() + static_cast<size_t>(i) * np, i);
  }
}

// The action space as plain data, for python/pamdp/spaces.py: per discrete action its name and
// its parameters as (name, lo, hi).
py::list describe_actions(const ActionSpace& space) {
  py::list out;
  for (const DiscreteActionSpec& a : space.actions) {
    py::list params;
    for (int i : a.param_indices) {
      const ParamSpec& p = space.params[static_cast<size_t>(i)];
      params.append(py::make_tuple(p.name, p.lo, p.hi));
    }
    out.append(py::make_tuple(a.name, params));
  }
  return out;
}

py::list describe_outcomes(const Env& env) {
  py::list out;
  for (int s : env.outcomes()) {
    out.append(py::make_tuple(s, outcome_name(env, s)));
  }
  return out;
}

class PyEnv {
 public:
  PyEnv(const std::string& id, const Options& options) : PyEnv(resolve_env(id, options)) {}
  explicit PyEnv(const app::EnvConfig& config)
      : config_(config),
        env_(build_env(config_)),
        facts_(*env_),
        shared_(static_cast<size_t>(facts_.space.num_params()), 0.0F) {}

  py::tuple reset(py::handle seed, py::handle options) {
    check_reset_options(options);
    py::array_t<float> obs(facts_.obs_size);
    const std::span<float> out(obs.mutable_data(), static_cast<size_t>(facts_.obs_size));
    if (seed.is_none()) {
      env_->reset(out);
    } else {
      const uint64_t s = read_seed(seed);
      if (fresh_env_per_seed(config_)) {
        env_ = build_env(config_);  // the seed alone decides the episode
      }
      env_->reset(s, out);
    }
    needs_reset_ = false;
    steps_ = 0;
    last_status_ = 0;
    return py::make_tuple(std::move(obs), info(0));
  }

  py::tuple step(py::handle action) {
    if (needs_reset_) {
      throw std::logic_error(std::string(env_->name()) +
                             ": step() before reset() or after the episode ended; call reset() first");
    }
    const int id = read_action(action, facts_, shared_);
    if (!warned_out_of_bounds_) {
      warn_out_of_bounds(id);
    }
    py::array_t<float> obs(facts_.obs_size);
    const StepResult r =
        env_->step({id, shared_}, std::span<float>(obs.mutable_data(), static_cast<size_t>(facts_.obs_size)));
    const bool timeout = r.status == facts_.timeout_status;
    needs_reset_ = r.terminal();
    ++steps_;
    last_status_ = r.status;
    return py::make_tuple(std::move(obs), static_cast<double>(r.reward), r.terminal() && !timeout, timeout,
                          info(r.status));
  }

  [[nodiscard]] const Env& env() const { return *env_; }
  [[nodiscard]] const app::EnvConfig& config() const { return config_; }
  // render("ansi"): the field as text (python/field_text.hpp).
  [[nodiscard]] std::string render_text() { return field_text(*env_, last_status_, steps_); }

 private:
  // The rule for a parameter outside action_space's bounds is the env's own, the real HFO's:
  // it is clamped to the range the env accepts (HFO: powers to the server's range, directions
  // to [-180, 180]), never refused. Said once per env, as a Python warning.
  void warn_out_of_bounds(int id) {
    for (int i : facts_.space.actions[static_cast<size_t>(id)].param_indices) {
      const ParamSpec& p = facts_.space.params[static_cast<size_t>(i)];
      const float v = shared_[static_cast<size_t>(i)];
      if (v >= p.lo && v <= p.hi) {
        continue;
      }
      warned_out_of_bounds_ = true;
      const auto num = [](float x) {
        char text[32];
        std::snprintf(text, sizeof(text), "%g", static_cast<double>(x));
        return std::string(text);
      };
      const std::string text =
          std::string(env_->name()) + ": " + facts_.space.actions[static_cast<size_t>(id)].name + " parameter " +
          p.name + " = " + num(v) + " is outside action_space's bounds [" + num(p.lo) + ", " + num(p.hi) +
          "]; the env clamps out-of-range parameters to the range it accepts, as the real HFO does (wrap the env in "
          "gymnasium.wrappers.ClipAction to clip to these bounds instead). Warned once per env.";
      if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 1) != 0) {
        throw py::error_already_set();  // warnings turned into errors (python -W error)
      }
      return;
    }
  }

  [[nodiscard]] py::dict info(int status) const {
    py::dict d;
    d["outcome"] = facts_.status_names[static_cast<size_t>(status)];
    d["status"] = status;
    return d;
  }

  app::EnvConfig config_;
  std::unique_ptr<Env> env_;
  EnvFacts facts_;
  std::vector<float> shared_;
  bool needs_reset_ = true;
  bool warned_out_of_bounds_ = false;
  int steps_ = 0;
  int last_status_ = 0;
};

// What every team (make_team, make_team_vec) checks: `config` (of id `id`) is the embedded HFO
// simulator, and `agents` within the players it holds.
void check_team(const app::EnvConfig& config, const std::string& id, int agents) {
  if (config.name != "hfo") {
    throw py::value_error("a team plays the embedded HFO simulator: give an hfo id (hfo-1v0, hfo-1v1, hfo), got '" +
                          id + "'");
  }
  if (agents < 1 || agents > hfo::kMaxOffenseAgents) {
    throw py::value_error("agents must be within [1, " + std::to_string(hfo::kMaxOffenseAgents) + "], got " +
                          std::to_string(agents));
  }
}

// N offense agents in one embedded HFO game (envs/hfo/hfo_team_env.hpp), for python/pamdp's
// ParallelEnv: one observation, action and reward per agent, in player order.
class PyTeamEnv {
 public:
  PyTeamEnv(const std::string& id, int agents, const Options& options) : config_(resolve_env(id, options)) {
    check_team(config_, id, agents);
    hfo::SoccerSimConfig c = hfo::sim_config(config_.params);
    c.offense_agents = agents;
    env_ = std::make_unique<hfo::HfoTeamEnv>(c, config_.params.boolean("shoot_action"),
                                             static_cast<int>(config_.params.integer("out_of_bounds_penalty")),
                                             config_.params.boolean("team_reward"));
    width_ = static_cast<size_t>(env_->observation_size());
    obs_.resize(width_ * static_cast<size_t>(agents));
    rewards_.resize(static_cast<size_t>(agents));
    actions_.resize(static_cast<size_t>(agents));
    shared_.assign(static_cast<size_t>(agents),
                   std::vector<float>(static_cast<size_t>(facts_.space.num_params()), 0.0F));
  }

  py::list reset(py::handle seed) {
    if (seed.is_none()) {
      env_->reset(obs_);
    } else {
      env_->reset(read_seed(seed), obs_);
    }
    needs_reset_ = false;
    return observations();
  }

  // actions: a sequence of one action per agent, in player order (each as PyEnv.step takes
  // one). Returns (observations, rewards, status name, status code, terminated, truncated).
  py::tuple step(py::handle actions) {
    if (needs_reset_) {
      throw std::logic_error("team env: step() before reset() or after the episode ended; call reset() first");
    }
    if (!py::isinstance<py::sequence>(actions) || py::isinstance<py::str>(actions)) {
      throw py::type_error("actions must be a sequence of one action per agent, got " + type_name(actions));
    }
    const auto seq = py::reinterpret_borrow<py::sequence>(actions);
    if (seq.size() != static_cast<size_t>(env_->agents())) {
      throw py::value_error("actions: " + std::to_string(seq.size()) + " given, one per agent (" +
                            std::to_string(env_->agents()) + ") expected");
    }
    for (size_t i = 0; i < seq.size(); ++i) {
      const int id = read_action(seq[i], facts_, shared_[i]);
      actions_[i] = {id, shared_[i]};
    }
    const int status = env_->step(actions_, obs_, rewards_);
    needs_reset_ = status != hfo::kInGame;
    py::list rewards;
    for (float r : rewards_) {
      rewards.append(static_cast<double>(r));
    }
    const bool timeout = status == hfo::kOutOfTime;
    return py::make_tuple(observations(), rewards, outcome_name(single_, status), status, needs_reset_ && !timeout,
                          timeout);
  }

  [[nodiscard]] int agents() const { return env_->agents(); }
  [[nodiscard]] int observation_size() const { return env_->observation_size(); }
  [[nodiscard]] int max_episode_steps() const { return env_->max_episode_steps(); }
  [[nodiscard]] const app::EnvConfig& config() const { return config_; }
  [[nodiscard]] const ActionSpace& action_space() const { return env_->action_space(); }

 private:
  py::list observations() const {
    py::list out;
    for (int i = 0; i < env_->agents(); ++i) {
      py::array_t<float> o(static_cast<py::ssize_t>(width_));
      std::memcpy(o.mutable_data(), obs_.data() + static_cast<size_t>(i) * width_, width_ * sizeof(float));
      out.append(std::move(o));
    }
    return out;
  }

  app::EnvConfig config_;
  // Status names and action facts, as the one-agent env has them.
  hfo::HfoEnv single_{hfo::SoccerSimConfig{}, config_.params.boolean("shoot_action")};
  EnvFacts facts_{single_};
  std::unique_ptr<hfo::HfoTeamEnv> env_;
  size_t width_ = 0;
  std::vector<float> obs_;
  std::vector<float> rewards_;
  std::vector<ParamAction> actions_;
  std::vector<std::vector<float>> shared_;
  bool needs_reset_ = true;
};

class PyVectorEnv {
 public:
  // No agents: one player per env (make_vec). agents = A: a team vector env (make_team_vec), A
  // learned players in each embedded HFO game (check_team), every per-player array with an agent
  // axis (obs N x A x obs_size, reward N x A, actions N x A).
  PyVectorEnv(const std::string& id, const Options& options, int num_envs, int num_threads,
              const std::string& autoreset, bool copy, std::optional<int> agents = std::nullopt)
      : config_(resolve_env(id, with_agents(id, options, agents))), copy_(copy), team_(agents.has_value()) {
    if (num_envs < 1) {
      throw py::value_error("num_envs must be >= 1, got " + std::to_string(num_envs));
    }
    if (num_threads < 1) {
      throw py::value_error("num_threads must be >= 1, got " + std::to_string(num_threads));
    }
    AutoReset mode = AutoReset::kNextStep;
    if (autoreset == "same_step") {
      mode = AutoReset::kSameStep;
    } else if (autoreset != "next_step") {
      throw py::value_error("autoreset_mode must be one of: next_step, same_step; got '" + autoreset + "'");
    }
    std::vector<std::unique_ptr<Env>> envs;
    for (int i = 0; i < num_envs; ++i) {
      envs.push_back(build_env(config_, team_));
    }
    facts_.emplace(*envs[0]);
    const int obs = facts_->obs_size;
    std::function<std::unique_ptr<Env>()> rebuild;
    if (fresh_env_per_seed(config_)) {
      rebuild = [config = config_, team = team_] { return build_env(config, team); };
    }
    vec_ = std::make_unique<VectorEnv>(std::move(envs), num_threads, mode, facts_->timeout_status, rebuild);
    const py::ssize_t players = vec_->agents();
    const auto shape = [&](std::initializer_list<py::ssize_t> tail) {
      std::vector<py::ssize_t> s{num_envs};
      if (team_) {
        s.push_back(players);
      }
      s.insert(s.end(), tail.begin(), tail.end());
      return s;
    };
    obs_ = py::array_t<float>(shape({obs}));
    reward_ = py::array_t<float>(shape({}));
    terminated_ = py::array_t<bool>(num_envs);
    truncated_ = py::array_t<bool>(num_envs);
    status_ = py::array_t<int32_t>(num_envs);
    same_step_ = mode == AutoReset::kSameStep;
    if (same_step_) {
      final_obs_ = py::array_t<float>(shape({obs}));
      has_final_ = py::array_t<bool>(num_envs);
      std::fill_n(final_obs_.mutable_data(), final_obs_.size(), 0.0F);
    }
    const auto rows = static_cast<size_t>(num_envs) * static_cast<size_t>(players);
    ids_.resize(rows);
    shared_.resize(rows * static_cast<size_t>(facts_->space.num_params()), 0.0F);
  }

  py::tuple reset(py::handle seed, py::handle options) {
    check_reset_options(options);
    const auto n = static_cast<size_t>(vec_->num_envs());
    std::vector<uint64_t> seeds;
    if (py::isinstance<py::list>(seed) || py::isinstance<py::tuple>(seed) || py::isinstance<py::array>(seed)) {
      const auto seq = py::reinterpret_borrow<py::sequence>(seed);
      if (seq.size() != n) {
        throw py::value_error("seed as a sequence needs one seed per env (" + std::to_string(n) + "), got " +
                              std::to_string(seq.size()));
      }
      for (size_t i = 0; i < n; ++i) {
        seeds.push_back(read_seed(seq[i]));
      }
    } else if (!seed.is_none() || !seeded_) {
      // Env i takes seed + i (Gymnasium's rule); never seeded, env i takes i.
      const uint64_t base = seed.is_none() ? 0 : read_seed(seed);
      for (size_t i = 0; i < n; ++i) {
        seeds.push_back(base + i);
      }
    }
    seeded_ = true;
    vec_->reset(seeds, buffers());
    was_reset_ = true;
    return py::make_tuple(out(obs_), info());
  }

  py::tuple step(py::handle action) {
    if (!was_reset_) {
      throw std::logic_error("vector env: step() before reset(); call reset() first");
    }
    // A team's actions arrive flattened to N x A rows (python/pamdp's TeamVectorEnv reshapes them).
    read_actions(action, *facts_, vec_->num_envs() * vec_->agents(), ids_, shared_);
    {
      const py::gil_scoped_release unlocked;
      vec_->step(ids_, shared_, buffers());
    }
    return py::make_tuple(out(obs_), out(reward_), out(terminated_), out(truncated_), info());
  }

  [[nodiscard]] const VectorEnv& vec() const { return *vec_; }
  [[nodiscard]] const app::EnvConfig& config() const { return config_; }

 private:
  VectorBuffers buffers() {
    const auto n = static_cast<size_t>(vec_->num_envs());
    const auto players = n * static_cast<size_t>(vec_->agents());
    const size_t rows = players * static_cast<size_t>(facts_->obs_size);
    VectorBuffers b{{obs_.mutable_data(), rows},
                    {reward_.mutable_data(), players},
                    {reinterpret_cast<uint8_t*>(terminated_.mutable_data()), n},
                    {reinterpret_cast<uint8_t*>(truncated_.mutable_data()), n},
                    {status_.mutable_data(), n},
                    {},
                    {}};
    if (same_step_) {
      b.final_obs = {final_obs_.mutable_data(), rows};
      b.has_final = {reinterpret_cast<uint8_t*>(has_final_.mutable_data()), n};
    }
    return b;
  }
  [[nodiscard]] py::object out(const py::array& a) const {
    return copy_ ? py::array(a.dtype(), std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()), a.data())
                 : py::object(a);
  }
  [[nodiscard]] py::dict info() const {
    py::dict d;
    d["status"] = out(status_);
    if (same_step_) {
      d["final_obs"] = out(final_obs_);
      d["_final_obs"] = out(has_final_);
    }
    return d;
  }

  // The options with offense_agents = agents for a team, after check_team.
  static Options with_agents(const std::string& id, const Options& options, std::optional<int> agents) {
    if (!agents) {
      return options;
    }
    Options out;
    for (const auto& [key, value] : options) {
      if (key == "offense_agents") {
        throw py::value_error("make_team_vec takes the team's size as agents=..., not as offense_agents");
      }
      out.emplace_back(key, value);
    }
    check_team(resolve_env(id, out), id, *agents);
    out.emplace_back("offense_agents", std::to_string(*agents));
    return out;
  }

  app::EnvConfig config_;
  bool copy_;
  bool team_ = false;
  std::optional<EnvFacts> facts_;
  std::unique_ptr<VectorEnv> vec_;
  py::array_t<float> obs_;
  py::array_t<float> reward_;
  py::array_t<bool> terminated_;
  py::array_t<bool> truncated_;
  py::array_t<int32_t> status_;
  bool same_step_ = false;
  py::array_t<float> final_obs_;  // same_step only (a default py::array_t is an empty array, not null)
  py::array_t<bool> has_final_;
  std::vector<int> ids_;
  std::vector<float> shared_;
  bool seeded_ = false;
  bool was_reset_ = false;
};

// A checkpoint's actor as a batch policy: the greedy action `pamdp eval` plays (the actor copy
// its run evaluated, masked actions never chosen, parameters unclipped as the actor outputs
// them; the env clamps), or with exploration the checkpoint's ε-greedy selection.
class PyPolicy {
 public:
  PyPolicy(const std::string& path, bool explore, std::optional<double> epsilon, uint64_t seed,
           const std::string& actor)
      : config_(load_config(path)),
        env_(build_env(config_.env)),
        facts_(*env_),
        learner_(app::make_learner(config_, env_->observation_size(), env_->action_space(), config_.seed,
                                   UpdateDevice::kCpu)),
        explore_(explore) {
    load_checkpoint(path, *learner_);
    if (actor == "evaluated") {
      copy_ = learner_->evaluated_copy();
    } else if (actor == "online") {
      copy_ = ActorCopy::kOnline;
    } else if (actor == "target") {
      copy_ = ActorCopy::kTarget;
    } else if (actor == "average") {
      if (learner_->evaluated_copy() != ActorCopy::kAverage) {
        throw py::value_error("actor='average': " + path + " keeps no actor average (ddpg.actor_average_tau = 0)");
      }
      copy_ = ActorCopy::kAverage;
    } else {
      throw py::value_error("actor must be one of: evaluated, online, target, average; got '" + actor + "'");
    }
    const ExplorationConfig exploration = app::resolve_exploration(config_, env_->action_space());
    epsilon_ = epsilon.value_or(linear_epsilon(learner_->updates(), exploration.epsilon_start, exploration.epsilon_end,
                                               exploration.epsilon_anneal_updates));
    if (!(epsilon_ >= 0.0 && epsilon_ <= 1.0)) {
      throw py::value_error("epsilon must be within [0, 1], got " + std::to_string(epsilon_));
    }
    select_.emplace(env_->action_space(), exploration, seed);
    output_.resize(static_cast<size_t>(learner_->output_width()));
    stored_.resize(output_.size());
  }

  py::tuple call(py::handle observations) {
    const auto obs = FloatArray::ensure(observations);
    const int width = facts_.obs_size;
    if (!obs || (obs.ndim() != 1 && obs.ndim() != 2) || obs.shape(obs.ndim() - 1) != width) {
      std::string got = obs ? "shape (" : "a " + type_name(observations);
      for (py::ssize_t d = 0; obs && d < obs.ndim(); ++d) {
        got += (d ? ", " : "") + std::to_string(obs.shape(d));
      }
      got += obs ? (obs.ndim() == 1 ? ",)" : ")") : "";
      throw py::value_error("observations must be a float array of shape (" + std::to_string(width) + ",) or (B, " +
                            std::to_string(width) + ") for this policy's env '" + id_of(config_.env) + "', got " + got +
                            (obs && obs.ndim() > 0 && obs.shape(obs.ndim() - 1) != width
                                 ? " (an observation of another env? pamdp.evaluate(policy) plays the "
                                   "checkpoint's own env)"
                                 : ""));
    }
    const bool single = obs.ndim() == 1;
    const py::ssize_t batch = single ? 1 : obs.shape(0);
    const ActionSpace& space = facts_.space;
    const size_t na = static_cast<size_t>(space.num_actions());
    py::array_t<int64_t> ids(batch);
    std::vector<py::array_t<float>> params;
    for (const DiscreteActionSpec& a : space.actions) {
      params.emplace_back(std::vector<py::ssize_t>{batch, static_cast<py::ssize_t>(a.param_indices.size())});
    }
    for (py::ssize_t b = 0; b < batch; ++b) {
      const std::span<const float> row(obs.data() + b * width, static_cast<size_t>(width));
      learner_->act(row, output_, copy_);
      int id = 0;
      const float* chosen = output_.data() + na;
      if (explore_) {
        id = select_->select(row, output_, epsilon_, stored_);
        chosen = stored_.data() + na;
      } else {
        id = select_->greedy(row, output_);
      }
      ids.mutable_data()[b] = id;
      for (size_t a = 0; a < na; ++a) {
        const std::vector<int>& owned = space.actions[a].param_indices;
        float* dst = params[a].mutable_data() + static_cast<size_t>(b) * owned.size();
        for (size_t k = 0; k < owned.size(); ++k) {
          dst[k] = chosen[owned[k]];
        }
      }
    }
    py::tuple per_action(na);
    for (size_t a = 0; a < na; ++a) {
      per_action[a] = single ? params[a][py::int_(0)] : py::object(params[a]);
    }
    if (single) {
      return py::make_tuple(py::int_(ids.data()[0]), per_action);
    }
    return py::make_tuple(ids, per_action);
  }

  [[nodiscard]] const app::ExperimentConfig& config() const { return config_; }
  [[nodiscard]] const Algorithm& learner() const { return *learner_; }
  [[nodiscard]] double epsilon() const { return epsilon_; }
  [[nodiscard]] bool explores() const { return explore_; }
  [[nodiscard]] std::string actor() const {
    switch (copy_) {
      case ActorCopy::kOnline: return "online";
      case ActorCopy::kTarget: return "target";
      case ActorCopy::kAverage: return "average";
    }
    return "online";
  }

 private:
  static app::ExperimentConfig load_config(const std::string& path) {
    try {
      return app::parse_experiment_config(read_checkpoint_config(path), path + " (config)", {});
    } catch (const std::runtime_error& e) {
      throw py::value_error(e.what());
    }
  }

  app::ExperimentConfig config_;
  std::unique_ptr<Env> env_;  // the env the checkpoint was trained on: its sizes and action space
  EnvFacts facts_;
  std::unique_ptr<Algorithm> learner_;
  bool explore_;
  ActorCopy copy_ = ActorCopy::kOnline;
  double epsilon_ = 0.0;
  std::optional<EpsilonGreedy> select_;
  std::vector<float> output_;
  std::vector<float> stored_;
};

Options to_options(const py::dict& d) {
  Options out;
  for (const auto& [k, v] : d) {
    out.emplace_back(py::str(k), py::str(v));
  }
  return out;
}

}  // namespace
}  // namespace pamdp::python

PYBIND11_MODULE(_pamdp, m) {
  using namespace pamdp::python;
  m.doc() = "pamdp's C++ core; use the pamdp package, not this module";
  // pybind11 turns std::invalid_argument (config errors) into ValueError and other exceptions into
  // RuntimeError.
  m.def("env_ids", [] {
    py::list out;
    for (const EnvId& e : env_ids()) {
      out.append(py::make_tuple(e.id, e.description));
    }
    return out;
  });
  m.def("option_names", &option_names, py::arg("env_id"));
  m.def(
      "defaults_toml", [](const std::string& id) { return env_toml(resolve_env(id, {})); }, py::arg("env_id"));

  py::class_<PyEnv>(m, "Env", py::dynamic_attr())
      .def(py::init([](const std::string& id, const py::dict& options) {
             return std::make_unique<PyEnv>(id, to_options(options));
           }),
           py::arg("env_id"), py::arg("options"))
      .def("reset", &PyEnv::reset, py::arg("seed") = py::none(), py::arg("options") = py::none())
      .def("step", &PyEnv::step, py::arg("action"))
      .def("render_text", &PyEnv::render_text)
      .def_property_readonly("env_id", [](const PyEnv& e) { return id_of(e.config()); })
      .def_property_readonly("config_toml", [](const PyEnv& e) { return env_toml(e.config()); })
      .def_property_readonly("observation_size", [](const PyEnv& e) { return e.env().observation_size(); })
      .def_property_readonly("observation_bound", [](const PyEnv& e) { return observation_bound(e.config()); })
      .def_property_readonly("max_episode_steps", [](const PyEnv& e) { return e.env().max_episode_steps(); })
      .def_property_readonly("actions", [](const PyEnv& e) { return describe_actions(e.env().action_space()); })
      .def_property_readonly("outcomes", [](const PyEnv& e) { return describe_outcomes(e.env()); })
      .def_property_readonly("success_status", [](const PyEnv& e) { return e.env().success_status(); });

  py::class_<PyTeamEnv>(m, "TeamEnv", py::dynamic_attr())
      .def(py::init([](const std::string& id, int agents, const py::dict& options) {
             return std::make_unique<PyTeamEnv>(id, agents, to_options(options));
           }),
           py::arg("env_id"), py::arg("agents"), py::arg("options"))
      .def("reset", &PyTeamEnv::reset, py::arg("seed") = py::none())
      .def("step", &PyTeamEnv::step, py::arg("actions"))
      .def_property_readonly("env_id", [](const PyTeamEnv& e) { return id_of(e.config()); })
      .def_property_readonly("num_agents", &PyTeamEnv::agents)
      .def_property_readonly("observation_size", &PyTeamEnv::observation_size)
      .def_property_readonly("observation_bound", [](const PyTeamEnv& e) { return observation_bound(e.config()); })
      .def_property_readonly("max_episode_steps", &PyTeamEnv::max_episode_steps)
      .def_property_readonly("actions", [](const PyTeamEnv& e) { return describe_actions(e.action_space()); });

  py::class_<PyVectorEnv>(m, "VectorEnv", py::dynamic_attr())
      .def(py::init([](const std::string& id, const py::dict& options, int num_envs, int num_threads,
                       const std::string& autoreset, bool copy, std::optional<int> agents) {
             return std::make_unique<PyVectorEnv>(id, to_options(options), num_envs, num_threads, autoreset, copy,
                                                  agents);
           }),
           py::arg("env_id"), py::arg("options"), py::arg("num_envs"), py::arg("num_threads"),
           py::arg("autoreset_mode"), py::arg("copy"), py::arg("agents") = py::none())
      .def("reset", &PyVectorEnv::reset, py::arg("seed") = py::none(), py::arg("options") = py::none())
      .def("step", &PyVectorEnv::step, py::arg("actions"))
      .def_property_readonly("env_id", [](const PyVectorEnv& v) { return id_of(v.config()); })
      .def_property_readonly("config_toml", [](const PyVectorEnv& v) { return env_toml(v.config()); })
      .def_property_readonly("num_envs", [](const PyVectorEnv& v) { return v.vec().num_envs(); })
      .def_property_readonly("num_threads", [](const PyVectorEnv& v) { return v.vec().num_threads(); })
      .def_property_readonly("num_agents", [](const PyVectorEnv& v) { return v.vec().agents(); })
      .def_property_readonly("observation_size", [](const PyVectorEnv& v) { return v.vec().observation_size(); })
      .def_property_readonly("observation_bound", [](const PyVectorEnv& v) { return observation_bound(v.config()); })
      .def_property_readonly("max_episode_steps",
                             [](const PyVectorEnv& v) { return v.vec().env(0).max_episode_steps(); })
      .def_property_readonly("actions",
                             [](const PyVectorEnv& v) { return describe_actions(v.vec().env(0).action_space()); })
      .def_property_readonly("outcomes", [](const PyVectorEnv& v) { return describe_outcomes(v.vec().env(0)); })
      .def_property_readonly("success_status", [](const PyVectorEnv& v) { return v.vec().env(0).success_status(); });

  py::class_<PyPolicy>(m, "Policy", py::dynamic_attr())
      .def(py::init([](const std::string& path, bool explore, std::optional<double> epsilon, py::handle seed,
                       const std::string& actor) {
             return std::make_unique<PyPolicy>(path, explore, epsilon, read_seed(seed), actor);
           }),
           py::arg("path"), py::arg("exploration"), py::arg("epsilon"), py::arg("seed"), py::arg("actor"))
      .def("__call__", &PyPolicy::call, py::arg("observations"))
      .def_property_readonly("env_id", [](const PyPolicy& p) { return id_of(p.config().env); })
      .def_property_readonly("config_toml", [](const PyPolicy& p) { return pamdp::app::to_toml(p.config()); })
      .def_property_readonly("updates", [](const PyPolicy& p) { return p.learner().updates(); })
      .def_property_readonly("algorithm", [](const PyPolicy& p) { return std::string(p.learner().name()); })
      .def_property_readonly("epsilon", &PyPolicy::epsilon)
      .def_property_readonly("exploration", &PyPolicy::explores)
      .def_property_readonly("actor", &PyPolicy::actor)
      .def_property_readonly("observation_size", [](const PyPolicy& p) { return p.learner().obs_dim(); });
}
