// DDPG's acting policy: the actor network "actor", plus the fixed pass-through layer
// "actor_passthrough" on its parameter outputs when the learner has one (ddpg.passthrough), the
// output squashed into the parameter bounds when the learner bounds by squashing (bound 2), as
// the learner's own act() does (core/actor_output.hpp).
#include <Eigen/Core>
#include <algorithm>
#include <memory>
#include <vector>

#include "actor/acting_policy.hpp"
#include "core/actor_output.hpp"
#include "core/bounds.hpp"
#include "core/mlp.hpp"

namespace pamdp {
namespace {

constexpr uint8_t kBoundSquashing = 2;  // BoundMethod::kSquashing (learner/gradient_bounds.hpp)
constexpr uint8_t kMaxBound = 2;

class DdpgActingPolicy final : public ActingPolicy {
 public:
  DdpgActingPolicy(int obs_dim, const ActionSpace& space)
      : obs_dim_(obs_dim),
        width_(space.output_width()),
        num_params_(space.num_params()),
        bounds_(OutputBounds::for_actor(space)),
        input_(obs_dim, 1) {}

  [[nodiscard]] const char* check(std::span<const NetworkView> networks, uint8_t bound) const override {
    if (networks.empty() || networks.size() > 2 || networks[0].name != "actor" ||
        (networks.size() == 2 && networks[1].name != "actor_passthrough")) {
      return "DDPG weights carry the network \"actor\", and optionally \"actor_passthrough\"";
    }
    if (networks.size() == 2) {
      const std::span<const int> t = networks[1].widths;
      if (t.size() != 2 || t.front() != obs_dim_ || t.back() != num_params_ || num_params_ < 1) {
        return "the DDPG pass-through layer's widths do not fit this env's observation and parameter widths";
      }
    }
    const std::span<const int> w = networks[0].widths;
    if (w.front() != obs_dim_ || w.back() != width_) {
      return "the actor's widths do not fit this env's observation and action widths";
    }
    return bound > kMaxBound ? "an unknown gradient bound" : nullptr;
  }

  void load(std::span<const NetworkView> networks, uint8_t bound) override {
    load_network(networks[0], net_, 1);
    if (networks.size() == 2) {
      load_network(networks[1], passthrough_, 1);
    } else {
      passthrough_.reset();
    }
    squash_ = bound == kBoundSquashing;
  }

  void act(std::span<const float> obs, std::span<float> out) override {
    actor_output(*net_, input_, obs, squash_ ? &bounds_ : nullptr, out, passthrough_.get());
  }

  [[nodiscard]] int64_t num_params() const override {
    return (net_ != nullptr ? net_->num_params() : 0) + (passthrough_ != nullptr ? passthrough_->num_params() : 0);
  }

 private:
  int obs_dim_;
  int width_;
  int num_params_;
  OutputBounds bounds_;
  Eigen::MatrixXf input_;
  std::unique_ptr<Mlp<float>> net_;
  std::unique_ptr<Mlp<float>> passthrough_;
  bool squash_ = false;
};

}  // namespace

void register_ddpg_acting_policy(ActingPolicyRegistry& registry) {
  registry.add({"ddpg", [](int obs_dim, const ActionSpace& space) {
                  return std::make_unique<DdpgActingPolicy>(obs_dim, space);
                }});
}

}  // namespace pamdp
