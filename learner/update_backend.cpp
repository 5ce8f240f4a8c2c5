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
  if (ddpg.config().demo_bc_weight > 0.0) {
    // The CUDA update has no cloning term (learner/ddpg.hpp).
    if (device == UpdateDevice::kCuda) {
      throw std::runtime_error(
          "ddpg.device = \"cuda\" cannot clone demonstrations (ddpg.demo_bc_weight > 0 runs on the CPU only); use "
          "ddpg.device = \"cpu\" or \"auto\", or set ddpg.demo_bc_weight = 0");
    }
    log::info("learner: ddpg.device = auto: ddpg.demo_bc_weight > 0 runs on the CPU; updates run on the CPU");
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
