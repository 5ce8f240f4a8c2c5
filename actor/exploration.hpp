// Acting in a parameterized action space (paper §4.1, reference §7.3).
//
// Greedy: the discrete action is the arg-max of the scores over the allowed actions (Tackle is
// masked by default in HFO, as in the paper's code); its parameters are read from the output
// vector unclipped (the env clamps and wraps them).
// ε-greedy: with probability ε the whole output vector is replaced by a random one (scores
// U[-1, 1], each parameter uniform in its exploration range), and the stored transition
// carries that random vector. With uniform_random_params off, only the scores are drawn: the
// random action keeps the policy's own parameters (MP-DQN's runs, which explore the parameters
// with Ornstein-Uhlenbeck noise of σ 0.0001 instead: cycraig/MP-DQN agents/pdqn.py act()).
// Parameter noise (param_noise > 0, not in the paper): on the other, greedy steps each
// parameter gets Gaussian noise of std param_noise * (hi - lo) / 2 of its action-space bounds,
// clamped to them; the discrete choice stays greedy and the stored vector carries the noise.
// select() allocates nothing; not thread-safe (one per actor thread).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/action_space.hpp"
#include "core/rng.hpp"

namespace pamdp {

struct ExplorationConfig {
  double epsilon_start = 1.0;
  double epsilon_end = 0.1;
  int64_t epsilon_anneal_updates = 10000;  // paper: 10,000 updates
  std::vector<int> masked_actions;         // never executed (HFO: Tackle)
  // Taken only where their feature is on (exploration.gated_actions, resolved against the env).
  std::vector<ActionGate> gates;
  // Sampling range of each parameter for random actions; empty = the action space's bounds.
  std::vector<float> random_param_lo;
  std::vector<float> random_param_hi;
  // Whether a random step draws its parameters (true, the paper's) or keeps the policy's.
  bool uniform_random_params = true;
  // Gaussian noise on the parameters of greedy steps, as a fraction of each parameter's half
  // range (0: none, the paper's pure ε-greedy).
  double param_noise = 0.0;
  // Demonstrations (pamdp train, HFO only): the share of episodes the scripted offense plays
  // instead of the actor, falling linearly to demo_fraction_end over demo_anneal_updates learner
  // updates and staying there (anneal 0: demo_fraction throughout). Their transitions go to
  // replay like any other; the stored action is the scripted one (score 1 for its action, -1 for
  // the others, its parameters; the parameters of the other actions are the actor's own output).
  double demo_fraction = 0.0;
  int64_t demo_anneal_updates = 0;
  double demo_fraction_end = 0.0;  // the share kept after the anneal (0: the teacher stops)
  // With cloning (ddpg.demo_bc_weight > 0): the agent's own steps also go into the cloning
  // memory, each labelled with the scripted offense's action for the same state (DAgger), so the
  // agent is taught in the states it reaches, not only in those its teacher does.
  bool demo_relabel = false;
};

// The demonstration share after `updates` learner updates (see ExplorationConfig).
double demo_share(int64_t updates, double fraction, int64_t anneal, double end);

// A teacher's action as the actor's output vector carries it (a demonstration's stored action, or
// a teacher's label): score 1 for its action and -1 for the others, its parameters, and `fill`
// (the actor's own output) for the other actions' parameters. Returns the action id.
int write_teacher_output(const ActionSpace& space, const ParamAction& a, std::span<const float> fill,
                         std::span<float> out);

// Linear from start to end over `anneal` learner updates, then constant.
double linear_epsilon(int64_t updates, double start, double end, int64_t anneal);
// Ape-X per-actor fixed epsilon: eps_i = base^(1 + alpha * i / (N - 1)) (eps = base for N = 1).
double apex_epsilon(int actor_index, int num_actors, double base = 0.4, double alpha = 7.0);

class EpsilonGreedy {
 public:
  EpsilonGreedy(const ActionSpace& space, const ExplorationConfig& config, uint64_t seed);

  // Picks the action for this step. `net_output` is the actor's output vector (scores then
  // params); `stored` receives the vector to store in replay (net_output or the random draw).
  // Returns the chosen discrete action id; its parameters are `stored` minus the scores.
  // With gates (ExplorationConfig::gates), the obs overload must be used: a gated action is
  // neither a random nor a greedy choice where its gate is shut in `obs`.
  int select(std::span<const float> net_output, double epsilon, std::span<float> stored);
  int select(std::span<const float> obs, std::span<const float> net_output, double epsilon, std::span<float> stored);
  // Whether select() at this ε may read net_output: below ε = 1, or when its random steps keep
  // the network's parameters (exploration.uniform_random_params off).
  [[nodiscard]] bool uses_output(double epsilon) const { return epsilon < 1.0 || !uniform_random_params_; }

  // Arg-max of the scores over unmasked actions (and, given obs, over those whose gate is open).
  [[nodiscard]] int greedy(std::span<const float> output) const;
  [[nodiscard]] int greedy(std::span<const float> obs, std::span<const float> output) const;
  // Offset of the parameters inside an output vector.
  [[nodiscard]] int num_actions() const { return num_actions_; }

  Rng& rng() { return rng_; }

 private:
  int num_actions_;
  std::vector<bool> masked_;
  std::vector<ActionGate> gates_;
  std::vector<float> lo_;
  std::vector<float> hi_;
  std::vector<float> bound_lo_;  // the action space's bounds (parameter noise is clamped to them)
  std::vector<float> bound_hi_;
  std::vector<float> noise_std_;  // empty: no parameter noise
  bool uniform_random_params_ = true;
  Rng rng_;
};

}  // namespace pamdp
