#include "learner/ddpg_algorithm.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace pamdp {
namespace {

constexpr const char* kAverage = "actor_average";
constexpr const char* kPassthrough = "actor_passthrough";

}  // namespace

DdpgAlgorithm::DdpgAlgorithm(int obs_dim, const ActionSpace& space, const DdpgConfig& config, uint64_t seed,
                             UpdateDevice device, const ParameterPrior* prior)
    : ddpg_(obs_dim, space, config, seed, prior), backend_(make_update_backend(ddpg_, device)) {}

UpdateStats DdpgAlgorithm::update(const BatchView& batch, const BatchView* demos) {
  return demos != nullptr ? backend_->update(batch, *demos) : backend_->update(batch);
}

ActorCopy DdpgAlgorithm::evaluated_copy() const {
  return ddpg_.averages_actor() ? ActorCopy::kAverage : ActorCopy::kOnline;
}

std::string DdpgAlgorithm::evaluated_copy_note() const {
  if (!ddpg_.averages_actor()) {
    return {};
  }
  std::ostringstream s;
  s << "evaluations and best.ckpt play the actor average (ddpg.actor_average_tau = " << ddpg_.config().actor_average_tau
    << ")";
  return s.str();
}

ActingWeights DdpgAlgorithm::acting_weights() {
  const Mlp<float>& actor = ddpg_.actor();
  ActingWeights w{name(), static_cast<uint8_t>(ddpg_.config().bound), {{"actor", actor.widths(), actor.params()}}};
  if (ddpg_.config().passthrough) {
    w.networks.push_back({kPassthrough, ddpg_.passthrough().widths(), ddpg_.passthrough().params()});
  }
  return w;
}

std::vector<StateTensor> DdpgAlgorithm::state_tensors() {
  std::vector<StateTensor> t;
  const auto net = [&](const char* n, Mlp<float>& m) { t.push_back({n, m.params(), m.widths(), false}); };
  const auto adam = [&](const std::string& n, Adam<float>& a) {
    t.push_back({n + ".m", a.first_moment(), {}, false});
    t.push_back({n + ".v", a.second_moment(), {}, false});
  };
  net("actor", ddpg_.actor());
  net("critic", ddpg_.critic());
  net("target_actor", ddpg_.target_actor());
  net("target_critic", ddpg_.target_critic());
  adam("actor_adam", ddpg_.actor_optimizer());
  adam("critic_adam", ddpg_.critic_optimizer());
  if (ddpg_.config().passthrough) {
    t.push_back({kPassthrough, ddpg_.passthrough().params(), {}, false});
  }
  if (ddpg_.averages_actor()) {
    t.push_back({kAverage, ddpg_.actor_average().params(), ddpg_.actor_average().widths(), true});
  }
  return t;
}

std::vector<StateCounter> DdpgAlgorithm::state_counters() {
  counters_ = {ddpg_.updates(), ddpg_.actor_optimizer().steps(), ddpg_.critic_optimizer().steps(),
               ddpg_.actor_average_updates()};
  std::vector<StateCounter> c = {
      {"updates", &counters_[0]}, {"actor_adam.steps", &counters_[1]}, {"critic_adam.steps", &counters_[2]}};
  if (ddpg_.averages_actor()) {
    c.push_back({"actor_average_updates", &counters_[3]});
  }
  return c;
}

void DdpgAlgorithm::restored(const std::vector<std::string>& missing) {
  ddpg_.set_updates(counters_[0]);
  ddpg_.actor_optimizer().set_steps(counters_[1]);
  ddpg_.critic_optimizer().set_steps(counters_[2]);
  if (std::find(missing.begin(), missing.end(), kAverage) != missing.end()) {
    ddpg_.reset_actor_average();  // written without one (ddpg.actor_average_tau was 0, or an older build)
  } else {
    ddpg_.set_actor_average_updates(counters_[3]);
  }
  backend_->load_from_host();
}

void DdpgAlgorithm::warm_started() {
  ddpg_.reset_actor_average();  // this run's average starts at the weights it starts from
  backend_->load_from_host();
}

void register_ddpg_algorithm(AlgorithmRegistry& registry) {
  registry.add({"ddpg",
                "DDPG with inverting, zeroing or squashing gradient bounds (Hausknecht & Stone 2016)",
                [](const AlgorithmArgs& a) {
                  if (!a.gates.empty()) {
                    throw std::invalid_argument(
                        "exploration.gated_actions: DDPG's critic reads the action scores its actor stored, "
                        "and a gate would take an action they do not rank first; gate actions with "
                        "train.algorithm = \"pdqn\" or \"mpdqn\", or leave exploration.gated_actions empty");
                  }
                  return std::make_unique<DdpgAlgorithm>(a.obs_dim, *a.space, *a.ddpg, a.seed, a.device, a.prior);
                },
                {}});  // no keys beyond ddpg.*
}

}  // namespace pamdp
