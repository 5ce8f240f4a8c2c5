#include "envs/hfo/features.hpp"

#include <algorithm>
#include <cassert>

namespace pamdp::hfo {
namespace {

float flag(bool b) {
  return b ? 1.0F : -1.0F;
}

// 2 * (1 - clamp(d / max, 0, 1)) - 1: +1 touching, -1 at or beyond max.
float proximity(double d, double max) {
  return static_cast<float>(1.0 - 2.0 * clamp(d / max, 0.0, 1.0));
}

// 2 * clamp(x / max, 0, 1) - 1.
float magnitude(double x, double max) {
  return static_cast<float>(2.0 * clamp(x / max, 0.0, 1.0) - 1.0);
}

// sin, cos of wrap(bearing(self -> point) - body) and the proximity of the distance, written
// at out[0..2]. `body` is the unit vector of the body angle.
void landmark(Vec2 self, Vec2 body, Vec2 point, double max, float* out) {
  const Vec2 d = point - self;
  const double dist = d.r();
  const Vec2 u = dist > 0.0 ? d * (1.0 / dist) : Vec2{1.0, 0.0};
  out[0] = static_cast<float>(u.y * body.x - u.x * body.y);  // sin(bearing - body)
  out[1] = static_cast<float>(u.x * body.x + u.y * body.y);  // cos(bearing - body)
  out[2] = proximity(dist, max);
}

Vec2 unit_or_x(Vec2 v) {
  const double r = v.r();
  return r > 0.0 ? v * (1.0 / r) : Vec2{1.0, 0.0};
}

}  // namespace

void write_features(const SoccerState& state, std::span<float> out) {
  write_features(state, 0, out);
}

void write_features(const SoccerState& state, int self_index, std::span<float> out) {
  assert(static_cast<int>(out.size()) == feature_count(state.num_players));
  assert(self_index >= 0 && self_index < state.num_players);
  const PlayerState& self = state.players[self_index];
  const double body_rad = self.body_deg * kDegToRad;
  const Vec2 b{std::cos(body_rad), std::sin(body_rad)};
  const double R = kMaxDistance;
  float* f = out.data();

  f[0] = 1.0F;  // self position valid (full state)
  f[1] = 1.0F;  // self velocity valid
  const Vec2 uv = unit_or_x(self.vel);
  f[feat::kSelfVelAngleSin] = static_cast<float>(b.y * uv.x - b.x * uv.y);  // sin(body - vdir)
  f[feat::kSelfVelAngleCos] = static_cast<float>(b.x * uv.x + b.y * uv.y);
  f[feat::kSelfSpeed] = magnitude(self.vel.r(), 0.46);
  f[feat::kBodySin] = static_cast<float>(b.y);
  f[feat::kBodyCos] = static_cast<float>(b.x);
  f[feat::kStamina] = magnitude(self.stamina, kStaminaMax);
  f[feat::kFrozen] = flag(self.tackle_cycles > 0);
  f[feat::kCollidedBall] = flag(self.collided_ball);
  f[feat::kCollidedPlayer] = flag(self.collided_player);
  f[feat::kCollidedPost] = flag(self.collided_post);
  const Vec2 to_ball = state.ball.pos - self.pos;
  f[feat::kKickable] = flag(to_ball.r() <= kClientKickableArea);

  const Vec2 p = self.pos;
  landmark(p, b, {kPitchHalfLength, 0.0}, R, f + feat::kGoalCentre);
  landmark(p, b, {kPitchHalfLength, -kGoalHalfWidth}, R, f + feat::kGoalPostTop);
  landmark(p, b, {kPitchHalfLength, kGoalHalfWidth}, R, f + feat::kGoalPostBottom);
  landmark(p, b, {kPenaltyBoxX, 0.0}, R, f + feat::kPenaltyCentre);
  landmark(p, b, {kPenaltyBoxX, -kPenaltyBoxHalfWidth}, R, f + feat::kPenaltyTop);
  landmark(p, b, {kPenaltyBoxX, kPenaltyBoxHalfWidth}, R, f + feat::kPenaltyBottom);
  landmark(p, b, {0.0, 0.0}, R, f + feat::kCentreField);
  landmark(p, b, {0.0, -kPitchHalfWidth}, R, f + feat::kCornerTopLeft);
  landmark(p, b, {kPitchHalfLength, -kPitchHalfWidth}, R, f + feat::kCornerTopRight);
  landmark(p, b, {kPitchHalfLength, kPitchHalfWidth}, R, f + feat::kCornerBottomRight);
  landmark(p, b, {0.0, kPitchHalfWidth}, R, f + feat::kCornerBottomLeft);

  f[feat::kOobLeft] = proximity(p.x, kPitchHalfLength);
  f[feat::kOobRight] = proximity(kPitchHalfLength - p.x, kPitchHalfLength);
  f[feat::kOobTop] = proximity(kPitchHalfWidth + p.y, 2.0 * kPitchHalfWidth);
  f[feat::kOobBottom] = proximity(kPitchHalfWidth - p.y, 2.0 * kPitchHalfWidth);

  f[feat::kBallPosValid] = 1.0F;
  landmark(p, b, state.ball.pos, R, f + feat::kBallAngleSin);
  f[feat::kBallVelValid] = 1.0F;
  f[feat::kBallSpeed] = magnitude(state.ball.vel.r(), 5.0);
  const double bv = state.ball.vel.r();
  f[feat::kBallVelAngleSin] = bv > 0.0 ? static_cast<float>(state.ball.vel.y / bv) : 0.0F;
  f[feat::kBallVelAngleCos] = bv > 0.0 ? static_cast<float>(state.ball.vel.x / bv) : 1.0F;

  // Other players (reference §3.3): teammates then opponents, each group sorted by distance;
  // only players with x > 0 count, missing slots are zeros.
  const int others = state.num_players - 1;
  if (others <= 0) {
    return;
  }
  std::array<int, SoccerState::kMaxPlayers> order{};
  int n = 0;
  for (int i = 0; i < state.num_players; ++i) {
    if (i != self_index) {
      order[n++] = i;
    }
  }
  const Team my_team = self.team;
  // Teammates first, then opponents, each nearest first (ties by index): an insertion sort of at
  // most kMaxPlayers - 1 entries.
  const auto before = [&](int a, int c) {
    const PlayerState& pa = state.players[a];
    const PlayerState& pc = state.players[c];
    const bool ta = pa.team == my_team;
    const bool tc = pc.team == my_team;
    if (ta != tc) {
      return ta;
    }
    const double da = (pa.pos - p).r2();
    const double dc = (pc.pos - p).r2();
    return da != dc ? da < dc : a < c;
  };
  for (int i = 1; i < n; ++i) {
    const int v = order[i];
    int j = i;
    for (; j > 0 && before(v, order[j - 1]); --j) {
      order[j] = order[j - 1];
    }
    order[j] = v;
  }
  float* block = f + kNumAgentFeatures;
  std::fill(block, block + static_cast<ptrdiff_t>(kFeaturesPerPlayer) * others, 0.0F);
  int teammates = 0;
  for (int k = 0; k < n; ++k) {
    teammates += state.players[order[k]].team == my_team ? 1 : 0;
  }
  int written_team = 0;
  int written_opp = 0;
  for (int k = 0; k < n; ++k) {
    const PlayerState& o = state.players[order[k]];
    if (o.pos.x <= 0.0) {
      continue;
    }
    const bool mate = o.team == my_team;
    const int slot = mate ? written_team++ : teammates + written_opp++;
    float* q = block + static_cast<ptrdiff_t>(kFeaturesPerPlayer) * slot;
    landmark(p, b, o.pos, R, q);
    const double ob = o.body_deg * kDegToRad;
    q[3] = static_cast<float>(std::sin(ob));
    q[4] = static_cast<float>(std::cos(ob));
    q[5] = magnitude(o.vel.r(), 0.75);
    const Vec2 ov = unit_or_x(o.vel);
    q[6] = static_cast<float>(ov.y);
    q[7] = static_cast<float>(ov.x);
  }
}

double proximity_to_distance(float proximity) {
  return (1.0 - static_cast<double>(proximity)) * 0.5 * kMaxDistance;
}

Vec2 body_frame_position(std::span<const float> f, size_t index) {
  const double d = proximity_to_distance(f[index + 2]);
  return {d * f[index + 1], d * f[index]};
}

Vec2 ball_velocity_in_body_frame(std::span<const float> f) {
  const double speed = 0.5 * (f[feat::kBallSpeed] + 1.0) * 5.0;
  const double vgx = speed * f[feat::kBallVelAngleCos];
  const double vgy = speed * f[feat::kBallVelAngleSin];
  const double bs = f[feat::kBodySin];
  const double bc = f[feat::kBodyCos];
  return {vgx * bc + vgy * bs, -vgx * bs + vgy * bc};
}

}  // namespace pamdp::hfo
