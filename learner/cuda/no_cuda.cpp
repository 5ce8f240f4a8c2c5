// A build without the CUDA backend (PAMDP_CUDA=OFF): no device, and "cuda" is refused.
#include <stdexcept>

#include "learner/cuda/cuda_update_backend.hpp"

namespace pamdp {

namespace {
constexpr const char* kNoCuda = "this build has no CUDA support: configure with -DPAMDP_CUDA=ON";
}

int cuda_device_count(std::string* why) {
  if (why != nullptr) {
    *why = kNoCuda;
  }
  return 0;
}

std::string cuda_device_description() {
  return "none";
}

std::unique_ptr<UpdateBackend> make_cuda_update_backend(Ddpg& /*ddpg*/) {
  throw std::runtime_error(kNoCuda);
}

double time_device_sgemm(int /*m*/, int /*n*/, int /*k*/, int /*reps*/) {
  throw std::runtime_error(kNoCuda);
}

}  // namespace pamdp
