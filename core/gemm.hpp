// General matrix products for the MLP: c = op(a) * op(b), or c += op(a) * op(b), on
// column-major Eigen storage. Where CMake found OpenBLAS (PAMDP_BLAS, on by default) the
// products run on its sgemm/dgemm, single-threaded; otherwise on Eigen's. Why OpenBLAS: on
// the reference machine (Zen 3, AVX2) its kernels reach ~94 GFLOP/s on a 2048^3 float product
// and ~74 GFLOP/s on a paper layer at batch 32, against Eigen's ~66 and ~55 (docs/learning.md).
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

template <typename Scalar>
using MatrixRef = Eigen::Ref<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>;
template <typename Scalar>
using ConstMatrixRef = Eigen::Ref<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>;

// c = op_a(a) * op_b(b) when accumulate is false (c is written, never read), c += ... when true.
template <typename Scalar>
void gemm(Op op_a, const ConstMatrixRef<Scalar>& a, Op op_b, const ConstMatrixRef<Scalar>& b, MatrixRef<Scalar> c,
          bool accumulate);

// What runs the products: "OpenBLAS <version and core>" or "Eigen <version>", for benchmark
// labels and logs.
std::string gemm_backend();

extern template void gemm<float>(Op, const ConstMatrixRef<float>&, Op, const ConstMatrixRef<float>&, MatrixRef<float>,
                                 bool);
extern template void gemm<double>(Op, const ConstMatrixRef<double>&, Op, const ConstMatrixRef<double>&,
                                  MatrixRef<double>, bool);

}  // namespace pamdp
