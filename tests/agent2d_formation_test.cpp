// agent2d's formations (envs/hfo/agent2d_formation.hpp) against librcsc's own
// FormationDT::getPosition at 900 points (tests/data/agent2d-formation-reference.csv, dumped by
// tools/agent2d-formation/dump_formation.cpp: 300 per formation, the first 20 of them samples,
// the rest uniform over agent2d's half of the field and 4.5 m beyond it), and hand-worked cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "envs/hfo/agent2d_formation.hpp"

namespace pamdp::hfo::agent2d {
namespace {

FormationKind kind_of(const std::string& name) {
  if (name == "defense-formation") {
    return FormationKind::kDefense;
  }
  if (name == "offense-formation") {
    return FormationKind::kOffense;
  }
  EXPECT_EQ(name, "normal-formation");
  return FormationKind::kNormal;
}

TEST(Agent2dFormation, MatchesLibrcscAtEveryReferencePoint) {
  std::ifstream in(PAMDP_TEST_DATA_DIR "/data/agent2d-formation-reference.csv");
  ASSERT_TRUE(in) << "no tests/data/agent2d-formation-reference.csv";
  std::string line;
  std::getline(in, line);
  ASSERT_EQ(line, "formation,x,y,p2x,p2y,p3x,p3y");
  int rows = 0;
  double worst = 0.0;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string name;
    std::getline(ss, name, ',');
    double v[6];
    for (double& x : v) {
      std::string cell;
      std::getline(ss, cell, ',');
      x = std::stod(cell);
    }
    const FormationData& f = formation_data(kind_of(name));
    ASSERT_EQ(f.name, name);
    const Vec2 focus{v[0], v[1]};
    const Vec2 p2 = formation_position(f, 2, focus);
    const Vec2 p3 = formation_position(f, 3, focus);
    worst = std::max(
        {worst, std::fabs(p2.x - v[2]), std::fabs(p2.y - v[3]), std::fabs(p3.x - v[4]), std::fabs(p3.y - v[5])});
    EXPECT_NEAR(p2.x, v[2], 1e-9) << line;
    EXPECT_NEAR(p2.y, v[3], 1e-9) << line;
    EXPECT_NEAR(p3.x, v[4], 1e-9) << line;
    EXPECT_NEAR(p3.y, v[5], 1e-9) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 900);
  std::printf("largest difference from librcsc: %.3g m\n", worst);
}

// Every triangle uses three distinct samples, and no two triangles are the same: the data is a
// triangulation, not a copy error. Its triangles cover the hull: 2 n - 2 - h of them for n
// samples with h on the hull (here 8), Euler's formula for a triangulated point set.
TEST(Agent2dFormation, TheTrianglesAreATriangulationOfTheSamples) {
  for (const FormationKind k : {FormationKind::kDefense, FormationKind::kOffense, FormationKind::kNormal}) {
    const FormationData& f = formation_data(k);
    std::set<std::array<int, 3>> seen;
    double area = 0.0;
    for (auto t : f.triangles) {
      ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
      for (const int v : t) {
        ASSERT_GE(v, 0);
        ASSERT_LT(v, kFormationSamples);
      }
      const Vec2 a = f.samples[static_cast<size_t>(t[0])].ball;
      const Vec2 b = f.samples[static_cast<size_t>(t[1])].ball;
      const Vec2 c = f.samples[static_cast<size_t>(t[2])].ball;
      area += 0.5 * std::fabs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
      std::sort(t.begin(), t.end());
      EXPECT_TRUE(seen.insert(t).second) << f.name << ": a triangle twice";
    }
    // The samples span the whole field and beyond (x in [-54.5, 54.5], y in [-36, 36]): the
    // triangles tile it without overlap, so their areas add up to the hull's, 109 x 72.
    EXPECT_NEAR(area, 109.0 * 72.0, 1e-6) << f.name;
  }
}

// At a sample's ball position the players stand where the file puts them; halfway along an
// edge, halfway between its two samples' positions (linear interpolation).
TEST(Agent2dFormation, SamplesAndEdgesInterpolateLinearly) {
  const FormationData& f = formation_data(FormationKind::kDefense);
  // Sample 2 of defense-formation.conf: ball (0, 0), unum 2 at (-15.53, -5.42), unum 3 at
  // (-15.53, 5.42).
  const Vec2 p2 = formation_position(f, 2, {0.0, 0.0});
  EXPECT_NEAR(p2.x, -15.53, 1e-9);
  EXPECT_NEAR(p2.y, -5.42, 1e-9);
  const Vec2 p3 = formation_position(f, 3, {0.0, 0.0});
  EXPECT_NEAR(p3.x, -15.53, 1e-9);
  EXPECT_NEAR(p3.y, 5.42, 1e-9);
  const auto& t = f.triangles[0];
  const FormationSample& a = f.samples[static_cast<size_t>(t[1])];
  const FormationSample& b = f.samples[static_cast<size_t>(t[2])];
  const Vec2 mid = formation_position(f, 2, (a.ball + b.ball) * 0.5);
  EXPECT_NEAR(mid.x, 0.5 * (a.players[0].x + b.players[0].x), 1e-9);
  EXPECT_NEAR(mid.y, 0.5 * (a.players[0].y + b.players[0].y), 1e-9);
}

TEST(Agent2dFormation, TheSituationPicksTheFormation) {
  EXPECT_EQ(formation_for(5, 3), FormationKind::kDefense);  // the opponents first by 2
  EXPECT_EQ(formation_for(4, 3), FormationKind::kNormal);
  EXPECT_EQ(formation_for(3, 5), FormationKind::kOffense);
  EXPECT_EQ(formation_for(3, 4), FormationKind::kNormal);
}

}  // namespace
}  // namespace pamdp::hfo::agent2d
