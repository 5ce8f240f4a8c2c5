// DDPG for parameterized action spaces (learner/ddpg.hpp) behind the algorithm seam
// (learner/algorithm.hpp): the Ddpg and the update backend it runs on (host or CUDA,
// learner/update_backend.hpp). Registered as "ddpg".
//
// Its state, by name: the networks "actor", "critic", "target_actor", "target_critic"; the Adam
// moments "actor_adam.m", "actor_adam.v", "critic_adam.m", "critic_adam.v"; with an actor
// average, "actor_average" (optional: a checkpoint without one restarts it); with the
// pass-through layer (ddpg.passthrough), "actor_passthrough". Counters:
// "updates", "actor_adam.steps", "critic_adam.steps", "actor_average_updates". The actors get
// the network "actor", "actor_passthrough" with the layer, and the bound (they squash the output
// under the squashing bound).
#pragma once

#include <array>
#include <memory>

#include "learner/algorithm.hpp"
#include "learner/ddpg.hpp"
#include "learner/update_backend.hpp"

namespace pamdp {

class DdpgAlgorithm final : public Algorithm {
 public:
  DdpgAlgorithm(int obs_dim, const ActionSpace& space, const DdpgConfig& config, uint64_t seed, UpdateDevice device,
                const ParameterPrior* prior = nullptr);

  [[nodiscard]] std::string_view name() const override { return "ddpg"; }
  [[nodiscard]] int obs_dim() const override { return ddpg_.obs_dim(); }
  [[nodiscard]] int output_width() const override { return ddpg_.output_width(); }
  [[nodiscard]] int batch_size() const override { return ddpg_.config().batch_size; }
  [[nodiscard]] int64_t updates() const override { return ddpg_.updates(); }
  [[nodiscard]] const char* device() const override { return backend_->name(); }
  [[nodiscard]] bool clones_demonstrations() const override { return ddpg_.config().demo_bc_weight > 0.0; }

  UpdateStats update(const BatchView& batch, const BatchView* demos = nullptr) override;
  UpdateStats finish() override { return backend_->finish(); }

  void sync_acting() override { backend_->sync_actor_to_host(); }
  void act(std::span<const float> obs, std::span<float> out, ActorCopy copy = ActorCopy::kOnline) override {
    ddpg_.act(obs, out, copy);
  }
  [[nodiscard]] ActorCopy evaluated_copy() const override;
  [[nodiscard]] std::string evaluated_copy_note() const override;
  ActingWeights acting_weights() override;

  void sync_to_host() override { backend_->sync_to_host(); }
  std::vector<StateTensor> state_tensors() override;
  std::vector<StateCounter> state_counters() override;
  void restored(const std::vector<std::string>& missing) override;
  void warm_started() override;

  Ddpg& ddpg() { return ddpg_; }
  UpdateBackend& backend() { return *backend_; }

 private:
  Ddpg ddpg_;
  std::unique_ptr<UpdateBackend> backend_;
  // The counters as state_counters() hands them out: filled from ddpg_ there, applied back by
  // restored().
  std::array<int64_t, 4> counters_{};
};

void register_ddpg_algorithm(AlgorithmRegistry& registry);

}  // namespace pamdp
