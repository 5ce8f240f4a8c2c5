// The real HFO server's low-level features (current HFO, "E3", shared/hfo-reference.md §3.4)
// and their exact conversion to the embedded simulator's encoding (E1/E2, §3.2–§3.3), so that an
// agent trained in-process can be evaluated on the real server. Pure functions: no HFO needed,
// compiled in every build.
//
// E3 for T teammates and O opponents, as HFO's lowlevel_feature_extractor.cpp writes it:
//   [0, 58)              the same 58 basic values as E1/E2, but every landmark, ball and player
//                        proximity normalized by R3 = sqrt(52.5^2 + 68^2) = 85.908 (E1/E2:
//                        R1 = sqrt(52.5^2 + 34^2) = 62.548) and the out-of-bounds proximities by
//                        1.1 * 52.5 = 57.75 (left, right) and 1.05 * 68 = 71.4 (top, bottom)
//                        (E1/E2: 52.5 and 68);
//   58 + 8k, k < T + O   the same 8-value player blocks (proximity by R3);
//   then T + O           uniform numbers, unum / 100 (-1 for an empty slot);
//   last                 +1 / -1: whether the last command was accepted.
// Every other normalizer (self speed 0.46, stamina 8000, ball speed 5.0, player speed 0.75) and
// every sin/cos convention is the same in both encodings.
//
// A proximity p with maximum M encodes the distance d = (1 - p) * M / 2 (p = 1 - 2 clamp(d/M,
// 0, 1)); re-encoding with another maximum is exact except where a distance saturated, and the
// E3 maxima are the larger ones, so a value saturated in E3 is saturated in E1/E2 as well.
// With --fullstate every valid flag is +1; a value HFO zeroed because its valid flag is -1
// (and an empty player slot, all zeros) stays zero.
#pragma once

#include <span>

namespace pamdp::hfo_server {

inline constexpr int kE3BasicFeatures = 58;  // before the player blocks, as in E1/E2
inline constexpr int kE3FeaturesPerPlayer = 8;

// Feature count of current HFO: 59 in 1v0, 68 with one opponent (59 + 9 per other player).
constexpr int e3_feature_count(int teammates, int opponents) {
  return kE3BasicFeatures + (kE3FeaturesPerPlayer + 1) * (teammates + opponents) + 1;
}

// The E3 normalizers, as HFO computes them (float32).
float e3_max_distance();                             // sqrtf(52.5^2 + 68^2) = 85.90838
inline constexpr float kE3OobLength = 1.1F * 52.5F;  // 57.75
inline constexpr float kE3OobWidth = 1.05F * 68.0F;  // 71.4

// Writes the E1/E2 encoding of `e3` into `out`. `e3` must hold e3_feature_count(T, O) values and
// `out` hfo::feature_count(1 + T + O). No allocation.
void e3_to_embedded(std::span<const float> e3, int teammates, int opponents, std::span<float> out);

// Index of the "last command accepted" flag in an E3 vector.
constexpr int e3_last_action_index(int teammates, int opponents) {
  return e3_feature_count(teammates, opponents) - 1;
}

}  // namespace pamdp::hfo_server
