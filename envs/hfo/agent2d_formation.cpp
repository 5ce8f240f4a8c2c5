#include "envs/hfo/agent2d_formation.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pamdp::hfo::agent2d {
namespace {

// librcsc DelaunayTriangulation::EPSILON and Segment2D's CALC_ERROR (geom/segment_2d.h).
constexpr double kEps = 1.0e-10;
constexpr double kSegmentCalcError = 1.0e-9;

// Vector2D::dist: sqrt of the squared distance.
double dist_of(double dx, double dy) {
  return std::sqrt(dx * dx + dy * dy);
}

double cross(Vec2 a, Vec2 b) {
  return a.x * b.y - a.y * b.x;
}

// A line a x + b y + c = 0 through p and q (librcsc Line2D::assign(p1, p2)).
struct Line {
  double a, b, c;
};
Line line_through(Vec2 p, Vec2 q) {
  const double a = -(q.y - p.y);
  const double b = q.x - p.x;
  return {a, b, -a * p.x - b * p.y};
}

// Line2D::intersection; false for (near) parallel lines.
bool intersect(const Line& l1, const Line& l2, Vec2& out) {
  const double d = l1.a * l2.b - l1.b * l2.a;
  if (std::fabs(d) < kEps) {
    return false;
  }
  out = {(l1.b * l2.c - l2.b * l1.c) / d, (l2.a * l1.c - l1.a * l2.c) / d};
  return true;
}

// The circumcircle's bounding box test of DelaunayTriangulation::findTriangleContains, which
// skips triangles whose circumcircle's box does not hold the point.
bool outside_circumcircle_box(Vec2 a, Vec2 b, Vec2 c, Vec2 p) {
  const Vec2 ab = b - a;
  const Vec2 ca = c - a;  // librcsc's "ca" is c - a in Triangle2D::circumcenter's closed form
  const double d = cross(ab, ca);
  if (std::fabs(d) < kEps) {
    return false;  // degenerate: let the orientation tests decide
  }
  const double inv = 0.5 / d;
  const double ab2 = ab.x * ab.x + ab.y * ab.y;
  const double ca2 = ca.x * ca.x + ca.y * ca.y;
  const Vec2 centre{a.x + inv * (ab2 * ca.y - ca2 * ab.y), a.y + inv * (ab.x * ca2 - ca.x * ab2)};
  const double r = dist_of(centre.x - a.x, centre.y - a.y);
  return std::fabs(centre.x - p.x) > r || std::fabs(centre.y - p.y) > r;
}

// On the segment p-q, as librcsc's online test: the cross product near zero and p and q not on
// one side of the point in x or in y.
bool on_edge(double outer, Vec2 rp, Vec2 rq) {
  return std::fabs(outer) <= kEps && !(rp.x * rq.x > kEps || rp.y * rq.y > kEps);
}

// The first triangle, in librcsc's order, that holds p (on an edge counts), or -1.
int find_triangle(const FormationData& f, Vec2 p) {
  for (int t = 0; t < kFormationTriangles; ++t) {
    const auto& tri = f.triangles[static_cast<size_t>(t)];
    const Vec2 v0 = f.samples[static_cast<size_t>(tri[0])].ball;
    const Vec2 v1 = f.samples[static_cast<size_t>(tri[1])].ball;
    const Vec2 v2 = f.samples[static_cast<size_t>(tri[2])].ball;
    if (outside_circumcircle_box(v0, v1, v2, p)) {
      continue;
    }
    const Vec2 r0 = v0 - p;
    const Vec2 r1 = v1 - p;
    const Vec2 r2 = v2 - p;
    const double o0 = cross(r0, r1);
    const double o1 = cross(r1, r2);
    const double o2 = cross(r2, r0);
    // An edge the point lies on decides at once: on it, this triangle; beside it, the next.
    if (std::fabs(o0) <= kEps) {
      if (on_edge(o0, r0, r1)) {
        return t;
      }
      continue;
    }
    if (std::fabs(o1) <= kEps) {
      if (on_edge(o1, r1, r2)) {
        return t;
      }
      continue;
    }
    if (std::fabs(o2) <= kEps) {
      if (on_edge(o2, r2, r0)) {
        return t;
      }
      continue;
    }
    if ((o0 >= 0.0 && o1 >= 0.0 && o2 >= 0.0) || (o0 <= 0.0 && o1 <= 0.0 && o2 <= 0.0)) {
      return t;
    }
  }
  return -1;
}

}  // namespace

Vec2 formation_position(const FormationData& f, int unum, Vec2 focus) {
  const int k = unum - kFirstFormationUnum;
  if (k < 0 || k >= kFormationUnums) {
    std::fprintf(stderr, "formation_position: unum %d has no formation position here (2 or 3)\n", unum);
    std::abort();
  }
  const auto player = static_cast<size_t>(k);
  const int t = find_triangle(f, focus);
  if (t < 0) {
    // DelaunayTriangulation::findNearestVertex: the first sample strictly nearest.
    size_t best = 0;
    double best_d2 = 10000000.0;
    for (size_t i = 0; i < f.samples.size(); ++i) {
      const Vec2 d = f.samples[i].ball - focus;
      const double d2 = d.x * d.x + d.y * d.y;
      if (d2 < best_d2) {
        best = i;
        best_d2 = d2;
      }
    }
    return f.samples[best].players[player];
  }
  const auto& tri = f.triangles[static_cast<size_t>(t)];
  const FormationSample& s0 = f.samples[static_cast<size_t>(tri[0])];
  const FormationSample& s1 = f.samples[static_cast<size_t>(tri[1])];
  const FormationSample& s2 = f.samples[static_cast<size_t>(tri[2])];
  // FormationDT::interpolate: the line from vertex 0 through the focus meets edge 1-2 at i; the
  // position is interpolated along 1-2 at i, then from vertex 0 to i at the focus.
  Vec2 i;
  const bool met = intersect(line_through(s1.ball, s2.ball), line_through(s0.ball, focus), i) &&
                   (i.x - s1.ball.x) * (i.x - s2.ball.x) <= kSegmentCalcError &&
                   (i.y - s1.ball.y) * (i.y - s2.ball.y) <= kSegmentCalcError;
  if (!met) {
    const Vec2 d0 = focus - s0.ball;
    if (d0.x * d0.x + d0.y * d0.y < 1.0e-5) {
      return s0.players[player];
    }
    return (s0.players[player] + s1.players[player] + s2.players[player]) * (1.0 / 3.0);
  }
  const double d1i = dist_of(s1.ball.x - i.x, s1.ball.y - i.y);
  const double d2i = dist_of(s2.ball.x - i.x, s2.ball.y - i.y);
  const Vec2 p12 = s1.players[player] + (s2.players[player] - s1.players[player]) * (d1i / (d1i + d2i));
  const double d0f = dist_of(s0.ball.x - focus.x, s0.ball.y - focus.y);
  const double dif = dist_of(i.x - focus.x, i.y - focus.y);
  return s0.players[player] + (p12 - s0.players[player]) * (d0f / (d0f + dif));
}

}  // namespace pamdp::hfo::agent2d
