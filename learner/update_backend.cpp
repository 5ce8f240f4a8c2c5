#include "learner/update_backend.hpp"

#include <stdexcept>
#include <string>

#include "core/log.hpp"
#include "learner/cuda/cuda_update_backend.hpp"

namespace pamdp {

const char* update_device_name(UpdateDevice device) {
  switch (device) {
    case UpdateDevice::kAuto: return "auto";
    case UpdateDevice::kCpu: return "cpu";
    case UpdateDevice::kCuda: return "cuda";
  }
  return "?";
}

UpdateStats UpdateBackend::update(const BatchView& /*batch*/, const BatchView& /*demos*/) {
  throw std::logic_error(std::string("the ") + name() +
                         " update backend does not clone demonstrations (ddpg.demo_bc_weight > 0 runs on the CPU)");
}

std::unique_ptr<UpdateBackend> make_update_backend(Ddpg& ddpg, UpdateDevice device) {
  if (device == UpdateDevice::kCpu) {
    return std::make_unique<CpuUpdateBackend>(ddpg);
  }
  // Settings the CUDA update does not have (learner/ddpg.hpp): the cloning term, the pass-through
  // layer and a reward scale.
  const DdpgConfig& c = ddpg.config();
  const char* cpu_only = c.demo_bc_weight > 0.0  ? "ddpg.demo_bc_weight > 0"
                         : c.passthrough         ? "ddpg.passthrough = true"
                         : c.reward_scale != 1.0 ? "ddpg.reward_scale != 1"
                                                 : nullptr;
  if (cpu_only != nullptr) {
    if (device == UpdateDevice::kCuda) {
      throw std::runtime_error(std::string("ddpg.device = \"cuda\": ") + cpu_only +
                               " runs on the CPU only; use ddpg.device = \"cpu\" or \"auto\", or leave that setting "
                               "at its default");
    }
    log::info("learner: ddpg.device = auto: {} runs on the CPU; updates run on the CPU", cpu_only);
    return std::make_unique<CpuUpdateBackend>(ddpg);
  }
  std::string why;
  const bool have_device = cuda_device_count(&why) > 0;
  if (device == UpdateDevice::kCuda) {
    if (!have_device) {
      throw std::runtime_error("ddpg.device = \"cuda\" but no CUDA device is usable (" + why +
                               "); use ddpg.device = \"cpu\" or \"auto\"");
    }
    try {
      return make_cuda_update_backend(ddpg);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(std::string("ddpg.device = \"cuda\" but the CUDA learner could not start (") + e.what() +
                               "); use ddpg.device = \"cpu\" or \"auto\"");
    }
  }
  if (have_device) {
    try {
      std::unique_ptr<UpdateBackend> cuda = make_cuda_update_backend(ddpg);
      log::info("learner: ddpg.device = auto: updates run on the GPU ({})", cuda_device_description());
      return cuda;
    } catch (const std::exception& e) {
      // A device that is listed but unusable (busy, exclusive, out of memory) falls back too.
      why = e.what();
    }
  }
  log::info("learner: ddpg.device = auto: no usable CUDA device ({}); updates run on the CPU", why);
  return std::make_unique<CpuUpdateBackend>(ddpg);
}

}  // namespace pamdp
