// Dumps what librcsc makes of HFO's agent2d formation files (bin/teams/base/config/formations-dt):
// the samples (ball position and the field defenders' positions, unums 2 and 3), the Delaunay
// triangles librcsc's FormationDT::train() computes over the samples' ball positions, and
// FormationDT::getPosition() at reference points. The project carries the first two over as data
// (envs/hfo/agent2d_formation_data.cpp) and checks its interpolation against the third
// (tests/data/agent2d-formation-reference.csv). Built beside HFO only, never by the project:
//
//   g++ -std=c++17 -O1 -I/work/hfo-ext/librcsc tools/agent2d-formation/dump_formation.cpp \
//       -L/work/hfo-ext/HFO/build/librcsc-prefix/src/librcsc-build/lib -lrcsc_agent -lrcsc_geom \
//       -lrcsc_param -lrcsc_time -lrcsc_net -lrcsc_gz -lz -o /tmp/dump_formation
//   /tmp/dump_formation samples NAME FILE...    # C++ initializers, one formation per FILE
//   /tmp/dump_formation reference N SEED FILE... # CSV: formation,x,y,p2x,p2y,p3x,p3y
#include <rcsc/formation/formation_dt.h>
#include <rcsc/geom/delaunay_triangulation.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

namespace {

// The formation stays alive for the process (librcsc's Ptr is a shared pointer of its own kind).
const rcsc::FormationDT* load(const char* path) {
  static std::vector<rcsc::Formation::Ptr> keep;
  std::ifstream in(path);
  rcsc::Formation::Ptr f = rcsc::Formation::create(in);
  if (!f) {
    std::fprintf(stderr, "cannot read %s\n", path);
    std::exit(1);
  }
  in.seekg(0);
  if (!f->read(in)) {
    std::fprintf(stderr, "cannot parse %s\n", path);
    std::exit(1);
  }
  keep.push_back(f);
  const auto* dt = dynamic_cast<const rcsc::FormationDT*>(f.get());
  if (!dt) {
    std::fprintf(stderr, "%s is not a DelaunayTriangulation formation\n", path);
    std::exit(1);
  }
  return dt;
}

std::string base_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  return name.substr(0, name.find('.'));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s samples FILE... | reference N SEED FILE...\n", argv[0]);
    return 2;
  }
  const std::string mode = argv[1];
  if (mode == "samples") {
    for (int a = 2; a < argc; ++a) {
      auto f = load(argv[a]);
      const auto& samples = f->samples()->dataCont();
      std::printf("// %s: %zu samples, %zu triangles\n", base_name(argv[a]).c_str(), samples.size(),
                  f->triangulation().triangles().size());
      std::printf("{\"%s\",\n {", base_name(argv[a]).c_str());
      for (const auto& s : samples) {
        const rcsc::Vector2D p2 = s.getPosition(2);
        const rcsc::Vector2D p3 = s.getPosition(3);
        std::printf("{{%.17g, %.17g}, {{%.17g, %.17g}, {%.17g, %.17g}}},\n  ", s.ball_.x, s.ball_.y, p2.x, p2.y, p3.x,
                    p3.y);
      }
      std::printf("},\n {");
      for (const auto& t : f->triangulation().triangles()) {
        std::printf("{%d, %d, %d}, ", t.second->vertex(0)->id(), t.second->vertex(1)->id(), t.second->vertex(2)->id());
      }
      std::printf("}},\n");
    }
    return 0;
  }
  if (mode == "reference" && argc >= 5) {
    const int n = std::atoi(argv[2]);
    std::mt19937_64 rng(std::strtoull(argv[3], nullptr, 10));
    // agent2d's own frame (its goal at x = -52.5); HFO's half field is x in [-52.5, 0], and a
    // little beyond every side so that points outside the triangles are met too.
    std::uniform_real_distribution<double> ux(-57.0, 3.0);
    std::uniform_real_distribution<double> uy(-39.0, 39.0);
    std::printf("formation,x,y,p2x,p2y,p3x,p3y\n");
    for (int a = 4; a < argc; ++a) {
      auto f = load(argv[a]);
      for (int i = 0; i < n; ++i) {
        rcsc::Vector2D ball(ux(rng), uy(rng));
        if (i < 20) {  // the samples themselves
          ball = std::next(f->samples()->dataCont().begin(), i * 5)->ball_;
        }
        const rcsc::Vector2D p2 = f->getPosition(2, ball);
        const rcsc::Vector2D p3 = f->getPosition(3, ball);
        std::printf("%s,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", base_name(argv[a]).c_str(), ball.x, ball.y, p2.x, p2.y,
                    p3.x, p3.y);
      }
    }
    return 0;
  }
  std::fprintf(stderr, "unknown mode '%s'\n", mode.c_str());
  return 2;
}
