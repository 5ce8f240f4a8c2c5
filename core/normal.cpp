#include "core/normal.hpp"

#include <array>
#include <cmath>
#include <cstdint>

namespace pamdp {
namespace {

constexpr int kLayers = 256;
// The rightmost layer's edge r and the common area v of the 256 layers (Marsaglia & Tsang,
// section 2, for n = 256).
constexpr double kR = 3.6541528853610088;
constexpr double kV = 4.92867323399e-3;

double density(double x) {
  return std::exp(-0.5 * x * x);
}

detail::ZigguratTables make_tables() {
  detail::ZigguratTables t{};
  t.x[0] = kV / density(kR);
  t.x[1] = kR;
  for (size_t i = 2; i < kLayers; ++i) {
    t.x[i] = std::sqrt(-2.0 * std::log(kV / t.x[i - 1] + density(t.x[i - 1])));
  }
  t.x[kLayers] = 0.0;
  for (size_t i = 0; i < kLayers; ++i) {
    t.ratio[i] = t.x[i + 1] / t.x[i];
  }
  return t;
}

// A draw from the tail beyond r (Marsaglia 1964, as in both papers).
double tail(Rng& rng, bool negative) {
  double x = 0.0;
  double y = 0.0;
  do {
    double u1 = rng.uniform();
    double u2 = rng.uniform();
    while (u1 <= 0.0) {
      u1 = rng.uniform();
    }
    while (u2 <= 0.0) {
      u2 = rng.uniform();
    }
    x = std::log(u1) / kR;
    y = std::log(u2);
  } while (-2.0 * y < x * x);
  return negative ? x - kR : kR - x;
}

}  // namespace

namespace detail {

const ZigguratTables kZigguratTables = make_tables();

double ziggurat_outside_core(Rng& rng, size_t layer, double u) {
  const ZigguratTables& t = kZigguratTables;
  for (;;) {
    if (layer == 0) {
      return tail(rng, u < 0.0);
    }
    // In the wedge between the core and the density: accept under the curve.
    const double x = u * t.x[layer];
    const double f0 = std::exp(-0.5 * (t.x[layer] * t.x[layer] - x * x));
    const double f1 = std::exp(-0.5 * (t.x[layer + 1] * t.x[layer + 1] - x * x));
    if (f1 + rng.uniform() * (f0 - f1) < 1.0) {
      return x;
    }
    // Start over, as the first try did.
    const uint64_t bits = rng.next_u64();
    layer = static_cast<size_t>(bits & 0xFFU);
    u = 2.0 * (static_cast<double>(bits >> 11U) + 0.5) * 0x1.0p-53 - 1.0;
    if (std::fabs(u) < t.ratio[layer]) {
      return u * t.x[layer];
    }
  }
}

}  // namespace detail
}  // namespace pamdp
