#include "envs/hfo_server/feature_encoding.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "envs/hfo/features.hpp"
#include "envs/hfo/geometry.hpp"

namespace pamdp::hfo_server {
namespace {

// Re-encodes a proximity with maximum `from_max` as one with maximum `to_max`: recover the
// distance, clamp it to the new maximum. Computed in double; the result is float32 as HFO's.
float reencode(float p, double from_max, double to_max) {
  const double d = (1.0 - static_cast<double>(p)) * 0.5 * from_max;
  return static_cast<float>(1.0 - 2.0 * std::clamp(d / to_max, 0.0, 1.0));
}

}  // namespace

float e3_max_distance() {
  // HFO's FeatureExtractor: float members from ServerParam, then sqrtf.
  const float half_length = 52.5F;
  const float width = 68.0F;
  return std::sqrt(half_length * half_length + width * width);
}

void e3_to_embedded(std::span<const float> e3, int teammates, int opponents, std::span<float> out) {
  const int others = teammates + opponents;
  assert(static_cast<int>(e3.size()) == e3_feature_count(teammates, opponents));
  assert(static_cast<int>(out.size()) == hfo::feature_count(1 + others));
  const double r3 = e3_max_distance();
  const double r1 = hfo::kMaxDistance;

  std::copy(e3.begin(), e3.begin() + kE3BasicFeatures, out.begin());
  const bool self_pos_valid = e3[0] > 0.0F;
  if (self_pos_valid) {
    for (int i = hfo::feat::kGoalCentre + 2; i < hfo::feat::kOobLeft; i += 3) {
      out[i] = reencode(e3[i], r3, r1);
    }
    out[hfo::feat::kOobLeft] = reencode(e3[hfo::feat::kOobLeft], kE3OobLength, hfo::kPitchHalfLength);
    out[hfo::feat::kOobRight] = reencode(e3[hfo::feat::kOobRight], kE3OobLength, hfo::kPitchHalfLength);
    out[hfo::feat::kOobTop] = reencode(e3[hfo::feat::kOobTop], kE3OobWidth, 2.0 * hfo::kPitchHalfWidth);
    out[hfo::feat::kOobBottom] = reencode(e3[hfo::feat::kOobBottom], kE3OobWidth, 2.0 * hfo::kPitchHalfWidth);
    if (e3[hfo::feat::kBallPosValid] > 0.0F) {
      out[hfo::feat::kBallProximity] = reencode(e3[hfo::feat::kBallProximity], r3, r1);
    }
  }

  // Player blocks keep their layout; an empty slot is all zeros in both encodings, and only the
  // uniform-number value (-1 when empty) tells it from a player whose proximity happens to be 0.
  const int unum_base = kE3BasicFeatures + kE3FeaturesPerPlayer * others;
  for (int k = 0; k < others; ++k) {
    const int b = kE3BasicFeatures + kE3FeaturesPerPlayer * k;
    std::copy(e3.begin() + b, e3.begin() + b + kE3FeaturesPerPlayer, out.begin() + b);
    const bool present = e3[unum_base + k] > 0.0F;
    if (present && self_pos_valid) {
      out[b + 2] = reencode(e3[b + 2], r3, r1);
    }
  }
}

}  // namespace pamdp::hfo_server
