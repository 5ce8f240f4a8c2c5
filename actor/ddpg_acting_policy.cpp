// DDPG's acting policy: the actor network "actor", its output squashed into the parameter bounds
// when the learner bounds by squashing (bound 2), as the learner's own act() does
// (core/actor_output.hpp).
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
      : obs_dim_(obs_dim), width_(space.output_width()), bounds_(OutputBounds::for_actor(space)), input_(obs_dim, 1) {}

  [[nodiscard]] const char* check(std::span<const NetworkView> networks, uint8_t bound) const override {
    if (networks.size() != 1 || networks[0].name != "actor") {
      return "DDPG weights carry one network, \"actor\"";
    }
    const std::span<const int> w = networks[0].widths;
    if (w.front() != obs_dim_ || w.back() != width_) {
      return "the actor's widths do not fit this env's observation and action widths";
    }
    return bound > kMaxBound ? "an unknown gradient bound" : nullptr;
  }

  void load(std::span<const NetworkView> networks, uint8_t bound) override {
    const NetworkView& n = networks[0];
    if (net_ == nullptr ||
        !std::equal(n.widths.begin(), n.widths.end(), net_->widths().begin(), net_->widths().end())) {
      // Only on the first weights (or a learner restarted with other hidden widths): not per step.
      net_ = std::make_unique<Mlp<float>>(std::vector<int>(n.widths.begin(), n.widths.end()), 1);
    }
    std::copy(n.params.begin(), n.params.end(), net_->params().begin());
    squash_ = bound == kBoundSquashing;
  }

  void act(std::span<const float> obs, std::span<float> out) override {
    actor_output(*net_, input_, obs, squash_ ? &bounds_ : nullptr, out);
  }

  [[nodiscard]] int64_t num_params() const override { return net_ != nullptr ? net_->num_params() : 0; }

 private:
  int obs_dim_;
  int width_;
  OutputBounds bounds_;
  Eigen::MatrixXf input_;
  std::unique_ptr<Mlp<float>> net_;
  bool squash_ = false;
};

}  // namespace

void register_ddpg_acting_policy(ActingPolicyRegistry& registry) {
  registry.add({"ddpg", [](int obs_dim, const ActionSpace& space) {
                  return std::make_unique<DdpgActingPolicy>(obs_dim, space);
                }});
}

}  // namespace pamdp
