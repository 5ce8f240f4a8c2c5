// The HFO low-level state features of the paper era (E1/E2), reference §3: 58 values for the
// agent, then 8 per other player. All in [-1, 1]; full state, so every valid flag is +1.
//
// write_features() is the hot path of every env step: no allocation, no atan2 (bearing
// sines and cosines come from unit vectors), a handful of square roots.
#pragma once

#include <span>

#include "envs/hfo/soccer_sim.hpp"

namespace pamdp::hfo {

inline constexpr int kNumAgentFeatures = 58;
inline constexpr int kFeaturesPerPlayer = 8;

// Feature indices used outside this file (reward, scripted policy, tests).
namespace feat {
inline constexpr int kSelfVelAngleSin = 2;
inline constexpr int kSelfVelAngleCos = 3;
inline constexpr int kSelfSpeed = 4;
inline constexpr int kBodySin = 5;
inline constexpr int kBodyCos = 6;
inline constexpr int kStamina = 7;
inline constexpr int kFrozen = 8;
inline constexpr int kCollidedBall = 9;
inline constexpr int kCollidedPlayer = 10;
inline constexpr int kCollidedPost = 11;
inline constexpr int kKickable = 12;
inline constexpr int kGoalCentre = 13;      // sin, cos, proximity
inline constexpr int kGoalPostTop = 16;     // (52.5, -7.01)
inline constexpr int kGoalPostBottom = 19;  // (52.5, +7.01)
inline constexpr int kPenaltyCentre = 22;
inline constexpr int kPenaltyTop = 25;
inline constexpr int kPenaltyBottom = 28;
inline constexpr int kCentreField = 31;
inline constexpr int kCornerTopLeft = 34;
inline constexpr int kCornerTopRight = 37;
inline constexpr int kCornerBottomRight = 40;
inline constexpr int kCornerBottomLeft = 43;
inline constexpr int kOobLeft = 46;
inline constexpr int kOobRight = 47;
inline constexpr int kOobTop = 48;
inline constexpr int kOobBottom = 49;
inline constexpr int kBallPosValid = 50;
inline constexpr int kBallAngleSin = 51;
inline constexpr int kBallAngleCos = 52;
inline constexpr int kBallProximity = 53;
inline constexpr int kBallVelValid = 54;
inline constexpr int kBallSpeed = 55;
inline constexpr int kBallVelAngleSin = 56;
inline constexpr int kBallVelAngleCos = 57;
}  // namespace feat

// Number of features for a state with `num_players` players (the agent included).
constexpr int feature_count(int num_players) {
  return kNumAgentFeatures + kFeaturesPerPlayer * (num_players - 1);
}

// Writes the features of players[self] (the agent: 0): its own 58, then a block for each other
// player, its teammates first, then its opponents, each group nearest first, as HFO's
// LowLevelFeatureExtractor orders them. `out` must hold feature_count(state.num_players) floats.
void write_features(const SoccerState& state, std::span<float> out);
void write_features(const SoccerState& state, int self, std::span<float> out);

// Metres represented by one unit of proximity feature (2 / R = 0.031975 per metre).
double proximity_to_distance(float proximity);

// Read back from a feature vector, in the player's body frame (x ahead, y to the right, as the
// bearings run): the position of the landmark triple (sin, cos, proximity) at `index`, and the
// ball's velocity (its speed and global direction turned by the body angle). For hand-coded
// policies that see only features.
Vec2 body_frame_position(std::span<const float> f, size_t index);
Vec2 ball_velocity_in_body_frame(std::span<const float> f);

}  // namespace pamdp::hfo
