// Where DDPG updates run: on the host (Ddpg::update itself) or on a CUDA device
// (learner/cuda/, docs/gpu.md). The host Ddpg stays the one source of truth for everything
// outside update(): acting, evaluation, weight broadcasts and checkpoints read it, so a device
// backend copies its state back when asked (sync_*) and starts from it (load_from_host).
//
// Threading: one thread at a time, like Ddpg. update() allocates nothing on either backend.
#pragma once

#include <memory>
#include <string>

#include "learner/ddpg.hpp"

namespace pamdp {

class UpdateBackend {
 public:
  // `ddpg` is owned by the caller and must outlive the backend.
  explicit UpdateBackend(Ddpg& ddpg) : ddpg_(ddpg) {}
  virtual ~UpdateBackend() = default;
  UpdateBackend(const UpdateBackend&) = delete;
  UpdateBackend& operator=(const UpdateBackend&) = delete;

  [[nodiscard]] virtual const char* name() const = 0;  // "cpu" or "cuda"

  // One DDPG update on a full batch (ddpg().config().batch_size samples). The batch is read or
  // copied before this returns, so the caller may reuse its buffers at once. ddpg().updates()
  // counts the update when this returns. Returns the statistics of the newest finished update:
  // this one on the CPU; on the GPU, where updates run asynchronously, the previous one (zeros
  // before the first has finished). Cost: CPU ~ the update itself; GPU ~ a 20 KB copy into a
  // pinned buffer and a graph launch, plus waiting for the previous update.
  virtual UpdateStats update(const BatchView& batch) = 0;
  // One update that also clones `demos` (ddpg.demo_bc_weight > 0; Ddpg::update). The CPU backend
  // has it; make_update_backend gives the CPU one whenever the config clones, so the others throw
  // std::logic_error.
  virtual UpdateStats update(const BatchView& batch, const BatchView& demos);
  // Waits for every queued update; returns the newest one's statistics.
  virtual UpdateStats finish() = 0;

  // Copies the device state into ddpg(): sync_to_host everything a checkpoint holds (both
  // networks, both targets, both Adam states and step counts), sync_actor_to_host only the
  // online actor's parameters (acting, evaluation, weight broadcasts; ~3 MB at the paper's
  // widths). Both wait for queued updates; the copies are no-ops on the CPU.
  // sync_actor_to_host then moves the actor average (Ddpg::track_actor_average), since the host
  // actor is current there: every point that reads the actor also feeds the average.
  virtual void sync_to_host() = 0;
  void sync_actor_to_host() {
    download_actor();
    ddpg_.track_actor_average();
  }
  // Replaces the device state with ddpg()'s (after a checkpoint was loaded into it). The
  // constructor does this once. No-op on the CPU.
  virtual void load_from_host() = 0;

  Ddpg& ddpg() { return ddpg_; }

 protected:
  virtual void download_actor() = 0;  // the online actor's parameters into ddpg().actor()

  Ddpg& ddpg_;
};

// Runs Ddpg::update in the calling thread: exactly the learner without a backend.
class CpuUpdateBackend final : public UpdateBackend {
 public:
  explicit CpuUpdateBackend(Ddpg& ddpg) : UpdateBackend(ddpg) {}
  [[nodiscard]] const char* name() const override { return "cpu"; }
  UpdateStats update(const BatchView& batch) override {
    last_ = ddpg_.update(batch);
    return last_;
  }
  UpdateStats update(const BatchView& batch, const BatchView& demos) override {
    last_ = ddpg_.update(batch, &demos);
    return last_;
  }
  UpdateStats finish() override { return last_; }
  void sync_to_host() override {}
  void load_from_host() override {}

 private:
  void download_actor() override {}

  UpdateStats last_;
};

// kCpu: the CPU backend. kCuda: the CUDA backend on device 0; throws std::runtime_error with a
// one-line message naming the problem and the fix when this build has no CUDA support or no
// device is usable. kAuto: CUDA when a device is usable (and the backend can be built on it),
// else the CPU; logs which it took and why. With ddpg.demo_bc_weight > 0 always the CPU (kCuda
// throws).
std::unique_ptr<UpdateBackend> make_update_backend(Ddpg& ddpg, UpdateDevice device);

// Number of usable CUDA devices (0 in a build without CUDA, without a driver or without a
// device); `why`, when given and the answer is 0, receives the reason in a few words.
int cuda_device_count(std::string* why = nullptr);

const char* update_device_name(UpdateDevice device);

}  // namespace pamdp
