// P-DQN's and MP-DQN's acting policy: the parameter network "param" and the Q-network "q", and
// the fixed pass-through layer "param_passthrough" when the learner has one (pdqn.passthrough),
// played through core/pdqn_output.hpp as the learner's own act() plays them; the parameters are
// squashed into their bounds when the learner bounds by squashing (bound 2).
#include <algorithm>
#include <memory>
#include <vector>

#include "actor/acting_policy.hpp"
#include "core/mlp.hpp"
#include "core/pdqn_output.hpp"

namespace pamdp {
namespace {

constexpr uint8_t kBoundSquashing = 2;  // BoundMethod::kSquashing (learner/gradient_bounds.hpp)
constexpr uint8_t kMaxBound = 2;

class PdqnActingPolicy final : public ActingPolicy {
 public:
  PdqnActingPolicy(int obs_dim, const ActionSpace& space, bool multipass)
      : obs_dim_(obs_dim),
        num_actions_(space.num_actions()),
        num_params_(space.num_params()),
        bounds_(parameter_bounds(space)),
        forward_(obs_dim, space, multipass) {}

  [[nodiscard]] const char* check(std::span<const NetworkView> networks, uint8_t bound) const override {
    if (networks.size() < 2 || networks.size() > 3 || networks[0].name != "param" || networks[1].name != "q" ||
        (networks.size() == 3 && networks[2].name != "param_passthrough")) {
      return "P-DQN weights carry the networks \"param\" and \"q\", and optionally \"param_passthrough\"";
    }
    if (networks.size() == 3) {
      const std::span<const int> t = networks[2].widths;
      if (t.size() != 2 || t.front() != obs_dim_ || t.back() != num_params_) {
        return "the P-DQN pass-through layer's widths do not fit this env's observation and parameter widths";
      }
    }
    const std::span<const int> p = networks[0].widths;
    const std::span<const int> q = networks[1].widths;
    if (p.front() != obs_dim_ || p.back() != num_params_ || q.front() != obs_dim_ + num_params_ ||
        q.back() != num_actions_) {
      return "the P-DQN networks' widths do not fit this env's observation and action widths";
    }
    return bound > kMaxBound ? "an unknown gradient bound" : nullptr;
  }

  void load(std::span<const NetworkView> networks, uint8_t bound) override {
    load_network(networks[0], param_, 1);
    load_network(networks[1], q_, forward_.passes());
    if (networks.size() == 3) {
      load_network(networks[2], passthrough_, 1);
    } else {
      passthrough_.reset();
    }
    squash_ = bound == kBoundSquashing;
  }

  void act(std::span<const float> obs, std::span<float> out) override {
    forward_(*param_, *q_, squash_ ? &bounds_ : nullptr, obs, out, passthrough_.get());
  }

  [[nodiscard]] int64_t num_params() const override {
    return (param_ ? param_->num_params() : 0) + (q_ ? q_->num_params() : 0) +
           (passthrough_ ? passthrough_->num_params() : 0);
  }

 private:
  int obs_dim_;
  int num_actions_;
  int num_params_;
  OutputBounds bounds_;
  PdqnForward forward_;
  std::unique_ptr<Mlp<float>> param_;
  std::unique_ptr<Mlp<float>> q_;
  std::unique_ptr<Mlp<float>> passthrough_;
  bool squash_ = false;
};

}  // namespace

void register_pdqn_acting_policies(ActingPolicyRegistry& registry) {
  for (const bool multipass : {false, true}) {
    registry.add({multipass ? "mpdqn" : "pdqn", [multipass](int obs_dim, const ActionSpace& space) {
                    return std::make_unique<PdqnActingPolicy>(obs_dim, space, multipass);
                  }});
  }
}

}  // namespace pamdp
