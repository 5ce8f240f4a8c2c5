// Standard normal draws by the ziggurat method: G. Marsaglia and W. W. Tsang, "The Ziggurat
// Method for Generating Random Variables", Journal of Statistical Software 5(8), 2000, with 256
// layers, in the form of J. A. Doornik, "An Improved Ziggurat Method to Generate Normal Random
// Samples" (2005): u uniform in (-1, 1) and the layer from independent bits, which removes the
// original's correlation between the two.
//
// For simulators whose noise is drawn every tick: most draws cost one 64-bit random word, a
// table look-up and a multiply (about 2 % fall through to an exp or the tail's logs), several
// times cheaper than Rng::normal's Box–Muller (a log, a sqrt and a cos). The stream differs
// from Rng::normal's, so an env picks one and keeps it.
//
// Thread-safe: the tables are built during static initialization (do not draw from another
// translation unit's static initializers); the Rng is the caller's.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "core/rng.hpp"

namespace pamdp {
namespace detail {

struct ZigguratTables {
  std::array<double, 257> x;      // layer edges: x[0] = v / f(r) (the base strip), x[1] = r, x[256] = 0
  std::array<double, 256> ratio;  // x[i + 1] / x[i]: a draw below it is inside layer i's core
};
extern const ZigguratTables kZigguratTables;
// The rare rest of a draw whose first try fell outside its layer's core.
double ziggurat_outside_core(Rng& rng, size_t layer, double u);

}  // namespace detail

inline double ziggurat_normal(Rng& rng) {
  const uint64_t bits = rng.next_u64();
  const auto layer = static_cast<size_t>(bits & 0xFFU);
  // u in (-1, 1) from the top 53 bits, independent of the layer's 8 low bits.
  const double u = 2.0 * (static_cast<double>(bits >> 11U) + 0.5) * 0x1.0p-53 - 1.0;
  if (std::fabs(u) < detail::kZigguratTables.ratio[layer]) {
    return u * detail::kZigguratTables.x[layer];
  }
  return detail::ziggurat_outside_core(rng, layer, u);
}

}  // namespace pamdp
