// agent2d's home positions for its field players: the Delaunay-triangulation formations HFO's
// base team reads (HFO bin/teams/base/config/formations-dt/{defense,offense,normal}-formation.conf)
// and librcsc's FormationDT::getPosition (formation/formation_dt.cpp): find the triangle of
// sample ball positions that holds the focus point, and interpolate the three samples' positions
// linearly; outside every triangle, the nearest sample's positions. HFO's Strategy::getFormation
// (src/strategy.cpp) picks the formation in play-on by who reaches the ball first: the defense
// formation when the opponents do by 2 cycles or more, the offense formation when agent2d's own
// team does, the normal one otherwise.
//
// The samples (ball position, then each player's position) and the triangles librcsc computes
// over the samples' ball positions (DelaunayTriangulation::compute, in the files' sample order)
// are carried over as data (agent2d_formation_data.cpp), dumped by
// tools/agent2d-formation/dump_formation.cpp from librcsc itself, so that ties between
// cocircular samples (HFO's files are mirror-symmetric in y, and every mirrored quadrilateral is
// cocircular) fall as librcsc's do. Positions are in agent2d's own frame (its goal at x = -52.5;
// goalie_world.hpp) and kept for the field defenders HFO runs with --defense-npcs 2 and 3: unums 2
// and 3 (HFO bin/Teams.py, Agent2d's defense order 2, 3, 4, ...).
//
// Nothing here allocates; a position is one pass over at most 220 triangles.
#pragma once

#include <array>
#include <string_view>

#include "envs/hfo/geometry.hpp"

namespace pamdp::hfo::agent2d {

inline constexpr int kFormationSamples = 115;
inline constexpr int kFormationTriangles = 220;
inline constexpr int kFormationUnums = 2;  // unums 2 and 3
inline constexpr int kFirstFormationUnum = 2;

struct FormationSample {
  Vec2 ball;
  std::array<Vec2, kFormationUnums> players;  // unum 2, unum 3
};

struct FormationData {
  std::string_view name;  // the .conf file's name without its extension
  std::array<FormationSample, kFormationSamples> samples;
  std::array<std::array<int, 3>, kFormationTriangles> triangles;  // sample indices, librcsc's triangle order
};

enum class FormationKind { kDefense, kOffense, kNormal };

// HFO's three play-on formations.
const FormationData& formation_data(FormationKind kind);

// Strategy::getFormation in play-on: opponents first by 2 cycles or more: defense; agent2d's
// team first by 2 or more: offense; else normal (Strategy::updateSituation).
inline FormationKind formation_for(int our_reach_cycles, int their_reach_cycles) {
  if (their_reach_cycles <= our_reach_cycles - 2) {
    return FormationKind::kDefense;
  }
  if (our_reach_cycles <= their_reach_cycles - 2) {
    return FormationKind::kOffense;
  }
  return FormationKind::kNormal;
}

// FormationDT::getPosition(unum, focus) for unum 2 or 3 (anything else is a programming error).
Vec2 formation_position(const FormationData& formation, int unum, Vec2 focus);

}  // namespace pamdp::hfo::agent2d
