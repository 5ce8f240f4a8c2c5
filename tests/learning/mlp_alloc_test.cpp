// Proves that Mlp::forward/backward, the optimizer steps and a whole DDPG update (with and
// without demonstrations to clone) allocate nothing (core/mlp.hpp, core/optim.hpp,
// learner/ddpg.hpp) at the learner's batch (32) and the actors' (1).
//
// Eigen allocates with std::malloc (its aligned_malloc over-allocates and aligns by hand), not
// operator new, so replacing operator new alone would miss exactly the allocations this test
// is about: GEMM blocking workspaces. This binary therefore interposes the C allocator itself
// (glibc's __libc_* entry points do the work), which also catches operator new, since
// libstdc++'s operator new calls malloc. Its own binary, so the replacement affects no other
// test. AddressSanitizer owns malloc, so under it the interposition is left out and the tests
// skip.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <vector>

#include "bench/random_batch.hpp"
#include "core/gemm.hpp"
#include "core/mlp.hpp"
#include "core/optim.hpp"
#include "core/rng.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "learner/ddpg.hpp"
#include "learner/pdqn.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define PAMDP_COUNT_MALLOC 0
#else
#define PAMDP_COUNT_MALLOC 1
#endif

namespace {

std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void note_allocation() {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
}

// Counts allocations made while it is alive.
class CountAllocations {
 public:
  CountAllocations() {
    g_allocations = 0;
    g_counting = true;
  }
  ~CountAllocations() { g_counting = false; }
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
  [[nodiscard]] long count() const { return g_allocations.load(); }
};

}  // namespace

#if PAMDP_COUNT_MALLOC
// NOLINTBEGIN: these must carry the C library's names and signatures.
extern "C" {
void* __libc_malloc(size_t size);
void* __libc_calloc(size_t count, size_t size);
void* __libc_realloc(void* p, size_t size);
void* __libc_memalign(size_t align, size_t size);

void* malloc(size_t size) {
  note_allocation();
  return __libc_malloc(size);
}
void* calloc(size_t count, size_t size) {
  note_allocation();
  return __libc_calloc(count, size);
}
void* realloc(void* p, size_t size) {
  note_allocation();
  return __libc_realloc(p, size);
}
void* memalign(size_t align, size_t size) {
  note_allocation();
  return __libc_memalign(align, size);
}
void* aligned_alloc(size_t align, size_t size) {
  note_allocation();
  return __libc_memalign(align, size);
}
int posix_memalign(void** out, size_t align, size_t size) {
  note_allocation();
  void* p = __libc_memalign(align, size);
  if (p == nullptr) {
    return 12;  // ENOMEM
  }
  *out = p;
  return 0;
}
}
// NOLINTEND
#endif

namespace pamdp {
namespace {

constexpr bool kCounting = PAMDP_COUNT_MALLOC != 0;

TEST(CountingAllocator, SeesNewAndEigenAllocations) {
  // Guards against a harness that counts nothing (the interposition not linked in).
  if (!kCounting) {
    GTEST_SKIP() << "AddressSanitizer owns malloc";
  }
  long from_new = 0;
  long from_eigen = 0;
  {
    CountAllocations scope;
    auto v = std::make_unique<std::vector<int>>(100);
    from_new = scope.count();
  }
  {
    CountAllocations scope;
    Eigen::MatrixXf m(64, 64);
    m.setZero();
    from_eigen = scope.count();
  }
  EXPECT_GE(from_new, 2);
  EXPECT_GE(from_eigen, 1);
}

// The paper's networks (reference §7.2): actor 58 -> ... -> 4 + 6, critic 68 -> ... -> 1.
const std::vector<int> kActorWidths{58, 1024, 512, 256, 128, 10};
const std::vector<int> kCriticWidths{68, 1024, 512, 256, 128, 1};

template <typename Scalar>
long allocations_in_forward_backward(const std::vector<int>& widths, int batch) {
  using Matrix = typename Mlp<Scalar>::Matrix;
  Rng rng(1);
  Mlp<Scalar> net(widths, 32);
  net.init_gaussian(rng, Scalar(0.01));
  Matrix x = Matrix::Random(widths.front(), batch);
  const Matrix d_out = Matrix::Random(widths.back(), batch);
  // No warm-up call: a first call that allocates lazily is still an allocation on the hot path.
  CountAllocations scope;
  for (int rep = 0; rep < 3; ++rep) {
    net.forward(x);
    net.backward(d_out, /*want_input_grad=*/true);
    net.backward(d_out, /*want_input_grad=*/false);
    net.backward_input(d_out);
  }
  return scope.count();
}

// Every transpose combination and row counts with and without a tail past a multiple of 16
// (OpenBLAS's AVX-512 kernels allocate on a * b for some tails; gemm routes those rows around).
template <typename Scalar>
long allocations_in_gemm(GemmLibrary library, int m, int n, int k) {
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  const Matrix a = Matrix::Random(std::max(m, k), std::max(m, k));
  const Matrix b = Matrix::Random(std::max(n, k), std::max(n, k));
  Matrix c = Matrix::Zero(m, n);
  CountAllocations scope;
  for (const Op op_a : {Op::kNone, Op::kTranspose}) {
    for (const Op op_b : {Op::kNone, Op::kTranspose}) {
      const auto lhs = op_a == Op::kNone ? a.topLeftCorner(m, k) : a.topLeftCorner(k, m);
      const auto rhs = op_b == Op::kNone ? b.topLeftCorner(k, n) : b.topLeftCorner(n, k);
      gemm_on<Scalar>(library, op_a, lhs, op_b, rhs, c, /*accumulate=*/false);
      gemm_on<Scalar>(library, op_a, lhs, op_b, rhs, c, /*accumulate=*/true);
    }
  }
  return scope.count();
}

TEST(GemmAllocations, EveryShapeOfTheMlpAllocatesNothing) {
  if (!kCounting) {
    GTEST_SKIP() << "AddressSanitizer owns malloc";
  }
  for (const GemmLibrary library : {GemmLibrary::kEigen, GemmLibrary::kOpenBlas}) {
    if (!gemm_library_available(library)) {
      continue;
    }
    const char* name = library == GemmLibrary::kEigen ? "Eigen" : "OpenBLAS";
    for (int m : {1, 3, 8, 10, 16, 24, 70, 128}) {
      for (int n : {1, 32}) {
        EXPECT_EQ(allocations_in_gemm<float>(library, m, n, 128), 0) << name << " float " << m << "x" << n << "x128";
        EXPECT_EQ(allocations_in_gemm<double>(library, m, n, 68), 0) << name << " double " << m << "x" << n << "x68";
      }
    }
  }
}

TEST(MlpAllocations, ForwardBackwardAllocateNothing) {
  if (!kCounting) {
    GTEST_SKIP() << "AddressSanitizer owns malloc";
  }
  for (int batch : {1, 32}) {
    EXPECT_EQ(allocations_in_forward_backward<float>(kActorWidths, batch), 0) << "actor, float, batch " << batch;
    EXPECT_EQ(allocations_in_forward_backward<float>(kCriticWidths, batch), 0) << "critic, float, batch " << batch;
    EXPECT_EQ(allocations_in_forward_backward<double>(kCriticWidths, batch), 0) << "critic, double, batch " << batch;
  }
}

TEST(OptimAllocations, StepClipAndSoftUpdateAllocateNothing) {
  if (!kCounting) {
    GTEST_SKIP() << "AddressSanitizer owns malloc";
  }
  Rng rng(2);
  Mlp<float> online(kCriticWidths, 1);
  Mlp<float> target(kCriticWidths, 1);
  online.init_gaussian(rng, 0.01F);
  target.init_gaussian(rng, 0.01F);
  for (float& g : online.grads()) {
    g = static_cast<float>(rng.normal());
  }
  Adam<float> adam(online.num_params(), AdamConfig{});
  long allocations = 0;
  {
    CountAllocations scope;
    (void)clip_global_norm(online.grads(), 10.0);
    adam.step(online.params(), online.grads());
    soft_update(target.params(), online.params(), 1e-3);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0);
}

// P-DQN and MP-DQN: update() and act() allocate nothing, with HFO's Tackle masked (MP-DQN skips
// its pass), and with the pass-through layer together with the indexed loss, the zeroed index
// gradients and the own-action gradients (one input back-propagation per action).
TEST(PdqnAllocations, UpdateAndActAllocateNothing) {
  if (!kCounting) {
    GTEST_SKIP() << "AddressSanitizer owns malloc";
  }
  const ActionSpace& space = hfo::hfo_action_space();
  const int obs = bench::RandomHfoBatch::kObs;
  const ParameterPrior prior{obs, std::vector<float>(static_cast<size_t>(obs * space.num_params()), 0.01F),
                             std::vector<float>(static_cast<size_t>(space.num_params()), 0.5F)};
  for (const bool multipass : {false, true}) {
    for (const bool passthrough : {false, true}) {
      DdpgConfig c;
      c.hidden = {64, 32};
      c.mc_mix = 0.5;
      PdqnSettings settings;
      settings.passthrough = passthrough;
      settings.indexed_loss = passthrough;
      settings.zero_index_gradients = passthrough;
      settings.own_action_gradients = passthrough;
      settings.reward_scale = 0.02;
      Pdqn p(obs, space, c, 3, multipass, {hfo::kTackle}, settings, &prior);
      const bench::RandomHfoBatch data(c.batch_size, 4);
      const BatchView batch = data.view();
      std::vector<float> out(static_cast<size_t>(p.output_width()));
      p.update(batch);
      p.act({batch.states.data(), static_cast<size_t>(obs)}, out);
      long allocations = 0;
      {
        CountAllocations scope;
        for (int i = 0; i < 3; ++i) {
          p.update(batch);
          p.act({batch.states.data(), static_cast<size_t>(obs)}, out);
        }
        allocations = scope.count();
      }
      EXPECT_EQ(allocations, 0) << (multipass ? "mpdqn" : "pdqn")
                                << (passthrough ? " with the pass-through layer and the gradient options" : "");
    }
  }
}

// DDPG: update() and act() allocate nothing, with and without cloning, and with the pass-through
// layer (ddpg.passthrough) under each bound, which reads its outputs before a squash.
TEST(DdpgAllocations, UpdateAllocatesNothing) {
  if (!kCounting) {
    GTEST_SKIP() << "AddressSanitizer owns malloc";
  }
  const ActionSpace& space = hfo::hfo_action_space();
  const int obs = bench::RandomHfoBatch::kObs;
  const ParameterPrior prior{obs, std::vector<float>(static_cast<size_t>(obs * space.num_params()), 0.01F),
                             std::vector<float>(static_cast<size_t>(space.num_params()), 0.5F)};
  for (const bool passthrough : {false, true}) {
    for (const BoundMethod bound : {BoundMethod::kInverting, BoundMethod::kSquashing}) {
      for (const double bc : {0.0, 1.0}) {
        DdpgConfig c;
        c.hidden = {256, 128, 64};
        c.mc_mix = 0.5;
        c.demo_bc_weight = bc;
        c.bound = bound;
        c.passthrough = passthrough;
        c.reward_scale = passthrough ? 0.02 : 1.0;
        Ddpg d(obs, space, c, 3, &prior);
        const bench::RandomHfoBatch data(c.batch_size, 4);
        const BatchView batch = data.view();
        std::vector<float> out(static_cast<size_t>(d.output_width()));
        d.update(batch, &batch);  // first-call work (none expected) out of the count
        d.act({batch.states.data(), static_cast<size_t>(obs)}, out);
        long allocations = 0;
        {
          CountAllocations scope;
          for (int i = 0; i < 3; ++i) {
            d.update(batch, &batch);
            d.act({batch.states.data(), static_cast<size_t>(obs)}, out);
          }
          allocations = scope.count();
        }
        EXPECT_EQ(allocations, 0) << "demo_bc_weight " << bc << ", bound " << static_cast<int>(bound)
                                  << (passthrough ? ", with the pass-through layer" : "");
      }
    }
  }
}

}  // namespace
}  // namespace pamdp
