// The CUDA update backend (docs/gpu.md), seen from plain C++: no CUDA header is included here
// or by anything that includes this. In a build without CUDA (PAMDP_CUDA=OFF) these are
// defined by no_cuda.cpp: no device, and make_cuda_update_backend refuses.
#pragma once

#include <memory>
#include <string>

#include "learner/update_backend.hpp"

namespace pamdp {

// Builds the backend on device 0 from ddpg's current state (parameters, targets, Adam state);
// captures the update into CUDA graphs. Throws std::runtime_error on any CUDA or cuBLAS
// failure. Cost: tens of milliseconds (allocation, one warm-up update, two graph captures).
std::unique_ptr<UpdateBackend> make_cuda_update_backend(Ddpg& ddpg);

// Device 0's name and memory, for logs ("NVIDIA H100 80GB HBM3, 79 GiB").
std::string cuda_device_description();

// Seconds that `reps` float32 SGEMMs C = A * B ((m x k) * (k x n), no TF32) take on device 0,
// timed with CUDA events after one warm-up call: the roofline for bench's BM_DdpgUpdateCuda.
// Allocates and frees its matrices on each call. Throws without a device.
double time_device_sgemm(int m, int n, int k, int reps);

}  // namespace pamdp
