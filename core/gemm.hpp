// General matrix products for the MLP: c = op(a) * op(b), or c += op(a) * op(b), on
// column-major Eigen storage, run by one of two libraries (GemmLibrary), single-threaded.
// OpenBLAS where CMake found it (PAMDP_BLAS, on by default): on the reference machine (Zen 3,
// AVX2) its kernels reach ~94 GFLOP/s on a 2048^3 float product and ~74 GFLOP/s on a paper
// layer at batch 32, against Eigen's ~66 and ~55 (docs/learning.md). But OpenBLAS picks its
// kernels at run time from a table of CPU models, and on a CPU newer than its table it falls
// back to generic ones (OpenBLAS 0.3.21 on Emerald Rapids: SSE3, a quarter of Eigen's rate);
// Eigen's are compiled for the build machine. So gemm() runs on OpenBLAS only where the kernels
// it chose are as wide as this build's vectors (AVX2, AVX-512), on Eigen otherwise.
//
// Not a general BLAS binding: only what Mlp needs. Shapes that do not agree are a bug in the
// caller and abort (an Eigen assertion would vanish under NDEBUG). Allocates nothing per call
// after the first (OpenBLAS keeps its packing buffers; Eigen's live on the stack, see
// core/CMakeLists.txt; the rows of an untransposed product past a multiple of 16 run on Eigen,
// because OpenBLAS's AVX-512 kernels allocate for them). Safe to call from several threads at
// once.
#pragma once

#include <Eigen/Core>
#include <string>

namespace pamdp {

enum class Op { kNone, kTranspose };

enum class GemmLibrary { kEigen, kOpenBlas };

template <typename Scalar>
using MatrixRef = Eigen::Ref<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>;
template <typename Scalar>
using ConstMatrixRef = Eigen::Ref<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>;

// c = op_a(a) * op_b(b) when accumulate is false (c is written, never read), c += ... when true,
// on gemm_library().
template <typename Scalar>
void gemm(Op op_a, const ConstMatrixRef<Scalar>& a, Op op_b, const ConstMatrixRef<Scalar>& b, MatrixRef<Scalar> c,
          bool accumulate);

// The same on a given library, which must be available (tests and benchmarks compare them).
template <typename Scalar>
void gemm_on(GemmLibrary library, Op op_a, const ConstMatrixRef<Scalar>& a, Op op_b, const ConstMatrixRef<Scalar>& b,
             MatrixRef<Scalar> c, bool accumulate);

// Whether this build has the library (Eigen always; OpenBLAS where CMake found it).
bool gemm_library_available(GemmLibrary library);

// The library gemm() uses, chosen at its first call and kept for the process: PAMDP_GEMM=eigen
// or PAMDP_GEMM=openblas in the environment where set (a value that is neither, or openblas
// where it is not built in, is reported on stderr once and the default kept); otherwise the
// rule above.
GemmLibrary gemm_library();

// What runs gemm()'s products: "OpenBLAS <version and core>" or "Eigen <version>" (with the
// kernels OpenBLAS chose, where the rule passed them over), for benchmark labels and logs.
std::string gemm_backend();

extern template void gemm<float>(Op, const ConstMatrixRef<float>&, Op, const ConstMatrixRef<float>&, MatrixRef<float>,
                                 bool);
extern template void gemm<double>(Op, const ConstMatrixRef<double>&, Op, const ConstMatrixRef<double>&,
                                  MatrixRef<double>, bool);
extern template void gemm_on<float>(GemmLibrary, Op, const ConstMatrixRef<float>&, Op, const ConstMatrixRef<float>&,
                                    MatrixRef<float>, bool);
extern template void gemm_on<double>(GemmLibrary, Op, const ConstMatrixRef<double>&, Op, const ConstMatrixRef<double>&,
                                     MatrixRef<double>, bool);

}  // namespace pamdp
