#include "core/gemm.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <mutex>
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

}  // namespace

template <typename Scalar>
void gemm(Op op_a, const ConstMatrixRef<Scalar>& a, Op op_b, const ConstMatrixRef<Scalar>& b, MatrixRef<Scalar> c,
          bool accumulate) {
  const bool ta = op_a == Op::kTranspose;
  const bool tb = op_b == Op::kTranspose;
  const Eigen::Index m = ta ? a.cols() : a.rows();
  const Eigen::Index k = ta ? a.rows() : a.cols();
  const Eigen::Index kb = tb ? b.cols() : b.rows();
  const Eigen::Index n = tb ? b.rows() : b.cols();
  if (k != kb || c.rows() != m || c.cols() != n) {
    misuse("shapes do not agree: op(a) is m x k, op(b) k x n, c m x n");
  }
  if (m == 0 || n == 0) {
    return;
  }
#ifdef PAMDP_HAVE_OPENBLAS
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
#else
  if (ta && tb) {
    eigen_gemm(a.transpose(), b.transpose(), c, accumulate);
  } else if (ta) {
    eigen_gemm(a.transpose(), b, c, accumulate);
  } else if (tb) {
    eigen_gemm(a, b.transpose(), c, accumulate);
  } else {
    eigen_gemm(a, b, c, accumulate);
  }
#endif
}

std::string gemm_backend() {
#ifdef PAMDP_HAVE_OPENBLAS
  return std::string("OpenBLAS ") + openblas_get_config();
#else
  return "Eigen " + std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
         std::to_string(EIGEN_MINOR_VERSION);
#endif
}

template void gemm<float>(Op, const ConstMatrixRef<float>&, Op, const ConstMatrixRef<float>&, MatrixRef<float>, bool);
template void gemm<double>(Op, const ConstMatrixRef<double>&, Op, const ConstMatrixRef<double>&, MatrixRef<double>,
                           bool);

}  // namespace pamdp
