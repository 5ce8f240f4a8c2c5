// TEMPORARY stand-in (not committed): helper's port replaces it.
#include <cmath>

#include "envs/hfo/goalie_world.hpp"

namespace pamdp::hfo::agent2d {

static int reach(Vec2 pos, double body_deg, const InterceptTable& t, double r) {
  for (int k = 0; k < t.ball_cache_size; ++k) {
    const Vec2 d = t.ball_cache[k] - pos;
    const double need = d.r() - r;
    if (need <= 0.0) return k;
    double rel = std::fabs(wrap_deg(std::atan2(d.y, d.x) * kRadToDeg - body_deg));
    int turn = rel > 20.0 ? 1 : 0;
    double v = 0, dist = 0;
    int n = 0;
    for (; n + turn < k; ++n) {
      v = std::min(1.0, v * 0.4 + 0.6);
      dist += v;
    }
    if (dist >= need) return k;
  }
  return 1000;
}

void predict_intercepts(const GoalieWorld& w, InterceptTable* t) {
  *t = InterceptTable{};
  Vec2 bp = w.ball_pos, bv = w.ball_vel;
  t->ball_cache[t->ball_cache_size++] = bp;
  for (int i = 1; i <= InterceptTable::kMaxCycle; ++i) {
    bp += bv;
    bv *= kBallDecay;
    t->ball_cache[t->ball_cache_size++] = bp;
    if (i >= 5 && bv.r2() < 1e-4) break;
  }
  t->self_reach_cycle = reach(w.self.pos, w.self.body_deg, *t, 1.0);
  if (w.num_opponents > 0)
    t->opponent_reach_cycle =
        w.exist_kickable_opponent ? 0 : reach(w.opponents[0].pos, w.opponents[0].body_deg, *t, 1.085);
}

bool body_intercept(const GoalieWorld& w, const InterceptTable& t, bool, Command* out) {
  const Vec2 p = ball_inertia_point(w, std::min(t.self_reach_cycle, 30));
  return body_go_to_point(w, p, 0.5, 100.0, -1.0, 1, false, 15.0, out);
}

}  // namespace pamdp::hfo::agent2d
