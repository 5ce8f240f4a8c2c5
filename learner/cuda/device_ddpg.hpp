// The DDPG update on a CUDA device, behind a plain C++ interface: this header includes no CUDA
// or Eigen header (device_ddpg.cu, built as the module libpamdp_cuda.so, holds every kernel and
// cuBLAS call), so the glue in cuda_update_backend.cpp and the rest of the project never see
// CUDA types and do not link CUDA.
//
// The device keeps both networks, both targets, both Adam states and every scratch buffer in
// Ddpg's flat layout (core/mlp.hpp: per layer W as out x in column-major, then b), so state
// moves between host and device as whole flat arrays. One update is a fixed sequence of cuBLAS
// SGEMMs and fused kernels, captured once into a CUDA graph per input slot (two slots: the copy
// of the next batch overlaps the running update). docs/gpu.md describes the scheme.
//
// Not thread-safe: one thread drives it (the learner's). Errors from CUDA or cuBLAS throw
// std::runtime_error naming the call; they are not expected once construction succeeded.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pamdp::cuda {

struct DeviceDdpgConfig {
  int obs_dim = 0;
  int width = 0;                   // actor outputs (scores + parameters)
  int batch = 0;                   // every update uses exactly this many samples
  std::vector<int> actor_widths;   // {obs_dim, hidden..., width}
  std::vector<int> critic_widths;  // {obs_dim + width, hidden..., 1}
  float leaky_slope = 0.01F;
  float gamma = 0.99F;
  float mc_mix = 0.0F;
  float bootstrap_clip = 0.0F;  // <= 0: Q'(s', mu'(s')) enters the target unclamped
  float tau = 1e-4F;            // as soft_update<float> casts it
  float one_minus_tau = 1.0F;   // float(1.0 - tau), likewise
  double clip_grad_norm = 0.0;  // <= 0: no clipping
  float adam_beta1 = 0.95F;
  float adam_beta2 = 0.999F;
  float adam_epsilon = 1e-8F;
  int bound = 0;              // 0 inverting, 1 zeroing, 2 squashing (learner/gradient_bounds.hpp)
  int num_actions = 0;        // outputs before the continuous parameters (for params_at_bound)
  std::vector<float> lo, hi;  // output bounds, width each
};

// Host arrays in Ddpg's layout: num_params floats each for the network they belong to.
struct HostState {
  float* actor = nullptr;
  float* critic = nullptr;
  float* target_actor = nullptr;
  float* target_critic = nullptr;
  float* actor_m = nullptr;
  float* actor_v = nullptr;
  float* critic_m = nullptr;
  float* critic_v = nullptr;
};

// One batch as BatchView holds it: column-major, one sample per column, contiguous.
struct HostBatch {
  const float* states = nullptr;       // obs x B
  const float* actions = nullptr;      // width x B
  const float* rewards = nullptr;      // B
  const float* next_states = nullptr;  // obs x B
  const float* terminal = nullptr;     // B
  const float* mc_returns = nullptr;   // B
};

struct DeviceStats {
  float critic_loss = 0.0F;
  float q_mean = 0.0F;
  float target_mean = 0.0F;
  float critic_grad_norm = 0.0F;
  float actor_grad_norm = 0.0F;
  float params_at_bound = 0.0F;  // count of continuous outputs at or past a bound (exact below 2^24)
};

// Implemented in libpamdp_cuda.so (device_ddpg.cu); the host side holds it through this
// interface only, so that only a process that asks for the GPU loads CUDA and cuBLAS (loading
// cuBLAS costs ~0.3 s and ~200 MB per process: actors, shards and `pamdp sim` must not pay it).
class DeviceDdpg {
 public:
  virtual ~DeviceDdpg() = default;

  [[nodiscard]] virtual int64_t actor_params() const = 0;
  [[nodiscard]] virtual int64_t critic_params() const = 0;

  // Wait for queued updates, then copy all state in or out (synchronous; ~40 MB each way at
  // the paper's widths).
  virtual void upload(const HostState& state) = 0;
  virtual void download(const HostState& state) = 0;
  // Waits for queued updates, then copies the online actor's parameters out.
  virtual void download_actor(float* actor) = 0;

  // Copies the batch into a pinned buffer, queues its transfer and the update's graph with
  // the two Adam step sizes of this update, and returns the statistics of the previous update
  // (zeros if none). `has_previous` tells whether there was one.
  virtual DeviceStats enqueue(const HostBatch& batch, float actor_step_size, float critic_step_size,
                              bool* has_previous) = 0;
  // Waits for every queued update; returns the newest one's statistics (zeros if none).
  virtual DeviceStats finish() = 0;
};

// The module's entry points, exported as one table named `pamdp_cuda_api`.
constexpr int kCudaApiVersion = 1;
struct CudaApi {
  int version;
  // Usable devices; on 0, `why` (if given) gets the reason.
  int (*device_count)(std::string* why);
  std::string (*device_description)();
  // Seconds that `reps` SGEMMs take (see time_device_sgemm in cuda_update_backend.hpp).
  double (*time_sgemm)(int m, int n, int k, int reps);
  // Allocates everything on device 0, runs one warm-up update on zeros (so that cuBLAS and the
  // kernels are loaded before capture) and captures the two graphs. The parameters are
  // undefined until upload(). Throws std::runtime_error on CUDA or cuBLAS errors.
  std::unique_ptr<DeviceDdpg> (*create)(const DeviceDdpgConfig& config);
};

// Loads libpamdp_cuda.so once (from the running executable's directory, else through the
// dynamic loader's search path) and returns its table, or nullptr with the reason in *why.
// Thread-safe; the module stays loaded for the life of the process.
const CudaApi* cuda_api(std::string* why);

}  // namespace pamdp::cuda
