// Every CUDA kernel and cuBLAS call of the learner (see device_ddpg.hpp, docs/gpu.md).
//
// Layout. Matrices are column-major with one sample per column, as in core/mlp.hpp, which is
// also cuBLAS's convention, so no transposition of storage is ever needed. A layer's W (out x in)
// and b (out) are adjacent in the flat parameter vector, so together they are one
// out x (in + 1) column-major matrix [W | b]. Every layer input therefore carries one extra row
// of ones ((in + 1) x B, leading dimension in + 1): the forward GEMM [W | b] * [a; 1] adds the
// bias, and the backward GEMM dz * [a; 1]^T writes [dW | db] in one call. The ones rows are
// written once at construction and no kernel touches them again.
//
// The leaky ReLU's derivative is taken from the activation, not the pre-activation: for
// slopes in [0, 1], act > 0 exactly when z > 0, so the forward pass keeps one buffer per layer.
//
// Reductions (gradient norms, the critic loss) use fixed grids and fixed-order trees, so a run
// on one device model is bit-for-bit repeatable; they differ from the CPU's order, which is
// why the CPU/GPU comparison (tests/cuda_learner_test.cpp) uses tolerances.
#include <cublas_v2.h>
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "learner/cuda/device_ddpg.hpp"

namespace pamdp::cuda {
namespace {

constexpr int kThreads = 256;
constexpr int kNormBlocks = 256;  // == kThreads: the Adam kernel reduces the partials with one thread each
static_assert(kNormBlocks == kThreads);
constexpr int kMaxAdamBlocks = 1024;
constexpr size_t kCublasWorkspaceBytes = size_t{32} << 20;
constexpr int kAlign = 32;  // floats: sections of the input slot start on 128-byte boundaries

// Slots of the per-update scalars at the start of the input slot.
constexpr int kActorStep = 0;
constexpr int kCriticStep = 1;
constexpr int kScalars = kAlign;

// Indices into the device statistics array (DeviceStats order).
constexpr int kStatLoss = 0;
constexpr int kStatQ = 1;
constexpr int kStatTarget = 2;
constexpr int kStatCriticNorm = 3;
constexpr int kStatActorNorm = 4;
constexpr int kStatAtBound = 5;
constexpr int kStats = 6;

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) {
    throw std::runtime_error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
  }
}

void check(cublasStatus_t s, const char* what) {
  if (s != CUBLAS_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cuBLAS: ") + what + ": " + cublasGetStatusString(s));
  }
}

// Kernel launches report configuration errors through cudaGetLastError.
void check_launch(const char* what) {
  check(cudaGetLastError(), what);
}

int blocks_for(int64_t n) {
  return static_cast<int>((n + kThreads - 1) / kThreads);
}
int64_t round_up(int64_t n) {
  return (n + kAlign - 1) / kAlign * kAlign;
}

template <typename T>
class DeviceArray {
 public:
  DeviceArray() = default;
  explicit DeviceArray(int64_t n) : n_(n) {
    check(cudaMalloc(reinterpret_cast<void**>(&p_), static_cast<size_t>(n) * sizeof(T)), "cudaMalloc");
  }
  ~DeviceArray() {
    if (p_ != nullptr) {
      cudaFree(p_);
    }
  }
  DeviceArray(DeviceArray&& o) noexcept : p_(std::exchange(o.p_, nullptr)), n_(o.n_) {}
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    return *this;
  }
  T* get() const { return p_; }
  [[nodiscard]] int64_t size() const { return n_; }
  [[nodiscard]] size_t bytes() const { return static_cast<size_t>(n_) * sizeof(T); }

 private:
  T* p_ = nullptr;
  int64_t n_ = 0;
};

template <typename T>
class PinnedArray {
 public:
  PinnedArray() = default;
  explicit PinnedArray(int64_t n) : n_(n) {
    check(cudaMallocHost(reinterpret_cast<void**>(&p_), static_cast<size_t>(n) * sizeof(T)), "cudaMallocHost");
    std::memset(static_cast<void*>(p_), 0, static_cast<size_t>(n) * sizeof(T));
  }
  ~PinnedArray() {
    if (p_ != nullptr) {
      cudaFreeHost(p_);
    }
  }
  PinnedArray(PinnedArray&& o) noexcept : p_(std::exchange(o.p_, nullptr)), n_(o.n_) {}
  PinnedArray& operator=(PinnedArray&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    return *this;
  }
  T* get() const { return p_; }
  [[nodiscard]] size_t bytes() const { return static_cast<size_t>(n_) * sizeof(T); }

 private:
  T* p_ = nullptr;
  int64_t n_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Kernels

__global__ void fill_kernel(float* __restrict__ x, int64_t n, float value) {
  for (int64_t i = blockIdx.x * int64_t{blockDim.x} + threadIdx.x; i < n; i += int64_t{gridDim.x} * blockDim.x) {
    x[i] = value;
  }
}

// Spreads the transferred batch into the network inputs (whose ones rows are already set):
// states into the actor input, the critic's batch input and the critic's policy input;
// next states into the target actor's and target critic's inputs; stored actions into the
// critic's batch input.
__global__ void prepare_batch_kernel(const float* __restrict__ states, const float* __restrict__ actions,
                                     const float* __restrict__ next_states, int obs, int width, int batch,
                                     float* __restrict__ actor_in, float* __restrict__ actor_in_next,
                                     float* __restrict__ critic_in_batch, float* __restrict__ critic_in_next,
                                     float* __restrict__ critic_in_pi) {
  const int rows = obs + width;
  const int64_t n = int64_t{rows} * batch;
  const int64_t i = blockIdx.x * int64_t{blockDim.x} + threadIdx.x;
  if (i >= n) {
    return;
  }
  const int r = static_cast<int>(i % rows);
  const int64_t j = i / rows;
  const int64_t ca = j * (obs + 1);
  const int64_t cc = j * (rows + 1);
  if (r < obs) {
    const float s = states[j * obs + r];
    const float s2 = next_states[j * obs + r];
    actor_in[ca + r] = s;
    actor_in_next[ca + r] = s2;
    critic_in_batch[cc + r] = s;
    critic_in_next[cc + r] = s2;
    critic_in_pi[cc + r] = s;
  } else {
    critic_in_batch[cc + r] = actions[j * width + (r - obs)];
  }
}

// z <- max(z, slope z) on the first `rows` rows of a (rows + 1) x batch activation.
__global__ void leaky_relu_kernel(float* __restrict__ z, int rows, int ld, int batch, float slope) {
  const int64_t n = int64_t{rows} * batch;
  const int64_t i = blockIdx.x * int64_t{blockDim.x} + threadIdx.x;
  if (i >= n) {
    return;
  }
  float& v = z[(i / rows) * ld + i % rows];
  v = fmaxf(v, slope * v);
}

// d (rows x batch) *= derivative of the leaky ReLU whose output is act (ld act_ld).
__global__ void leaky_relu_grad_kernel(float* __restrict__ d, const float* __restrict__ act, int rows, int act_ld,
                                       int batch, float slope) {
  const int64_t n = int64_t{rows} * batch;
  const int64_t i = blockIdx.x * int64_t{blockDim.x} + threadIdx.x;
  if (i >= n) {
    return;
  }
  d[i] *= act[(i / rows) * act_ld + i % rows] > 0.0F ? 1.0F : slope;
}

// The actor's raw outputs (width x batch) into the action rows of a critic input (ld dst_ld),
// squashed into the bounds when the method is squashing (core/bounds.hpp squash()).
__global__ void actions_to_critic_kernel(const float* __restrict__ raw, float* __restrict__ dst, int width, int dst_ld,
                                         int batch, bool squashing, const float* __restrict__ lo,
                                         const float* __restrict__ hi) {
  const int64_t n = int64_t{width} * batch;
  const int64_t i = blockIdx.x * int64_t{blockDim.x} + threadIdx.x;
  if (i >= n) {
    return;
  }
  const int r = static_cast<int>(i % width);
  const float u = raw[i];
  dst[(i / width) * dst_ld + r] = squashing ? lo[r] + (hi[r] - lo[r]) * 0.5F * (tanhf(u) + 1.0F) : u;
}

// Block-wide sum of one double per thread (blockDim.x == kThreads); the result in thread 0.
__device__ double block_sum(double x, double* shared) {
  shared[threadIdx.x] = x;
  __syncthreads();
  for (int s = kThreads / 2; s > 0; s >>= 1) {
    if (threadIdx.x < s) {
      shared[threadIdx.x] += shared[threadIdx.x + s];
    }
    __syncthreads();
  }
  const double total = shared[0];
  __syncthreads();
  return total;
}

// One block: the TD targets (optionally Monte-Carlo mixed), dLoss/dQ for the critic step and
// the loss, mean Q and mean target (Ddpg::update steps 1 and 2).
__global__ void critic_loss_kernel(const float* __restrict__ q_next, const float* __restrict__ q,
                                   const float* __restrict__ rewards, const float* __restrict__ terminal,
                                   const float* __restrict__ mc_returns, int batch, float gamma, float beta, float clip,
                                   float* __restrict__ d_q, float* __restrict__ stats) {
  __shared__ double shared[kThreads];
  double loss = 0.0;
  double q_sum = 0.0;
  double y_sum = 0.0;
  for (int j = threadIdx.x; j < batch; j += kThreads) {
    const float next = clip > 0.0F ? fminf(fmaxf(q_next[j], -clip), clip) : q_next[j];
    float y = rewards[j] + (terminal[j] > 0.5F ? 0.0F : gamma * next);
    if (beta > 0.0F) {
      y = beta * mc_returns[j] + (1.0F - beta) * y;
    }
    const float diff = q[j] - y;
    d_q[j] = diff / static_cast<float>(batch);
    loss += 0.5 * static_cast<double>(diff) * diff;
    q_sum += q[j];
    y_sum += y;
  }
  loss = block_sum(loss, shared);
  q_sum = block_sum(q_sum, shared);
  y_sum = block_sum(y_sum, shared);
  if (threadIdx.x == 0) {
    stats[kStatAtBound] = 0.0F;  // counted later in this update by gradient_bounds_kernel
    stats[kStatLoss] = static_cast<float>(loss / batch);
    stats[kStatQ] = static_cast<float>(q_sum / batch);
    stats[kStatTarget] = static_cast<float>(y_sum / batch);
  }
}

// learner/gradient_bounds.cpp on the device: grad (width x batch) rewritten in place; p is the
// output the critic saw (ld p_ld), raw the actor's pre-squash output. Also counts the
// continuous outputs (rows >= num_actions) at or past a bound into *at_bound (float adds of 1
// are exact, so the count does not depend on their order).
__global__ void gradient_bounds_kernel(float* __restrict__ grad, const float* __restrict__ p, int p_ld,
                                       const float* __restrict__ raw, int width, int batch, int method,
                                       const float* __restrict__ lo, const float* __restrict__ hi, int num_actions,
                                       float* __restrict__ at_bound) {
  const int64_t n = int64_t{width} * batch;
  const int64_t i = blockIdx.x * int64_t{blockDim.x} + threadIdx.x;
  if (i >= n) {
    return;
  }
  const int r = static_cast<int>(i % width);
  const float l = lo[r];
  const float h = hi[r];
  const float pv = p[(i / width) * p_ld + r];
  if (r >= num_actions && (pv <= l || pv >= h)) {
    atomicAdd(at_bound, 1.0F);
  }
  float g = grad[i];
  if (method == 0) {  // inverting
    g *= g < 0.0F ? (h - pv) / (h - l) : (pv - l) / (h - l);
  } else if (method == 1) {  // zeroing
    if ((g < 0.0F && pv >= h) || (g > 0.0F && pv <= l)) {
      g = 0.0F;
    }
  } else {  // squashing
    const float t = tanhf(raw[i]);
    g *= 0.5F * (h - l) * (1.0F - t * t);
  }
  grad[i] = g;
}

// Per-block partial sums of squares (in double) over a fixed grid of kNormBlocks blocks.
__global__ void norm_partials_kernel(const float* __restrict__ x, int64_t n, double* __restrict__ partials) {
  __shared__ double shared[kThreads];
  double acc = 0.0;
  for (int64_t i = blockIdx.x * int64_t{kThreads} + threadIdx.x; i < n; i += int64_t{kNormBlocks} * kThreads) {
    const double v = x[i];
    acc += v * v;
  }
  acc = block_sum(acc, shared);
  if (threadIdx.x == 0) {
    partials[blockIdx.x] = acc;
  }
}

// Global-norm clipping, Caffe Adam and the soft target update in one pass (core/optim.cpp):
// every block first reduces the norm partials itself (a fixed tree: the same value in every
// block), so no extra launch is needed to broadcast the clipping scale.
__global__ void adam_kernel(float* __restrict__ params, const float* __restrict__ grads, float* __restrict__ m,
                            float* __restrict__ v, float* __restrict__ target, int64_t n,
                            const double* __restrict__ partials, double max_norm, const float* __restrict__ step_size,
                            float b1, float b2, float eps, float tau, float one_minus_tau,
                            float* __restrict__ norm_out) {
  __shared__ double shared[kThreads];
  __shared__ float scale_shared;
  __shared__ bool clip_shared;
  const double total = block_sum(partials[threadIdx.x], shared);
  if (threadIdx.x == 0) {
    const double norm = sqrt(total);
    clip_shared = max_norm > 0.0 && norm > max_norm;
    scale_shared = clip_shared ? static_cast<float>(max_norm / norm) : 1.0F;
    if (blockIdx.x == 0) {
      *norm_out = static_cast<float>(norm);
    }
  }
  __syncthreads();
  const bool clip = clip_shared;
  const float scale = scale_shared;
  const float step = *step_size;
  for (int64_t i = blockIdx.x * int64_t{kThreads} + threadIdx.x; i < n; i += int64_t{gridDim.x} * kThreads) {
    const float g = clip ? grads[i] * scale : grads[i];
    const float mi = b1 * m[i] + (1.0F - b1) * g;
    const float vi = b2 * v[i] + (1.0F - b2) * (g * g);
    const float p = params[i] - step * mi / (sqrtf(vi) + eps);
    m[i] = mi;
    v[i] = vi;
    params[i] = p;
    target[i] = tau * p + one_minus_tau * target[i];
  }
}

// ---------------------------------------------------------------------------------------------
// Networks

int64_t count_params(const std::vector<int>& widths, std::vector<int64_t>* offsets) {
  int64_t total = 0;
  for (size_t l = 0; l + 1 < widths.size(); ++l) {
    offsets->push_back(total);
    total += int64_t{widths[l + 1]} * (widths[l] + 1);
  }
  return total;
}

// One network's parameters, gradients, Adam moments and target copy.
struct Net {
  std::vector<int> widths;
  std::vector<int64_t> offsets;  // of each layer's [W | b]
  int64_t n = 0;
  DeviceArray<float> params, grads, m, v, target;
  DeviceArray<double> norm_partials;
  int adam_blocks = 1;

  explicit Net(std::vector<int> w) : widths(std::move(w)) {
    n = count_params(widths, &offsets);
    params = DeviceArray<float>(n);
    grads = DeviceArray<float>(n);
    m = DeviceArray<float>(n);
    v = DeviceArray<float>(n);
    target = DeviceArray<float>(n);
    norm_partials = DeviceArray<double>(kNormBlocks);
    adam_blocks = static_cast<int>(std::min<int64_t>(blocks_for(n), kMaxAdamBlocks));
  }
  [[nodiscard]] int layers() const { return static_cast<int>(widths.size()) - 1; }
};

// The buffers of one forward pass through a network: the inputs of layers 1.. (with their ones
// row), the output, and dLoss/dz of the hidden layers for the backward pass.
struct Pass {
  std::vector<DeviceArray<float>> act;    // act[l], l >= 1: input of layer l, (widths[l] + 1) x B
  DeviceArray<float> out;                 // widths.back() x B
  std::vector<DeviceArray<float>> delta;  // delta[l]: hidden layer l's dLoss/dz, widths[l + 1] x B

  Pass(const std::vector<int>& widths, int batch) {
    const int layers = static_cast<int>(widths.size()) - 1;
    act.emplace_back();  // layer 0's input belongs to the caller
    for (int l = 1; l < layers; ++l) {
      act.emplace_back(int64_t{widths[l] + 1} * batch);
    }
    out = DeviceArray<float>(int64_t{widths.back()} * batch);
    for (int l = 0; l + 1 < layers; ++l) {
      delta.emplace_back(int64_t{widths[l + 1]} * batch);
    }
  }
};

// ---------------------------------------------------------------------------------------------

struct Impl {
  DeviceDdpgConfig c;
  int B;
  // A stream with its own cuBLAS handle and workspace. Lane 0 runs the update; inside the graph
  // lanes 1 and 2 run the two branches that do not wait for the critic step (the target
  // networks; the actor's forward pass), forked from lane 0 after the batch is spread into the
  // network inputs and joined back where their results are needed.
  struct Lane {
    cudaStream_t stream = nullptr;
    cublasHandle_t blas = nullptr;
    DeviceArray<char> workspace;
  };
  Lane lanes[3];
  cudaStream_t stream = nullptr;       // lanes[0].stream
  cudaStream_t copy_stream = nullptr;  // host-to-device batch transfers
  cudaEvent_t forked = nullptr;
  cudaEvent_t targets_done = nullptr;
  cudaEvent_t actor_forward_done = nullptr;
  cudaEvent_t dz_ready = nullptr;    // backward(): a layer's dLoss/dz is ready on lane 0
  cudaEvent_t grads_done = nullptr;  // backward(): lane 1 has written every [dW | db]

  Net actor, critic;
  Pass pass_target_actor, pass_target_critic, pass_critic, pass_actor;
  // Network inputs, ones row included: actor (obs + 1) x B, critic (obs + width + 1) x B.
  DeviceArray<float> actor_in, actor_in_next, critic_in_batch, critic_in_next, critic_in_pi;
  DeviceArray<float> d_q;         // 1 x B, the critic step's dLoss/dQ
  DeviceArray<float> minus_ones;  // 1 x B, the actor step's dLoss/dQ
  DeviceArray<float> d_action;    // width x B
  DeviceArray<float> lo, hi;
  DeviceArray<float> stats;  // kStats

  // The input slot: scalars, then states, actions, rewards, next states, terminal, returns.
  int64_t off_states = 0, off_actions = 0, off_rewards = 0, off_next = 0, off_terminal = 0, off_returns = 0;
  int64_t slot_floats = 0;

  struct Slot {
    PinnedArray<float> host_in;
    DeviceArray<float> staging;
    PinnedArray<float> host_stats;
    cudaGraphExec_t exec = nullptr;
    cudaEvent_t copied = nullptr;
    cudaEvent_t done = nullptr;
    bool launched = false;
  };
  Slot slots[2];
  int next = 0;     // slot of the next update
  int newest = -1;  // slot of the newest queued update

  explicit Impl(const DeviceDdpgConfig& config)
      : c(config),
        B(config.batch),
        actor(config.actor_widths),
        critic(config.critic_widths),
        pass_target_actor(config.actor_widths, config.batch),
        pass_target_critic(config.critic_widths, config.batch),
        pass_critic(config.critic_widths, config.batch),
        pass_actor(config.actor_widths, config.batch) {
    try {
      build();
    } catch (...) {
      release();  // the destructor does not run when the constructor throws
      throw;
    }
  }

  ~Impl() { release(); }

  // The constructor's work after the member initializers (which only allocate device arrays).
  void build() {
    const int obs = c.obs_dim;
    const int w = c.width;
    actor_in = DeviceArray<float>(int64_t{obs + 1} * B);
    actor_in_next = DeviceArray<float>(int64_t{obs + 1} * B);
    critic_in_batch = DeviceArray<float>(int64_t{obs + w + 1} * B);
    critic_in_next = DeviceArray<float>(int64_t{obs + w + 1} * B);
    critic_in_pi = DeviceArray<float>(int64_t{obs + w + 1} * B);
    d_q = DeviceArray<float>(B);
    minus_ones = DeviceArray<float>(B);
    d_action = DeviceArray<float>(int64_t{w} * B);
    lo = DeviceArray<float>(w);
    hi = DeviceArray<float>(w);
    stats = DeviceArray<float>(kStats);

    off_states = kScalars;
    off_actions = off_states + round_up(int64_t{obs} * B);
    off_rewards = off_actions + round_up(int64_t{w} * B);
    off_next = off_rewards + round_up(B);
    off_terminal = off_next + round_up(int64_t{obs} * B);
    off_returns = off_terminal + round_up(B);
    slot_floats = off_returns + round_up(B);
    for (Slot& s : slots) {
      s.host_in = PinnedArray<float>(slot_floats);
      s.staging = DeviceArray<float>(slot_floats);
      s.host_stats = PinnedArray<float>(kStats);
      check(cudaEventCreateWithFlags(&s.copied, cudaEventDisableTiming), "cudaEventCreate");
      check(cudaEventCreateWithFlags(&s.done, cudaEventDisableTiming), "cudaEventCreate");
    }

    for (Lane& lane : lanes) {
      check(cudaStreamCreateWithFlags(&lane.stream, cudaStreamNonBlocking), "cudaStreamCreate");
      check(cublasCreate(&lane.blas), "cublasCreate");
      check(cublasSetStream(lane.blas, lane.stream), "cublasSetStream");
      // Set after the stream (cublasSetStream resets it): graph capture then never asks cuBLAS
      // to allocate, and concurrent lanes never share scratch space.
      lane.workspace = DeviceArray<char>(static_cast<int64_t>(kCublasWorkspaceBytes));
      check(cublasSetWorkspace(lane.blas, lane.workspace.get(), kCublasWorkspaceBytes), "cublasSetWorkspace");
      // Plain float32 (no TF32 tensor cores): the CPU learner's precision.
      check(cublasSetMathMode(lane.blas, CUBLAS_DEFAULT_MATH), "cublasSetMathMode");
    }
    stream = lanes[0].stream;
    check(cudaStreamCreateWithFlags(&copy_stream, cudaStreamNonBlocking), "cudaStreamCreate");
    for (cudaEvent_t* e : {&forked, &targets_done, &actor_forward_done, &dz_ready, &grads_done}) {
      check(cudaEventCreateWithFlags(e, cudaEventDisableTiming), "cudaEventCreate");
    }

    // Ones everywhere: the bias rows of every layer input stay 1; everything else is
    // overwritten before it is read.
    for (DeviceArray<float>* a : {&actor_in, &actor_in_next, &critic_in_batch, &critic_in_next, &critic_in_pi}) {
      fill(*a, 1.0F);
    }
    for (Pass* p : {&pass_target_actor, &pass_target_critic, &pass_critic, &pass_actor}) {
      for (auto& a : p->act) {
        if (a.get() != nullptr) {
          fill(a, 1.0F);
        }
      }
    }
    fill(minus_ones, -1.0F);
    check(cudaMemcpyAsync(lo.get(), c.lo.data(), lo.bytes(), cudaMemcpyHostToDevice, stream), "cudaMemcpy lo");
    check(cudaMemcpyAsync(hi.get(), c.hi.data(), hi.bytes(), cudaMemcpyHostToDevice, stream), "cudaMemcpy hi");
    for (Net* net : {&actor, &critic}) {
      for (DeviceArray<float>* a : {&net->params, &net->grads, &net->m, &net->v, &net->target}) {
        fill(*a, 0.0F);
      }
    }
    for (Slot& s : slots) {
      fill(s.staging, 0.0F);
    }

    // Warm-up on zeros (step sizes 0), outside any capture: loads cuBLAS's kernels and ours.
    record_update(slots[0]);
    check(cudaStreamSynchronize(stream), "warm-up update");
    for (Slot& s : slots) {
      cudaGraph_t graph = nullptr;
      check(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal), "cudaStreamBeginCapture");
      try {
        record_update(s);
      } catch (...) {
        cudaStreamEndCapture(stream, &graph);
        if (graph != nullptr) {
          cudaGraphDestroy(graph);
        }
        throw;
      }
      check(cudaStreamEndCapture(stream, &graph), "cudaStreamEndCapture");
      const cudaError_t e = cudaGraphInstantiate(&s.exec, graph, 0);
      cudaGraphDestroy(graph);
      check(e, "cudaGraphInstantiate");
    }
  }

  // Waits for queued work and destroys every stream, handle, event and graph that exists.
  void release() noexcept {
    for (Lane& lane : lanes) {
      if (lane.stream != nullptr) {
        cudaStreamSynchronize(lane.stream);
      }
    }
    if (copy_stream != nullptr) {
      cudaStreamSynchronize(copy_stream);
    }
    for (cudaEvent_t e : {forked, targets_done, actor_forward_done, dz_ready, grads_done}) {
      if (e != nullptr) {
        cudaEventDestroy(e);
      }
    }
    for (Slot& s : slots) {
      if (s.exec != nullptr) {
        cudaGraphExecDestroy(s.exec);
      }
      if (s.copied != nullptr) {
        cudaEventDestroy(s.copied);
      }
      if (s.done != nullptr) {
        cudaEventDestroy(s.done);
      }
    }
    if (copy_stream != nullptr) {
      cudaStreamDestroy(copy_stream);
    }
    for (Lane& lane : lanes) {
      if (lane.blas != nullptr) {
        cublasDestroy(lane.blas);
      }
      if (lane.stream != nullptr) {
        cudaStreamDestroy(lane.stream);
      }
    }
  }

  void fill(const DeviceArray<float>& a, float value) {
    const int blocks = static_cast<int>(std::min<int64_t>(blocks_for(a.size()), 4096));
    fill_kernel<<<blocks, kThreads, 0, stream>>>(a.get(), a.size(), value);
    check_launch("fill_kernel");
  }

  // C (m x n, ldc) = op(A) op(B), float32.
  static void gemm(const Lane& lane, cublasOperation_t ta, cublasOperation_t tb, int m, int n, int k, const float* a,
                   int lda, const float* b, int ldb, float* cm, int ldc) {
    const float one = 1.0F;
    const float zero = 0.0F;
    check(cublasSgemm(lane.blas, ta, tb, m, n, k, &one, a, lda, b, ldb, &zero, cm, ldc), "cublasSgemm");
  }

  // Forward pass of `net` with parameters `params` on `input` ((widths[0] + 1) x B).
  void forward(const Lane& lane, const Net& net, const float* params, const float* input, Pass& pass) {
    const float* in = input;
    int ld_in = net.widths[0] + 1;
    const int layers = net.layers();
    for (int l = 0; l < layers; ++l) {
      const int out = net.widths[l + 1];
      const bool hidden = l + 1 < layers;
      float* z = hidden ? pass.act[l + 1].get() : pass.out.get();
      const int ld_z = hidden ? out + 1 : out;
      // [W | b] (out x (in + 1)) * [a; 1] ((in + 1) x B).
      gemm(lane, CUBLAS_OP_N, CUBLAS_OP_N, out, B, net.widths[l] + 1, params + net.offsets[l], out, in, ld_in, z, ld_z);
      if (hidden) {
        leaky_relu_kernel<<<blocks_for(int64_t{out} * B), kThreads, 0, lane.stream>>>(z, out, ld_z, B, c.leaky_slope);
        check_launch("leaky_relu_kernel");
      }
      in = z;
      ld_in = ld_z;
    }
  }

  // Backward pass of the last forward() of `net` on `input` with dLoss/doutput `d_out`
  // (widths.back() x B), queued on lane 0. With param_grads, writes net.grads; with
  // input_rows > 0, writes dLoss/dinput for input rows [input_row0, input_row0 + input_rows)
  // into input_grad (input_rows x B).
  //
  // The [dW | db] products run on lane 1, off the chain of input gradients: each needs only its
  // layer's dz and input, which lane 0 does not write again in this pass, and lane 0 waits for
  // all of them before returning (the norm and Adam read them; the next forward pass rewrites
  // the inputs and deltas they read).
  void backward(Net& net, const float* input, Pass& pass, const float* d_out, bool param_grads, int input_row0,
                int input_rows, float* input_grad) {
    const Lane& side = lanes[1];
    const float* dz = d_out;  // leading dimension: the layer's width
    for (int l = net.layers() - 1; l >= 0; --l) {
      const int out = net.widths[l + 1];
      const int in = net.widths[l];
      const float* a_prev = l == 0 ? input : pass.act[l].get();
      const float* w = net.params.get() + net.offsets[l];
      if (param_grads) {
        check(cudaEventRecord(dz_ready, stream), "cudaEventRecord");
        check(cudaStreamWaitEvent(side.stream, dz_ready, 0), "cudaStreamWaitEvent");
        // [dW | db] (out x (in + 1)) = dz (out x B) * [a; 1]^T.
        gemm(side, CUBLAS_OP_N, CUBLAS_OP_T, out, in + 1, B, dz, out, a_prev, in + 1, net.grads.get() + net.offsets[l],
             out);
      }
      if (l > 0) {
        float* d_prev = pass.delta[l - 1].get();
        // d_prev (in x B) = W^T (in x out) * dz, then through the leaky ReLU that produced a_prev.
        gemm(lanes[0], CUBLAS_OP_T, CUBLAS_OP_N, in, B, out, w, out, dz, out, d_prev, in);
        leaky_relu_grad_kernel<<<blocks_for(int64_t{in} * B), kThreads, 0, stream>>>(d_prev, a_prev, in, in + 1, B,
                                                                                     c.leaky_slope);
        check_launch("leaky_relu_grad_kernel");
        dz = d_prev;
      } else if (input_rows > 0) {
        // Columns [input_row0, input_row0 + input_rows) of W, transposed, times dz.
        gemm(lanes[0], CUBLAS_OP_T, CUBLAS_OP_N, input_rows, B, out, w + int64_t{input_row0} * out, out, dz, out,
             input_grad, input_rows);
      }
    }
    if (param_grads) {
      check(cudaEventRecord(grads_done, side.stream), "cudaEventRecord");
      check(cudaStreamWaitEvent(stream, grads_done, 0), "cudaStreamWaitEvent");
    }
  }

  void optimizer_step(Net& net, const float* step_size, float* norm_out) {
    norm_partials_kernel<<<kNormBlocks, kThreads, 0, stream>>>(net.grads.get(), net.n, net.norm_partials.get());
    check_launch("norm_partials_kernel");
    adam_kernel<<<net.adam_blocks, kThreads, 0, stream>>>(
        net.params.get(), net.grads.get(), net.m.get(), net.v.get(), net.target.get(), net.n, net.norm_partials.get(),
        c.clip_grad_norm, step_size, c.adam_beta1, c.adam_beta2, c.adam_epsilon, c.tau, c.one_minus_tau, norm_out);
    check_launch("adam_kernel");
  }

  // The whole update reading slot `s`, queued on lane 0 (captured into s.exec). Lanes 1 and 2
  // fork after prepare_batch and join back before their results are read; nothing they read
  // is written by lane 0 before the join (the Adam kernels that rewrite the actor, the critic
  // and both targets all run after both joins).
  void record_update(Slot& s) {
    const int obs = c.obs_dim;
    const int w = c.width;
    const float* in = s.staging.get();
    const bool squashing = c.bound == 2;
    const Lane& main = lanes[0];
    const Lane& targets = lanes[1];
    const Lane& policy = lanes[2];

    prepare_batch_kernel<<<blocks_for(int64_t{obs + w} * B), kThreads, 0, main.stream>>>(
        in + off_states, in + off_actions, in + off_next, obs, w, B, actor_in.get(), actor_in_next.get(),
        critic_in_batch.get(), critic_in_next.get(), critic_in_pi.get());
    check_launch("prepare_batch_kernel");
    check(cudaEventRecord(forked, main.stream), "cudaEventRecord");
    check(cudaStreamWaitEvent(targets.stream, forked, 0), "cudaStreamWaitEvent");
    check(cudaStreamWaitEvent(policy.stream, forked, 0), "cudaStreamWaitEvent");

    // 1. Q'(s', mu'(s')) on lane 1.
    forward(targets, actor, actor.target.get(), actor_in_next.get(), pass_target_actor);
    actions_to_critic_kernel<<<blocks_for(int64_t{w} * B), kThreads, 0, targets.stream>>>(
        pass_target_actor.out.get(), critic_in_next.get() + obs, w, obs + w + 1, B, squashing, lo.get(), hi.get());
    check_launch("actions_to_critic_kernel");
    forward(targets, critic, critic.target.get(), critic_in_next.get(), pass_target_critic);
    check(cudaEventRecord(targets_done, targets.stream), "cudaEventRecord");

    // mu(s) on lane 2: the actor does not change before its own Adam step.
    forward(policy, actor, actor.params.get(), actor_in.get(), pass_actor);
    actions_to_critic_kernel<<<blocks_for(int64_t{w} * B), kThreads, 0, policy.stream>>>(
        pass_actor.out.get(), critic_in_pi.get() + obs, w, obs + w + 1, B, squashing, lo.get(), hi.get());
    check_launch("actions_to_critic_kernel");
    check(cudaEventRecord(actor_forward_done, policy.stream), "cudaEventRecord");

    // 2. Critic step on lane 0.
    forward(main, critic, critic.params.get(), critic_in_batch.get(), pass_critic);
    check(cudaStreamWaitEvent(main.stream, targets_done, 0), "cudaStreamWaitEvent");
    critic_loss_kernel<<<1, kThreads, 0, main.stream>>>(pass_target_critic.out.get(), pass_critic.out.get(),
                                                        in + off_rewards, in + off_terminal, in + off_returns, B,
                                                        c.gamma, c.mc_mix, c.bootstrap_clip, d_q.get(), stats.get());
    check_launch("critic_loss_kernel");
    backward(critic, critic_in_batch.get(), pass_critic, d_q.get(), true, 0, 0, nullptr);
    optimizer_step(critic, in + kCriticStep, stats.get() + kStatCriticNorm);

    // 3. Actor step through the updated critic.
    check(cudaStreamWaitEvent(main.stream, actor_forward_done, 0), "cudaStreamWaitEvent");
    forward(main, critic, critic.params.get(), critic_in_pi.get(), pass_critic);
    backward(critic, critic_in_pi.get(), pass_critic, minus_ones.get(), false, obs, w, d_action.get());
    gradient_bounds_kernel<<<blocks_for(int64_t{w} * B), kThreads, 0, main.stream>>>(
        d_action.get(), critic_in_pi.get() + obs, obs + w + 1, pass_actor.out.get(), w, B, c.bound, lo.get(), hi.get(),
        c.num_actions, stats.get() + kStatAtBound);
    check_launch("gradient_bounds_kernel");
    backward(actor, actor_in.get(), pass_actor, d_action.get(), true, 0, 0, nullptr);
    // 4. Adam and the soft target updates (fused; the critic's target above).
    optimizer_step(actor, in + kActorStep, stats.get() + kStatActorNorm);

    check(cudaMemcpyAsync(s.host_stats.get(), stats.get(), stats.bytes(), cudaMemcpyDeviceToHost, main.stream),
          "cudaMemcpyAsync stats");
  }

  void copy_in(const float* host, DeviceArray<float>& dev) {
    check(cudaMemcpyAsync(dev.get(), host, dev.bytes(), cudaMemcpyHostToDevice, stream), "cudaMemcpyAsync upload");
  }
  void copy_out(const DeviceArray<float>& dev, float* host) {
    check(cudaMemcpyAsync(host, dev.get(), dev.bytes(), cudaMemcpyDeviceToHost, stream), "cudaMemcpyAsync download");
  }

  DeviceStats stats_of(const Slot& s) const {
    const float* h = s.host_stats.get();
    return {h[kStatLoss], h[kStatQ], h[kStatTarget], h[kStatCriticNorm], h[kStatActorNorm], h[kStatAtBound]};
  }
};

// DeviceDdpg, the interface the host side sees, over Impl.
class DeviceDdpgImpl final : public DeviceDdpg {
 public:
  explicit DeviceDdpgImpl(const DeviceDdpgConfig& config);
  [[nodiscard]] int64_t actor_params() const override;
  [[nodiscard]] int64_t critic_params() const override;
  void upload(const HostState& state) override;
  void download(const HostState& state) override;
  void download_actor(float* actor) override;
  DeviceStats enqueue(const HostBatch& batch, float actor_step_size, float critic_step_size,
                      bool* has_previous) override;
  DeviceStats finish() override;

 private:
  std::unique_ptr<Impl> impl_;
};

DeviceDdpgImpl::DeviceDdpgImpl(const DeviceDdpgConfig& config) {
  if (config.batch < 1 || config.obs_dim < 1 || config.width < 1 ||
      config.lo.size() != static_cast<size_t>(config.width) || config.hi.size() != static_cast<size_t>(config.width) ||
      config.actor_widths.size() < 2 || config.critic_widths.size() < 2 ||
      config.actor_widths.front() != config.obs_dim || config.actor_widths.back() != config.width ||
      config.critic_widths.front() != config.obs_dim + config.width || config.critic_widths.back() != 1) {
    throw std::invalid_argument("DeviceDdpg: inconsistent shapes");
  }
  check(cudaSetDevice(0), "cudaSetDevice");
  impl_ = std::make_unique<Impl>(config);
}

int64_t DeviceDdpgImpl::actor_params() const {
  return impl_->actor.n;
}
int64_t DeviceDdpgImpl::critic_params() const {
  return impl_->critic.n;
}

void DeviceDdpgImpl::upload(const HostState& s) {
  Impl& d = *impl_;
  check(cudaStreamSynchronize(d.stream), "cudaStreamSynchronize");
  d.copy_in(s.actor, d.actor.params);
  d.copy_in(s.target_actor, d.actor.target);
  d.copy_in(s.actor_m, d.actor.m);
  d.copy_in(s.actor_v, d.actor.v);
  d.copy_in(s.critic, d.critic.params);
  d.copy_in(s.target_critic, d.critic.target);
  d.copy_in(s.critic_m, d.critic.m);
  d.copy_in(s.critic_v, d.critic.v);
  check(cudaStreamSynchronize(d.stream), "upload");
}

void DeviceDdpgImpl::download(const HostState& s) {
  Impl& d = *impl_;
  check(cudaStreamSynchronize(d.stream), "cudaStreamSynchronize");
  d.copy_out(d.actor.params, s.actor);
  d.copy_out(d.actor.target, s.target_actor);
  d.copy_out(d.actor.m, s.actor_m);
  d.copy_out(d.actor.v, s.actor_v);
  d.copy_out(d.critic.params, s.critic);
  d.copy_out(d.critic.target, s.target_critic);
  d.copy_out(d.critic.m, s.critic_m);
  d.copy_out(d.critic.v, s.critic_v);
  check(cudaStreamSynchronize(d.stream), "download");
}

void DeviceDdpgImpl::download_actor(float* actor) {
  Impl& d = *impl_;
  check(cudaStreamSynchronize(d.stream), "cudaStreamSynchronize");
  d.copy_out(d.actor.params, actor);
  check(cudaStreamSynchronize(d.stream), "download_actor");
}

DeviceStats DeviceDdpgImpl::enqueue(const HostBatch& b, float actor_step_size, float critic_step_size,
                                    bool* has_previous) {
  Impl& d = *impl_;
  Impl::Slot& s = d.slots[d.next];
  const int obs = d.c.obs_dim;
  const int w = d.c.width;
  const int B = d.B;
  if (s.launched) {
    // The copy that last read this pinned buffer (two updates ago) has finished: the previous
    // call waited for its graph, which waited for it. Cheap insurance all the same.
    check(cudaEventSynchronize(s.copied), "cudaEventSynchronize");
  }
  float* h = s.host_in.get();
  h[kActorStep] = actor_step_size;
  h[kCriticStep] = critic_step_size;
  std::memcpy(h + d.off_states, b.states, sizeof(float) * obs * B);
  std::memcpy(h + d.off_actions, b.actions, sizeof(float) * w * B);
  std::memcpy(h + d.off_rewards, b.rewards, sizeof(float) * B);
  std::memcpy(h + d.off_next, b.next_states, sizeof(float) * obs * B);
  std::memcpy(h + d.off_terminal, b.terminal, sizeof(float) * B);
  std::memcpy(h + d.off_returns, b.mc_returns, sizeof(float) * B);
  if (s.launched) {
    // The device staging buffer is free once the graph that read it (two updates ago) is done.
    check(cudaStreamWaitEvent(d.copy_stream, s.done, 0), "cudaStreamWaitEvent");
  }
  check(cudaMemcpyAsync(s.staging.get(), h, s.staging.bytes(), cudaMemcpyHostToDevice, d.copy_stream),
        "cudaMemcpyAsync batch");
  check(cudaEventRecord(s.copied, d.copy_stream), "cudaEventRecord");
  check(cudaStreamWaitEvent(d.stream, s.copied, 0), "cudaStreamWaitEvent");
  check(cudaGraphLaunch(s.exec, d.stream), "cudaGraphLaunch");
  check(cudaEventRecord(s.done, d.stream), "cudaEventRecord");
  s.launched = true;

  Impl::Slot& prev = d.slots[d.next ^ 1];
  DeviceStats out;
  *has_previous = prev.launched && d.newest >= 0;
  if (*has_previous) {
    check(cudaEventSynchronize(prev.done), "cudaEventSynchronize");
    out = d.stats_of(prev);
  }
  d.newest = d.next;
  d.next ^= 1;
  return out;
}

DeviceStats DeviceDdpgImpl::finish() {
  Impl& d = *impl_;
  check(cudaStreamSynchronize(d.stream), "cudaStreamSynchronize");
  return d.newest < 0 ? DeviceStats{} : d.stats_of(d.slots[d.newest]);
}

int device_count(std::string* why) {
  int n = 0;
  const cudaError_t e = cudaGetDeviceCount(&n);
  if (e != cudaSuccess) {
    cudaGetLastError();  // not sticky, but leave no error behind for the next call
    if (why != nullptr) {
      *why = std::string(e == cudaErrorInsufficientDriver ? "no NVIDIA driver, or one too old for this CUDA runtime: "
                                                          : "") +
             "cudaGetDeviceCount: " + cudaGetErrorString(e);
    }
    return 0;
  }
  if (n == 0 && why != nullptr) {
    *why = "cudaGetDeviceCount found no device";
  }
  return n;
}

std::string device_description() {
  cudaDeviceProp prop{};
  check(cudaGetDeviceProperties(&prop, 0), "cudaGetDeviceProperties");
  return std::string(prop.name) + ", " + std::to_string(prop.totalGlobalMem >> 30) + " GiB, " +
         std::to_string(prop.multiProcessorCount) + " SMs";
}

double time_sgemm(int m, int n, int k, int reps) {
  check(cudaSetDevice(0), "cudaSetDevice");
  DeviceArray<float> a(int64_t{m} * k), b(int64_t{k} * n), cm(int64_t{m} * n);
  cudaStream_t stream = nullptr;
  cublasHandle_t blas = nullptr;
  cudaEvent_t start = nullptr, stop = nullptr;
  double seconds = 0.0;
  std::string error;
  try {
    check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "cudaStreamCreate");
    check(cublasCreate(&blas), "cublasCreate");
    check(cublasSetStream(blas, stream), "cublasSetStream");
    check(cublasSetMathMode(blas, CUBLAS_DEFAULT_MATH), "cublasSetMathMode");
    check(cudaEventCreate(&start), "cudaEventCreate");
    check(cudaEventCreate(&stop), "cudaEventCreate");
    for (const DeviceArray<float>* x : {&a, &b, &cm}) {
      fill_kernel<<<1024, kThreads, 0, stream>>>(x->get(), x->size(), 0.5F);
      check_launch("fill_kernel");
    }
    const float one = 1.0F;
    const float zero = 0.0F;
    auto run = [&] {
      check(cublasSgemm(blas, CUBLAS_OP_N, CUBLAS_OP_N, m, n, k, &one, a.get(), m, b.get(), k, &zero, cm.get(), m),
            "cublasSgemm");
    };
    run();  // warm-up
    check(cudaEventRecord(start, stream), "cudaEventRecord");
    for (int r = 0; r < reps; ++r) {
      run();
    }
    check(cudaEventRecord(stop, stream), "cudaEventRecord");
    check(cudaEventSynchronize(stop), "cudaEventSynchronize");
    float ms = 0.0F;
    check(cudaEventElapsedTime(&ms, start, stop), "cudaEventElapsedTime");
    seconds = ms / 1e3;
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (start != nullptr) {
    cudaEventDestroy(start);
  }
  if (stop != nullptr) {
    cudaEventDestroy(stop);
  }
  if (blas != nullptr) {
    cublasDestroy(blas);
  }
  if (stream != nullptr) {
    cudaStreamDestroy(stream);
  }
  if (!error.empty()) {
    throw std::runtime_error(error);
  }
  return seconds;
}

std::unique_ptr<DeviceDdpg> create(const DeviceDdpgConfig& config) {
  return std::make_unique<DeviceDdpgImpl>(config);
}

}  // namespace
}  // namespace pamdp::cuda

// The module's one exported symbol (see cuda_api() in device_ddpg.hpp).
extern "C" const pamdp::cuda::CudaApi pamdp_cuda_api = {pamdp::cuda::kCudaApiVersion, &pamdp::cuda::device_count,
                                                        &pamdp::cuda::device_description, &pamdp::cuda::time_sgemm,
                                                        &pamdp::cuda::create};
