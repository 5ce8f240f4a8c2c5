// Mlp (core/mlp.hpp) and the optimizer pieces (core/optim.hpp): gradients against central
// finite differences in double, batching, the actor's two heads, Adam against hand-computed
// steps, clipping, soft updates and the initializer's statistics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "core/gemm.hpp"
#include "core/mlp.hpp"
#include "core/optim.hpp"
#include "core/rng.hpp"

namespace pamdp {
namespace {

using MlpD = Mlp<double>;
using MatrixD = MlpD::Matrix;

MatrixD random_matrix(Rng& rng, int rows, int cols, double std = 1.0) {
  MatrixD m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    m.data()[i] = std * rng.normal();
  }
  return m;
}

// Weights ~ N(0, 0.5^2) and biases ~ N(0, 0.3^2): large enough that every layer matters and
// that non-zero biases make the bias gradients worth checking.
void init_for_check(MlpD& net, Rng& rng) {
  net.init_gaussian(rng, 0.5);
  for (int l = 0; l < net.num_layers(); ++l) {
    auto b = net.bias(l);
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      b[i] = 0.3 * rng.normal();
    }
  }
}

struct Reference {
  MatrixD output;
  double min_abs_hidden_z = INFINITY;  // distance of the closest hidden unit from the kink
  int negative_hidden_z = 0;           // how many units sit on the slope side
};

// Forward pass written out with loops, independent of Mlp's Eigen expressions.
Reference reference_forward(MlpD& net, const MatrixD& x, double slope) {
  Reference r;
  MatrixD a = x;
  for (int l = 0; l < net.num_layers(); ++l) {
    const auto w = net.weight(l);
    const auto b = net.bias(l);
    MatrixD z(w.rows(), a.cols());
    for (Eigen::Index s = 0; s < a.cols(); ++s) {
      for (Eigen::Index o = 0; o < w.rows(); ++o) {
        double sum = b[o];
        for (Eigen::Index i = 0; i < w.cols(); ++i) {
          sum += w(o, i) * a(i, s);
        }
        z(o, s) = sum;
      }
    }
    if (l + 1 == net.num_layers()) {
      r.output = z;
      break;
    }
    for (Eigen::Index i = 0; i < z.size(); ++i) {
      double& v = z.data()[i];
      r.min_abs_hidden_z = std::min(r.min_abs_hidden_z, std::abs(v));
      if (v <= 0.0) {
        ++r.negative_hidden_z;
        v *= slope;
      }
    }
    a = z;
  }
  return r;
}

double loss(MlpD& net, const MatrixD& x, const MatrixD& c) {
  return net.forward(x).cwiseProduct(c).sum();
}

double relative_error(double a, double b) {
  return std::abs(a - b) / std::max(std::abs(a) + std::abs(b), 1e-2);
}

constexpr double kStep = 1e-6;
// Central differences in double on a piecewise-smooth loss: truncation ~ kStep^2, rounding
// ~ 1e-16 / kStep, both far below this.
constexpr double kGradTolerance = 1e-6;
// A hidden unit closer than this to z = 0 could cross the kink under a kStep perturbation.
constexpr double kKinkMargin = 1e-3;

// Checks every parameter gradient and (if want_input) every input gradient of
// L = sum(c .* net(x)) against central differences.
void expect_gradients_match(MlpD& net, const MatrixD& x, const MatrixD& c, bool want_input) {
  const Reference ref = reference_forward(net, x, 0.01);
  ASSERT_GT(ref.min_abs_hidden_z, kKinkMargin) << "pick another seed: a unit sits on the kink";
  ASSERT_GT(ref.negative_hidden_z, 0) << "the slope side of the leaky ReLU would go untested";

  net.forward(x);
  net.backward(c, want_input);
  const std::vector<double> grads(net.grads().begin(), net.grads().end());
  const MatrixD input_grad = net.input_grad();

  auto params = net.params();
  int64_t offset = 0;
  for (int l = 0; l < net.num_layers(); ++l) {
    const int64_t count = static_cast<int64_t>(net.widths()[l + 1]) * (net.widths()[l] + 1);
    const int64_t weights = static_cast<int64_t>(net.widths()[l + 1]) * net.widths()[l];
    for (int64_t i = offset; i < offset + count; ++i) {
      const double saved = params[i];
      params[i] = saved + kStep;
      const double up = loss(net, x, c);
      params[i] = saved - kStep;
      const double down = loss(net, x, c);
      params[i] = saved;
      const double numeric = (up - down) / (2 * kStep);
      EXPECT_LT(relative_error(grads[i], numeric), kGradTolerance)
          << "layer " << l << (i - offset < weights ? " weight " : " bias ") << (i - offset) << ": analytic "
          << grads[i] << " numeric " << numeric;
    }
    offset += count;
  }
  ASSERT_EQ(offset, net.num_params());

  if (want_input) {
    MatrixD xp = x;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      xp.data()[i] = x.data()[i] + kStep;
      const double up = loss(net, xp, c);
      xp.data()[i] = x.data()[i] - kStep;
      const double down = loss(net, xp, c);
      xp.data()[i] = x.data()[i];
      const double numeric = (up - down) / (2 * kStep);
      EXPECT_LT(relative_error(input_grad.data()[i], numeric), kGradTolerance)
          << "input " << i << ": analytic " << input_grad.data()[i] << " numeric " << numeric;
    }
  }
}

TEST(Mlp, LayoutAndShapes) {
  MlpD net({5, 7, 6, 4}, 3);
  EXPECT_EQ(net.num_layers(), 3);
  EXPECT_EQ(net.input_width(), 5);
  EXPECT_EQ(net.output_width(), 4);
  EXPECT_EQ(net.num_params(), 7 * 5 + 7 + 6 * 7 + 6 + 4 * 6 + 4);
  // W of layer 1 starts after layer 0's W (7 x 5) and b (7); column-major, so (1, 0) is the
  // next element and (0, 1) is 6 further; its b follows its 6 x 7 W.
  const double* w1 = net.params().data() + 42;
  EXPECT_EQ(&net.weight(1)(0, 0), w1);
  EXPECT_EQ(&net.weight(1)(1, 0), w1 + 1);
  EXPECT_EQ(&net.weight(1)(0, 1), w1 + 6);
  EXPECT_EQ(net.bias(1).data(), w1 + 42);
  EXPECT_EQ(net.bias(2).data() + 4, net.params().data() + net.num_params());
}

TEST(Mlp, RejectsBadConstruction) {
  EXPECT_THROW(MlpD({5}, 1), std::invalid_argument);
  EXPECT_THROW(MlpD({5, 0, 3}, 1), std::invalid_argument);
  EXPECT_THROW(MlpD({5, 3}, 0), std::invalid_argument);
  EXPECT_THROW(MlpD({5, 3}, 1, -0.1), std::invalid_argument);
}

TEST(MlpDeathTest, BatchOverMaxBatchAborts) {
  MlpD net({5, 3}, 2);
  const MatrixD x = MatrixD::Zero(5, 3);
  EXPECT_DEATH(net.forward(x), "max_batch");
}

TEST(MlpDeathTest, BackwardWithOtherBatchAborts) {
  MlpD net({5, 3}, 4);
  net.forward(MatrixD::Zero(5, 2));
  EXPECT_DEATH(net.backward(MatrixD::Zero(3, 3), false), "d_output");
}

TEST(Mlp, ForwardMatchesLoopReference) {
  Rng rng(11);
  MlpD net({5, 7, 6, 4}, 3);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 5, 3);
  const Reference ref = reference_forward(net, x, 0.01);
  const MatrixD y = net.forward(x);
  ASSERT_EQ(y.rows(), 4);
  ASSERT_EQ(y.cols(), 3);
  EXPECT_GT(ref.negative_hidden_z, 0);
  EXPECT_LT((y - ref.output).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(MatrixD(net.output()), y);
}

TEST(Mlp, GradientsMatchFiniteDifferences) {
  Rng rng(1);
  MlpD net({5, 7, 6, 4}, 1);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 5, 1);
  const MatrixD c = random_matrix(rng, 4, 1);
  expect_gradients_match(net, x, c, /*want_input=*/true);
}

// Inputs wider than 8 and not a multiple of it: the batch-1 forward's eight-column kernel and
// its tail both run.
TEST(Mlp, WideLayerGradientsMatchFiniteDifferences) {
  Rng rng(12);
  MlpD net({19, 17, 10}, 1);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 19, 1);
  const MatrixD c = random_matrix(rng, 10, 1);
  expect_gradients_match(net, x, c, /*want_input=*/true);
}

TEST(Mlp, BatchOneForwardMatchesBatchedAndReference) {
  // Batch 1 takes its own matrix-vector kernel; larger batches take Eigen's product.
  Rng rng(13);
  MlpD net({58, 64, 32, 10}, 5);
  net.init_gaussian(rng, 0.2);
  const MatrixD x = random_matrix(rng, 58, 5);
  const MatrixD batched = net.forward(x);
  const Reference ref = reference_forward(net, x, 0.01);
  EXPECT_LT((batched - ref.output).cwiseAbs().maxCoeff(), 1e-12);
  for (int s = 0; s < 5; ++s) {
    const MatrixD single = net.forward(x.col(s));
    EXPECT_LT((single - ref.output.col(s)).cwiseAbs().maxCoeff(), 1e-12) << "sample " << s;
  }
}

TEST(Mlp, BatchGradientsMatchFiniteDifferences) {
  Rng rng(2);
  MlpD net({5, 7, 6, 4}, 3);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 5, 3);
  const MatrixD c = random_matrix(rng, 4, 3);
  expect_gradients_match(net, x, c, /*want_input=*/true);
}

TEST(Mlp, SingleLayerGradientsMatchFiniteDifferences) {
  Rng rng(3);
  MlpD net({5, 4}, 2);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 5, 2);
  const MatrixD c = random_matrix(rng, 4, 2);
  net.forward(x);
  net.backward(c, true);
  // Linear: dW = c x^T, db = row sums of c, dx = W^T c, exactly.
  const MatrixD dw = c * x.transpose();
  const Eigen::VectorXd db = c.rowwise().sum();
  const MatrixD dx = MatrixD(net.weight(0)).transpose() * c;
  for (Eigen::Index i = 0; i < dw.size(); ++i) {
    EXPECT_NEAR(net.grads()[i], dw.data()[i], 1e-12);
  }
  for (Eigen::Index i = 0; i < db.size(); ++i) {
    EXPECT_NEAR(net.grads()[dw.size() + i], db[i], 1e-12);
  }
  EXPECT_LT((net.input_grad() - dx).cwiseAbs().maxCoeff(), 1e-12);
}

// The actor's output is the two heads stacked (ActorHeads); a loss on one head must
// back-propagate exactly as through that head alone.
TEST(Mlp, ActorHeadsGradientsMatchFiniteDifferences) {
  const ActorHeads heads;
  Rng rng(4);
  MlpD net({6, 9, 8, heads.width()}, 2);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 6, 2);
  const MatrixD c = random_matrix(rng, heads.width(), 2);

  MatrixD scores_only = MatrixD::Zero(heads.width(), 2);
  scores_only.topRows(heads.num_actions) = c.topRows(heads.num_actions);
  expect_gradients_match(net, x, scores_only, /*want_input=*/true);
  // No gradient reaches the parameter head's output weights or biases.
  net.forward(x);
  net.backward(scores_only, false);
  const int last = net.num_layers() - 1;
  const int64_t out_w = net.bias(last).data() - net.weight(last).data();
  const int64_t w_offset = net.weight(last).data() - net.params().data();
  for (int o = heads.num_actions; o < heads.width(); ++o) {
    for (int i = 0; i < net.widths()[last]; ++i) {
      EXPECT_EQ(net.grads()[w_offset + static_cast<int64_t>(i) * heads.width() + o], 0.0);
    }
    EXPECT_EQ(net.grads()[w_offset + out_w + o], 0.0);
  }

  MatrixD params_only = MatrixD::Zero(heads.width(), 2);
  params_only.bottomRows(heads.num_params) = c.bottomRows(heads.num_params);
  expect_gradients_match(net, x, params_only, /*want_input=*/true);
}

TEST(Mlp, BatchGradientIsSumOfPerSampleGradients) {
  Rng rng(5);
  MlpD net({5, 7, 6, 4}, 4);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 5, 4);
  const MatrixD c = random_matrix(rng, 4, 4);

  std::vector<double> sum(static_cast<size_t>(net.num_params()), 0.0);
  MatrixD outputs(4, 4);
  MatrixD input_grads(5, 4);
  for (int s = 0; s < 4; ++s) {
    outputs.col(s) = net.forward(x.col(s));
    net.backward(c.col(s), true);
    input_grads.col(s) = net.input_grad();
    for (size_t i = 0; i < sum.size(); ++i) {
      sum[i] += net.grads()[i];
    }
  }
  const MatrixD batched = net.forward(x);
  net.backward(c, true);
  EXPECT_LT((batched - outputs).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((net.input_grad() - input_grads).cwiseAbs().maxCoeff(), 1e-12);
  for (size_t i = 0; i < sum.size(); ++i) {
    EXPECT_NEAR(net.grads()[i], sum[i], 1e-12) << "param " << i;
  }
}

TEST(Mlp, BackwardVariantsAgree) {
  Rng rng(6);
  MlpD net({5, 7, 6, 4}, 2);
  init_for_check(net, rng);
  const MatrixD x = random_matrix(rng, 5, 2);
  const MatrixD c = random_matrix(rng, 4, 2);
  net.forward(x);
  net.backward(c, true);
  const std::vector<double> first(net.grads().begin(), net.grads().end());
  const MatrixD input_grad = net.input_grad();
  net.backward(c, false);
  const std::vector<double> second(net.grads().begin(), net.grads().end());
  EXPECT_EQ(first, second);

  // backward_input: the same input gradient, parameter gradients left alone.
  std::fill(net.grads().begin(), net.grads().end(), 7.0);
  net.backward_input(c);
  EXPECT_EQ(MatrixD(net.input_grad()), input_grad);
  EXPECT_TRUE(std::all_of(net.grads().begin(), net.grads().end(), [](double g) { return g == 7.0; }));
}

TEST(Mlp, FloatAndDoubleForwardAgree) {
  Rng rng(7);
  MlpD net_d({58, 64, 32, 10}, 8);
  net_d.init_gaussian(rng, 0.2);
  Mlp<float> net_f({58, 64, 32, 10}, 8);
  std::transform(net_d.params().begin(), net_d.params().end(), net_f.params().begin(),
                 [](double v) { return static_cast<float>(v); });
  const MatrixD x = random_matrix(rng, 58, 8);
  const MatrixD y_d = net_d.forward(x);
  const Eigen::MatrixXf y_f = net_f.forward(x.cast<float>());
  const double scale = y_d.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.1);
  EXPECT_LT((y_f.cast<double>() - y_d).cwiseAbs().maxCoeff(), 1e-5 * scale);
  // And through the batch-1 kernel.
  const Eigen::MatrixXf y1_f = net_f.forward(x.col(3).cast<float>());
  EXPECT_LT((y1_f.cast<double>() - y_d.col(3)).cwiseAbs().maxCoeff(), 1e-5 * scale);
}

TEST(Mlp, InitGaussianStatistics) {
  Rng rng(8);
  Mlp<float> actor({58, 1024, 512, 256, 128, 10}, 1);
  actor.init_gaussian(rng, 0.01F);
  double sum = 0.0;
  double sum_sq = 0.0;
  int64_t n = 0;
  for (int l = 0; l < actor.num_layers(); ++l) {
    const auto w = actor.weight(l);
    for (Eigen::Index i = 0; i < w.size(); ++i) {
      sum += w.data()[i];
      sum_sq += static_cast<double>(w.data()[i]) * w.data()[i];
    }
    n += w.size();
    EXPECT_TRUE((actor.bias(l).array() == 0.0F).all()) << "layer " << l;
  }
  const double mean = sum / static_cast<double>(n);
  const double std = std::sqrt(sum_sq / static_cast<double>(n) - mean * mean);
  // n ~ 749k: the mean's standard error is 0.01 / sqrt(n) ~ 1.2e-5 and the std's relative
  // standard error 1 / sqrt(2n) ~ 8e-4; both tolerances are about 5 standard errors.
  EXPECT_NEAR(mean, 0.0, 6e-5);
  EXPECT_NEAR(std, 0.01, 0.01 * 4e-3);

  // Same seed, same network.
  Rng again(8);
  Mlp<float> copy({58, 1024, 512, 256, 128, 10}, 1);
  copy.init_gaussian(again, 0.01F);
  EXPECT_TRUE(std::equal(copy.params().begin(), copy.params().end(), actor.params().begin()));
}

TEST(Mlp, InitGaussianOutputLayerOverride) {
  Rng rng(9);
  MlpD net({300, 100, 400}, 1);
  net.init_gaussian(rng, 0.01, 0.05, 1.0);
  const auto hidden = net.weight(0);
  const auto out = net.weight(1);
  const double hidden_std = std::sqrt(hidden.array().square().mean());
  const double out_std = std::sqrt(out.array().square().mean());
  // 30k and 40k draws: relative standard error of the std ~ 0.4%; tolerance ~ 5 of those.
  EXPECT_NEAR(hidden_std, 0.01, 0.01 * 0.02);
  EXPECT_NEAR(out_std, 0.05, 0.05 * 0.02);
  EXPECT_TRUE((net.bias(0).array() == 0.0).all());
  EXPECT_TRUE((net.bias(1).array() == 1.0).all());
}

TEST(Adam, DefaultsAreThePaperCodes) {
  const AdamConfig config;
  EXPECT_EQ(config.learning_rate, 1e-3);
  EXPECT_EQ(config.beta1, 0.95);
  EXPECT_EQ(config.beta2, 0.999);
  EXPECT_EQ(config.epsilon, 1e-8);
}

TEST(Adam, MatchesHandComputedCaffeSteps) {
  // lr = 0.01, b1 = 0.9, b2 = 0.99, eps = 1e-8; theta = (1, -2).
  // Step 1, g = (0.5, -1):
  //   m = 0.1 g = (0.05, -0.1);  v = 0.01 g^2 = (0.0025, 0.01);  sqrt(v) = (0.05, 0.1)
  //   step size = 0.01 * sqrt(1 - 0.99) / (1 - 0.9) = 0.01 * 0.1 / 0.1 = 0.01
  //   theta0 = 1 - 0.01 * 0.05 / (0.05 + 1e-8) = 1 - 0.01 * 0.9999998 = 0.990000002
  //   theta1 = -2 - 0.01 * (-0.1) / (0.1 + 1e-8) = -2 + 0.009999999 = -1.990000001
  // Step 2, g = (-0.25, 2):
  //   m = 0.9 (0.05, -0.1) + 0.1 (-0.25, 2) = (0.02, 0.11)
  //   v = 0.99 (0.0025, 0.01) + 0.01 (0.0625, 4) = (0.0031, 0.0499)
  //   sqrt(v) = (0.0556776436283, 0.223383079037)
  //   step size = 0.01 * sqrt(1 - 0.9801) / (1 - 0.81) = 0.01 * 0.141067359797 / 0.19
  //             = 0.00742459788403
  //   theta0 = 0.990000002 - 0.00742459788403 * 0.02 / 0.0556776536283 = 0.987333008188
  //   theta1 = -1.990000001 - 0.00742459788403 * 0.11 / 0.223383089037 = -1.99365607797
  const AdamConfig config{.learning_rate = 0.01, .beta1 = 0.9, .beta2 = 0.99, .epsilon = 1e-8};
  Adam<double> adam(2, config);
  std::vector<double> theta{1.0, -2.0};
  adam.step(theta, std::vector<double>{0.5, -1.0});
  EXPECT_EQ(adam.steps(), 1);
  EXPECT_NEAR(theta[0], 0.990000002, 1e-12);
  EXPECT_NEAR(theta[1], -1.990000001, 1e-12);
  adam.step(theta, std::vector<double>{-0.25, 2.0});
  EXPECT_EQ(adam.steps(), 2);
  EXPECT_NEAR(theta[0], 0.987333008188, 1e-11);
  EXPECT_NEAR(theta[1], -1.99365607797, 1e-11);
  EXPECT_NEAR(adam.first_moment()[1], 0.11, 1e-15);
  EXPECT_NEAR(adam.second_moment()[0], 0.0031, 1e-15);

  // The float version follows the same arithmetic.
  Adam<float> adam_f(2, config);
  std::vector<float> theta_f{1.0F, -2.0F};
  adam_f.step(theta_f, std::vector<float>{0.5F, -1.0F});
  adam_f.step(theta_f, std::vector<float>{-0.25F, 2.0F});
  EXPECT_NEAR(theta_f[0], 0.987333008188, 1e-6);
  EXPECT_NEAR(theta_f[1], -1.99365607797, 1e-6);
}

TEST(Adam, RestoredStepCountSetsBiasCorrection) {
  // After set_steps(1) the next step is t = 2: with m = v = 0 and g = 1,
  // m = 0.1, v = 0.01, update = lr * sqrt(1 - 0.99^2) / (1 - 0.9^2) * 0.1 / (0.1 + eps).
  const AdamConfig config{.learning_rate = 0.01, .beta1 = 0.9, .beta2 = 0.99, .epsilon = 1e-8};
  Adam<double> adam(1, config);
  adam.set_steps(1);
  std::vector<double> theta{0.0};
  adam.step(theta, std::vector<double>{1.0});
  EXPECT_NEAR(theta[0], -0.01 * std::sqrt(1 - 0.9801) / 0.19 * 0.1 / (0.1 + 1e-8), 1e-15);
}

TEST(Optim, ClipGlobalNorm) {
  std::vector<float> g{3.0F, 4.0F};
  EXPECT_DOUBLE_EQ(global_norm(std::span<const float>(g)), 5.0);
  EXPECT_DOUBLE_EQ(global_norm(std::span<float>(g)), 5.0);
  EXPECT_DOUBLE_EQ(clip_global_norm(std::span<float>(g), 10.0), 5.0);
  EXPECT_EQ(g, (std::vector<float>{3.0F, 4.0F}));
  EXPECT_DOUBLE_EQ(clip_global_norm(std::span<float>(g), 0.0), 5.0);
  EXPECT_EQ(g, (std::vector<float>{3.0F, 4.0F}));
  EXPECT_DOUBLE_EQ(clip_global_norm(std::span<float>(g), 1.0), 5.0);
  EXPECT_FLOAT_EQ(g[0], 0.6F);
  EXPECT_FLOAT_EQ(g[1], 0.8F);

  std::vector<double> d{3.0, 4.0};
  EXPECT_DOUBLE_EQ(clip_global_norm(std::span<double>(d), 1.0), 5.0);
  EXPECT_DOUBLE_EQ(d[0], 0.6);
  EXPECT_DOUBLE_EQ(d[1], 0.8);
}

TEST(Optim, GlobalNormOfLongVectorWithRemainder) {
  // 1003 = 31 * 32 + 11 exercises both the lanes and the tail; sum of k^2 for k = 1..n is
  // n (n + 1) (2n + 1) / 6.
  std::vector<float> v(1003);
  for (size_t k = 0; k < v.size(); ++k) {
    v[k] = static_cast<float>(k + 1);
  }
  EXPECT_DOUBLE_EQ(global_norm(std::span<const float>(v)), std::sqrt(1003.0 * 1004.0 * 2007.0 / 6.0));
  EXPECT_EQ(global_norm(std::span<const float>()), 0.0);
}

TEST(Optim, SoftUpdate) {
  std::vector<float> target{1.0F, 2.0F};
  std::vector<float> source{3.0F, 6.0F};
  // 0.25 * 3 + 0.75 * 1 = 1.5 and 0.25 * 6 + 0.75 * 2 = 3, exact in binary.
  soft_update(std::span<float>(target), std::span<float>(source), 0.25);
  EXPECT_EQ(target, (std::vector<float>{1.5F, 3.0F}));
  soft_update(std::span<float>(target), std::span<const float>(source), 0.0);
  EXPECT_EQ(target, (std::vector<float>{1.5F, 3.0F}));
  soft_update(std::span<float>(target), std::span<const float>(source), 1.0);
  EXPECT_EQ(target, source);

  // Between two networks, as the learner does it.
  Rng rng(10);
  Mlp<double> online({3, 4, 2}, 1);
  Mlp<double> target_net({3, 4, 2}, 1);
  online.init_gaussian(rng, 1.0);
  target_net.init_gaussian(rng, 1.0);
  const std::vector<double> before(target_net.params().begin(), target_net.params().end());
  soft_update(target_net.params(), online.params(), 1e-3);
  for (size_t i = 0; i < before.size(); ++i) {
    EXPECT_DOUBLE_EQ(target_net.params()[i], 1e-3 * online.params()[i] + (1 - 1e-3) * before[i]);
  }
}

// gemm against a plain triple loop in double, for every transpose combination, written and
// accumulated, on blocks of larger matrices (leading dimension > rows), including a one-row
// operand, a batch of one and a shape large enough for any library's blocked kernels.
template <typename Scalar>
void check_gemm(GemmLibrary library, Op op_a, Op op_b, int m, int n, int k, bool accumulate) {
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  Rng rng(static_cast<uint64_t>(m * 131 + n * 17 + k));
  auto random = [&](int rows, int cols) {
    Matrix x(rows, cols);
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      x.data()[i] = static_cast<Scalar>(rng.uniform(-1.0, 1.0));
    }
    return x;
  };
  const bool ta = op_a == Op::kTranspose;
  const bool tb = op_b == Op::kTranspose;
  const Matrix a_store = random((ta ? k : m) + 3, ta ? m : k);
  const Matrix b_store = random((tb ? n : k) + 2, tb ? k : n);
  Matrix c_store = random(m + 5, n);
  const Matrix c_before = c_store;
  const auto a = a_store.topRows(ta ? k : m);
  const auto b = b_store.topRows(tb ? n : k);
  gemm_on<Scalar>(library, op_a, a, op_b, b, c_store.topRows(m), accumulate);
  double worst = 0.0;
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < n; ++j) {
      double want = accumulate ? static_cast<double>(c_before(i, j)) : 0.0;
      for (int p = 0; p < k; ++p) {
        want += static_cast<double>(ta ? a(p, i) : a(i, p)) * static_cast<double>(tb ? b(j, p) : b(p, j));
      }
      worst = std::max(worst, std::abs(static_cast<double>(c_store(i, j)) - want));
    }
  }
  // Float sums of up to 300 products of magnitude <= 1: rounding well under 1e-4.
  const double tolerance = std::is_same_v<Scalar, float> ? 1e-4 : 1e-12;
  EXPECT_LT(worst, tolerance) << "library " << static_cast<int>(library) << " op_a " << ta << " op_b " << tb << " " << m
                              << "x" << n << "x" << k << " accumulate " << accumulate;
  // Rows below the block are untouched.
  EXPECT_TRUE((c_store.bottomRows(5).array() == c_before.bottomRows(5).array()).all());
}

TEST(Gemm, AgreesWithALoopForEveryTransposeOnBlocks) {
  for (const GemmLibrary library : {GemmLibrary::kEigen, GemmLibrary::kOpenBlas}) {
    if (!gemm_library_available(library)) {
      continue;
    }
    for (const Op op_a : {Op::kNone, Op::kTranspose}) {
      for (const Op op_b : {Op::kNone, Op::kTranspose}) {
        for (const bool accumulate : {false, true}) {
          check_gemm<float>(library, op_a, op_b, 70, 32, 300, accumulate);
          check_gemm<float>(library, op_a, op_b, 1, 32, 64, accumulate);
          check_gemm<float>(library, op_a, op_b, 10, 1, 5, accumulate);
          check_gemm<float>(library, op_a, op_b, 16, 32, 64, accumulate);  // a whole row block, no tail
          check_gemm<float>(library, op_a, op_b, 24, 32, 64, accumulate);  // a block and an 8-row tail
          check_gemm<double>(library, op_a, op_b, 33, 7, 129, accumulate);
        }
      }
    }
  }
  EXPECT_TRUE(gemm_library_available(GemmLibrary::kEigen));  // so the loop checked at least one
  EXPECT_FALSE(gemm_backend().empty());
}

// PAMDP_GEMM picks the library at gemm()'s first call; each case runs in a fresh process
// (threadsafe death tests re-execute the binary), so the choice is not already made.
void expect_choice(const char* value, GemmLibrary want) {
  setenv("PAMDP_GEMM", value, 1);
  std::exit(gemm_library() == want ? 0 : 1);
}

TEST(GemmDeathTest, TheEnvironmentChoosesTheLibrary) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(expect_choice("eigen", GemmLibrary::kEigen), testing::ExitedWithCode(0), "");
  EXPECT_EXIT(
      {
        setenv("PAMDP_GEMM", "eigen", 1);
        std::fprintf(stderr, "%s\n", gemm_backend().c_str());
        std::exit(0);
      },
      testing::ExitedWithCode(0), "^Eigen [0-9]");
  if (gemm_library_available(GemmLibrary::kOpenBlas)) {
    EXPECT_EXIT(expect_choice("openblas", GemmLibrary::kOpenBlas), testing::ExitedWithCode(0), "");
  }
  // A wrong value is named with the fix, and the build's default is kept.
  EXPECT_EXIT(
      {
        setenv("PAMDP_GEMM", "mkl", 1);
        std::exit(gemm_library_available(gemm_library()) ? 0 : 1);
      },
      testing::ExitedWithCode(0),
      "PAMDP_GEMM=mkl is not a library of this build; using (Eigen|OpenBLAS).*Set it to eigen");
}

TEST(GemmDeathTest, ShapesThatDoNotAgreeAbort) {
  const Eigen::MatrixXf a = Eigen::MatrixXf::Ones(3, 4);
  const Eigen::MatrixXf b = Eigen::MatrixXf::Ones(5, 2);
  Eigen::MatrixXf c(3, 2);
  EXPECT_DEATH(gemm<float>(Op::kNone, a, Op::kNone, b, c, false), "shapes do not agree");
}

}  // namespace
}  // namespace pamdp
