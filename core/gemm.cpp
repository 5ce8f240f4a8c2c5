#include "core/gemm.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <mutex>
#include <string>
#include <type_traits>

#ifdef PAMDP_HAVE_OPENBLAS
// The Fortran BLAS interface (what Eigen's own BLAS backend calls): column-major, everything
// by pointer. Declared here rather than through cblas.h, whose location differs between
// OpenBLAS builds; only this file sees it.
extern "C" {
void sgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k, const float* alpha,
            const float* a, const int* lda, const float* b, const int* ldb, const float* beta, float* c,
            const int* ldc);
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* b, const int* ldb, const double* beta, double* c,
            const int* ldc);
void openblas_set_num_threads(int num_threads);
char* openblas_get_config();
char* openblas_get_corename();
}
#endif

namespace pamdp {
namespace {

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "gemm: %s\n", what);
  std::abort();
}

#ifdef PAMDP_HAVE_OPENBLAS
// Row block of the a * b products OpenBLAS runs; see gemm().
constexpr Eigen::Index kBlasRowBlock = 16;

// Every process here runs its own threads (actors, a learner, shards); a BLAS that starts one
// worker per core under each of them would oversubscribe the cores and make results depend on
// the split. One thread per call, set once before the first product.
void single_threaded_blas() {
  static std::once_flag once;
  std::call_once(once, [] { openblas_set_num_threads(1); });
}

template <typename Scalar>
void blas_gemm(char ta, char tb, int m, int n, int k, const Scalar* a, int lda, const Scalar* b, int ldb, Scalar beta,
               Scalar* c, int ldc) {
  const Scalar one = 1;
  if constexpr (std::is_same_v<Scalar, float>) {
    sgemm_(&ta, &tb, &m, &n, &k, &one, a, &lda, b, &ldb, &beta, c, &ldc);
  } else {
    dgemm_(&ta, &tb, &m, &n, &k, &one, a, &lda, b, &ldb, &beta, c, &ldc);
  }
}
#endif

template <typename Lhs, typename Rhs, typename Out>
void eigen_gemm(const Lhs& a, const Rhs& b, Out&& c, bool accumulate) {
  if (accumulate) {
    c.noalias() += a * b;
  } else {
    c.noalias() = a * b;
  }
}

#ifdef PAMDP_HAVE_OPENBLAS
// OpenBLAS picks its kernels at load time from a table of CPU models; a model newer than the
// table gets a generic fallback (0.3.21 on an Emerald Rapids VM: its SSE3 "Prescott" kernels, a
// fifth of the speed). Eigen's kernels are compiled for the build machine (-march=native). So
// OpenBLAS runs the products only where the kernels it chose use at least the vector width this
// build was compiled for. Names as openblas_get_corename() spells them, lower-cased.
bool openblas_kernels_match_build() {
  std::string core = openblas_get_corename();
  std::transform(core.begin(), core.end(), core.begin(), [](unsigned char ch) { return std::tolower(ch); });
  const auto one_of = [&](std::initializer_list<const char*> names) {
    return std::any_of(names.begin(), names.end(), [&](const char* name) { return core == name; });
  };
#if defined(EIGEN_VECTORIZE_AVX512)
  return one_of({"skylakex", "cooperlake", "sapphirerapids"});
#elif defined(EIGEN_VECTORIZE_AVX2)
  return one_of({"haswell", "zen", "skylakex", "cooperlake", "sapphirerapids"});
#else
  return true;
#endif
}
#endif

GemmLibrary default_library() {
#ifdef PAMDP_HAVE_OPENBLAS
  return openblas_kernels_match_build() ? GemmLibrary::kOpenBlas : GemmLibrary::kEigen;
#else
  return GemmLibrary::kEigen;
#endif
}

GemmLibrary choose_library() {
  const char* wanted = std::getenv("PAMDP_GEMM");
  if (wanted == nullptr || *wanted == '\0') {
    return default_library();
  }
  const std::string name(wanted);
  if (name == "eigen") {
    return GemmLibrary::kEigen;
  }
  if (name == "openblas" && gemm_library_available(GemmLibrary::kOpenBlas)) {
    return GemmLibrary::kOpenBlas;
  }
  const GemmLibrary fallback = default_library();
  std::fprintf(stderr, "gemm: PAMDP_GEMM=%s %s; using %s. Set it to eigen%s, or unset it for the default.\n", wanted,
               name == "openblas" ? "names a library this build lacks (apt-get install libopenblas-dev, then rebuild)"
                                  : "is not a library of this build",
               fallback == GemmLibrary::kEigen ? "Eigen" : "OpenBLAS",
               gemm_library_available(GemmLibrary::kOpenBlas) ? " or openblas" : "");
  return fallback;
}

}  // namespace

bool gemm_library_available(GemmLibrary library) {
#ifdef PAMDP_HAVE_OPENBLAS
  (void)library;
  return true;
#else
  return library == GemmLibrary::kEigen;
#endif
}

GemmLibrary gemm_library() {
  static const GemmLibrary library = choose_library();
  return library;
}

template <typename Scalar>
void gemm(Op op_a, const ConstMatrixRef<Scalar>& a, Op op_b, const ConstMatrixRef<Scalar>& b, MatrixRef<Scalar> c,
          bool accumulate) {
  gemm_on<Scalar>(gemm_library(), op_a, a, op_b, b, c, accumulate);
}

template <typename Scalar>
void gemm_on(GemmLibrary library, Op op_a, const ConstMatrixRef<Scalar>& a, Op op_b, const ConstMatrixRef<Scalar>& b,
             MatrixRef<Scalar> c, bool accumulate) {
  const bool ta = op_a == Op::kTranspose;
  const bool tb = op_b == Op::kTranspose;
  const Eigen::Index m = ta ? a.cols() : a.rows();
  const Eigen::Index k = ta ? a.rows() : a.cols();
  const Eigen::Index kb = tb ? b.cols() : b.rows();
  const Eigen::Index n = tb ? b.rows() : b.cols();
  if (k != kb || c.rows() != m || c.cols() != n) {
    misuse("shapes do not agree: op(a) is m x k, op(b) k x n, c m x n");
  }
  if (!gemm_library_available(library)) {
    misuse("gemm_on: OpenBLAS is not built in (gemm_library_available)");
  }
  if (m == 0 || n == 0) {
    return;
  }
#ifdef PAMDP_HAVE_OPENBLAS
  if (library == GemmLibrary::kOpenBlas) {
    single_threaded_blas();
    if (k == 0) {
      if (!accumulate) {
        c.setZero();
      }
      return;
    }
    // BLAS wants leading dimensions >= 1 even for one-row operands.
    const auto ld = [](const auto& x) { return static_cast<int>(std::max<Eigen::Index>(1, x.outerStride())); };
    // OpenBLAS 0.3.21's AVX-512 kernels (SkylakeX and newer cores) call malloc on every a * b
    // (no transpose) whose row count ends 1 to 8 rows past a multiple of 16 (float; 1 to 4 past
    // a multiple of 8, double); the transposed variants never do (measured on Sapphire Rapids).
    // So the rows past the last multiple of 16 -- an output layer's few, none of a hidden one's
    // in our presets -- go to Eigen, whose buffers live on the stack.
    const Eigen::Index m_blas = (!ta && !tb) ? m / kBlasRowBlock * kBlasRowBlock : m;
    if (m_blas > 0) {
      blas_gemm<Scalar>(ta ? 'T' : 'N', tb ? 'T' : 'N', static_cast<int>(m_blas), static_cast<int>(n),
                        static_cast<int>(k), a.data(), ld(a), b.data(), ld(b), accumulate ? Scalar(1) : Scalar(0),
                        c.data(), ld(c));
    }
    if (m_blas < m) {
      const Eigen::Index tail = m - m_blas;
      eigen_gemm(a.bottomRows(tail), b, c.bottomRows(tail), accumulate);
    }
    return;
  }
#endif
  if (ta && tb) {
    eigen_gemm(a.transpose(), b.transpose(), c, accumulate);
  } else if (ta) {
    eigen_gemm(a.transpose(), b, c, accumulate);
  } else if (tb) {
    eigen_gemm(a, b.transpose(), c, accumulate);
  } else {
    eigen_gemm(a, b, c, accumulate);
  }
}

std::string gemm_backend() {
  const std::string eigen = "Eigen " + std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
                            "." + std::to_string(EIGEN_MINOR_VERSION);
#ifdef PAMDP_HAVE_OPENBLAS
  if (gemm_library() == GemmLibrary::kOpenBlas) {
    return std::string("OpenBLAS ") + openblas_get_config();
  }
  if (!openblas_kernels_match_build()) {
    return eigen + " (OpenBLAS chose its " + openblas_get_corename() + " kernels, older than this build's)";
  }
#endif
  return eigen;
}

template void gemm<float>(Op, const ConstMatrixRef<float>&, Op, const ConstMatrixRef<float>&, MatrixRef<float>, bool);
template void gemm<double>(Op, const ConstMatrixRef<double>&, Op, const ConstMatrixRef<double>&, MatrixRef<double>,
                           bool);
template void gemm_on<float>(GemmLibrary, Op, const ConstMatrixRef<float>&, Op, const ConstMatrixRef<float>&,
                             MatrixRef<float>, bool);
template void gemm_on<double>(GemmLibrary, Op, const ConstMatrixRef<double>&, Op, const ConstMatrixRef<double>&,
                              MatrixRef<double>, bool);

}  // namespace pamdp
