// The CUDA backend's glue between the host Ddpg (Eigen, flat spans) and DeviceDdpg (raw
// pointers): shapes and constants are taken from the Ddpg exactly as its own update() casts
// them, and the Adam step sizes are computed here with core/optim's formula, so the device
// applies the same step as the host would.
#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>

#include "core/optim.hpp"
#include "learner/cuda/cuda_update_backend.hpp"
#include "learner/cuda/device_ddpg.hpp"

namespace pamdp {

namespace cuda {

const CudaApi* cuda_api(std::string* why) {
  static std::once_flag once;
  static const CudaApi* api = nullptr;
  static std::string error;
  std::call_once(once, [] {
    // Without the driver library there is no device: say so without loading cuBLAS.
    if (dlopen("libcuda.so.1", RTLD_LAZY | RTLD_LOCAL) == nullptr) {
      const char* e = dlerror();
      error = std::string("no NVIDIA driver: ") + (e != nullptr ? e : "libcuda.so.1 not found");
      return;
    }
    constexpr const char* kModule = "libpamdp_cuda.so";
    // Next to the executable first (the build puts programs and the module in bin/).
    std::string path = kModule;
    char exe[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (n > 0) {
      std::string dir(exe, static_cast<size_t>(n));
      dir.resize(dir.rfind('/') + 1);
      if (access((dir + kModule).c_str(), R_OK) == 0) {
        path = dir + kModule;
      }
    }
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* e = dlerror();
      error = std::string("cannot load ") + path + ": " + (e != nullptr ? e : "?");
      return;
    }
    const auto* table = static_cast<const CudaApi*>(dlsym(handle, "pamdp_cuda_api"));
    if (table == nullptr || table->version != kCudaApiVersion) {
      error = path + " is not this build's CUDA module (rebuild it)";
      return;
    }
    api = table;
  });
  if (api == nullptr && why != nullptr) {
    *why = error;
  }
  return api;
}

}  // namespace cuda

namespace {

// Only called after cuda_device_count() found a device, so the module is loaded.
const cuda::CudaApi& api() {
  std::string why;
  const cuda::CudaApi* a = cuda::cuda_api(&why);
  if (a == nullptr) {
    throw std::runtime_error(why);
  }
  return *a;
}

cuda::DeviceDdpgConfig device_config(Ddpg& ddpg) {
  const DdpgConfig& c = ddpg.config();
  cuda::DeviceDdpgConfig d;
  d.obs_dim = ddpg.obs_dim();
  d.width = ddpg.output_width();
  d.batch = c.batch_size;
  d.actor_widths = ddpg.actor().widths();
  d.critic_widths = ddpg.critic().widths();
  d.leaky_slope = ddpg.actor().leaky_slope();
  if (ddpg.critic().leaky_slope() != d.leaky_slope) {
    throw std::invalid_argument("CUDA learner: actor and critic must share one leaky ReLU slope");
  }
  d.gamma = static_cast<float>(c.gamma);
  d.mc_mix = static_cast<float>(c.mc_mix);
  d.bootstrap_clip = static_cast<float>(c.bootstrap_clip);
  d.tau = static_cast<float>(c.tau);
  d.one_minus_tau = static_cast<float>(1.0 - c.tau);
  d.clip_grad_norm = c.clip_grad_norm;
  d.adam_beta1 = static_cast<float>(c.adam_beta1);
  d.adam_beta2 = static_cast<float>(c.adam_beta2);
  d.adam_epsilon = static_cast<float>(c.adam_epsilon);
  switch (c.bound) {
    case BoundMethod::kInverting: d.bound = 0; break;
    case BoundMethod::kZeroing: d.bound = 1; break;
    case BoundMethod::kSquashing: d.bound = 2; break;
  }
  d.num_actions = ddpg.num_actions();
  d.lo = ddpg.bounds().lo;
  d.hi = ddpg.bounds().hi;
  return d;
}

class CudaUpdateBackend final : public UpdateBackend {
 public:
  explicit CudaUpdateBackend(Ddpg& ddpg) : UpdateBackend(ddpg), device_(api().create(device_config(ddpg))) {
    if (device_->actor_params() != ddpg.actor().num_params() ||
        device_->critic_params() != ddpg.critic().num_params()) {
      throw std::logic_error("CUDA learner: device and host parameter layouts differ");
    }
    load_from_host();
  }

  [[nodiscard]] const char* name() const override { return "cuda"; }

  using UpdateBackend::update;  // cloning: the base's refusal (make_update_backend picks the CPU)
  UpdateStats update(const BatchView& batch) override {
    const int B = ddpg_.config().batch_size;
    if (batch.states.cols() != B || batch.states.rows() != ddpg_.obs_dim() ||
        batch.actions.rows() != ddpg_.output_width() || batch.actions.cols() != B || batch.rewards.size() != B ||
        batch.next_states.cols() != B || batch.terminal.size() != B || batch.mc_returns.size() != B) {
      // The graphs are captured for one batch size; anything else is a bug in the caller.
      std::fprintf(stderr, "CUDA learner: update() needs a full obs x %d batch\n", B);
      std::abort();
    }
    ++actor_steps_;
    ++critic_steps_;
    ddpg_.schedule_learning_rates();
    const auto actor_step = static_cast<float>(adam_step_size(ddpg_.actor_optimizer().config(), actor_steps_));
    const auto critic_step = static_cast<float>(adam_step_size(ddpg_.critic_optimizer().config(), critic_steps_));
    const cuda::HostBatch b{batch.states.data(),      batch.actions.data(),  batch.rewards.data(),
                            batch.next_states.data(), batch.terminal.data(), batch.mc_returns.data()};
    bool has_previous = false;
    const cuda::DeviceStats s = device_->enqueue(b, actor_step, critic_step, &has_previous);
    ddpg_.set_updates(ddpg_.updates() + 1);
    if (has_previous) {
      last_ = convert(s);
    }
    return last_;
  }

  UpdateStats finish() override {
    last_ = convert(device_->finish());
    return last_;
  }

  void sync_to_host() override {
    device_->download(host_state());
    ddpg_.actor_optimizer().set_steps(actor_steps_);
    ddpg_.critic_optimizer().set_steps(critic_steps_);
  }

  void load_from_host() override {
    device_->upload(host_state());
    actor_steps_ = ddpg_.actor_optimizer().steps();
    critic_steps_ = ddpg_.critic_optimizer().steps();
  }

 private:
  void download_actor() override { device_->download_actor(ddpg_.actor().params().data()); }

  [[nodiscard]] UpdateStats convert(const cuda::DeviceStats& s) const {
    const int params = params_per_sample_ * ddpg_.config().batch_size;
    return {s.critic_loss,      s.q_mean,          s.target_mean,
            s.critic_grad_norm, s.actor_grad_norm, params > 0 ? s.params_at_bound / static_cast<float>(params) : 0.0F};
  }

  cuda::HostState host_state() {
    return {ddpg_.actor().params().data(),
            ddpg_.critic().params().data(),
            ddpg_.target_actor().params().data(),
            ddpg_.target_critic().params().data(),
            ddpg_.actor_optimizer().first_moment().data(),
            ddpg_.actor_optimizer().second_moment().data(),
            ddpg_.critic_optimizer().first_moment().data(),
            ddpg_.critic_optimizer().second_moment().data()};
  }

  std::unique_ptr<cuda::DeviceDdpg> device_;
  int params_per_sample_ = ddpg_.output_width() - ddpg_.num_actions();
  int64_t actor_steps_ = 0;
  int64_t critic_steps_ = 0;
  UpdateStats last_;
};

}  // namespace

std::unique_ptr<UpdateBackend> make_cuda_update_backend(Ddpg& ddpg) {
  return std::make_unique<CudaUpdateBackend>(ddpg);
}

int cuda_device_count(std::string* why) {
  const cuda::CudaApi* a = cuda::cuda_api(why);
  return a == nullptr ? 0 : a->device_count(why);
}

std::string cuda_device_description() {
  return api().device_description();
}

double time_device_sgemm(int m, int n, int k, int reps) {
  return api().time_sgemm(m, n, k, reps);
}

}  // namespace pamdp
