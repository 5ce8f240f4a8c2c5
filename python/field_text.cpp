#include "python/field_text.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "envs/goal/goal_env.hpp"
#include "envs/hfo/geometry.hpp"
#include "envs/hfo/hfo_env.hpp"
#include "envs/platform/platform_env.hpp"
#include "envs/scaled_parameters.hpp"
#include "envs/toy/reach_stop.hpp"

namespace pamdp::python {
namespace {

std::string format(const char* fmt, double a, double b, double c = 0.0, double d = 0.0, double e = 0.0) {
  char line[160];
  std::snprintf(line, sizeof(line), fmt, a, b, c, d, e);
  return line;
}

// The attacked half, x in [0, 52.5] to the right, y in [-34, 34] downward, one character per
// 1.5 m across and 4 m down; the goal mouth is the column of '#' on the right edge.
std::string hfo_field(const hfo::SoccerState& s) {
  constexpr int kCols = 36;
  constexpr int kRows = 17;
  constexpr double kXScale = hfo::kPitchHalfLength / (kCols - 1);
  constexpr double kYScale = 2.0 * hfo::kPitchHalfWidth / (kRows - 1);
  std::vector<std::string> grid(kRows, "|" + std::string(kCols, ' ') + "|");
  for (int r = 0; r < kRows; ++r) {
    const double y = -hfo::kPitchHalfWidth + r * kYScale;
    if (std::fabs(y) <= hfo::kGoalHalfWidth) {
      grid[static_cast<size_t>(r)].back() = '#';
    }
  }
  const auto put = [&](double x, double y, char c) {
    const long col = std::lround(x / kXScale);
    const long row = std::lround((y + hfo::kPitchHalfWidth) / kYScale);
    if (col >= 0 && col < kCols && row >= 0 && row < kRows) {
      grid[static_cast<size_t>(row)][static_cast<size_t>(col) + 1] = c;
    }
  };
  for (int i = s.num_players - 1; i >= 0; --i) {
    put(s.players[static_cast<size_t>(i)].pos.x, s.players[static_cast<size_t>(i)].pos.y, i == 0 ? 'A' : 'G');
  }
  put(s.ball.pos.x, s.ball.pos.y, 'o');
  std::string out = "+" + std::string(kCols, '-') + "+\n";
  for (const std::string& row : grid) {
    out += row + "\n";
  }
  out += "+" + std::string(kCols, '-') + "+   A agent, G goalie, o ball, # goal mouth\n";
  for (int i = 0; i < s.num_players; ++i) {
    const hfo::PlayerState& p = s.players[static_cast<size_t>(i)];
    out +=
        (i == 0 ? "agent  " : "goalie ") +
        format("x %6.2f  y %6.2f  body %7.1f deg  vel (%5.2f, %5.2f)", p.pos.x, p.pos.y, p.body_deg, p.vel.x, p.vel.y) +
        format("  stamina %.0f\n", p.stamina, 0.0);
  }
  out +=
      format("ball   x %6.2f  y %6.2f  vel (%5.2f, %5.2f)\n", s.ball.pos.x, s.ball.pos.y, s.ball.vel.x, s.ball.vel.y);
  return out;
}

}  // namespace

std::string field_text(Env& env, int status, int steps) {
  Env* inner = &env;
  if (auto* scaled = dynamic_cast<ScaledParametersEnv*>(inner)) {
    inner = &scaled->inner();
  }
  std::string out = std::string(env.name()) + "  step " + std::to_string(steps) + "  " +
                    (status == 0 ? std::string("IN_GAME") : std::string(env.status_name(status))) + "\n";
  if (const auto* hfo_env = dynamic_cast<const hfo::HfoEnv*>(inner)) {
    out += hfo_field(hfo_env->sim().state());
  } else if (const auto* toy = dynamic_cast<const toy::ReachStopEnv*>(inner)) {
    // The line [-1, 1] in 41 characters: P the position, T the target.
    std::string line(41, '-');
    const auto at = [](float v) {
      return static_cast<size_t>(std::lround((std::fmax(-1.0F, std::fmin(1.0F, v)) + 1.0F) * 20.0F));
    };
    line[at(toy->target())] = 'T';
    line[at(toy->pos())] = 'P';
    out += "[" + line + "]   P position, T target, over [-1, 1]\n" +
           format("position %.3f  target %.3f\n", toy->pos(), toy->target());
  } else if (const auto* platform = dynamic_cast<const platform::PlatformEnv*>(inner)) {
    const platform::PlatformEnv::Body& p = platform->player();
    out += format("player  x %7.2f  y %6.2f  dx %6.2f  dy %6.2f\n", p.x, p.y, p.dx, p.dy);
    for (int i = 0; i < 2; ++i) {
      const platform::PlatformEnv::Body& e = platform->enemy(i);
      out += format("enemy %.0f x %7.2f  y %6.2f  dx %6.2f\n", i + 1.0, e.x, e.y, e.dx);
    }
  } else if (const auto* goal = dynamic_cast<const goal::GoalEnv*>(inner)) {
    const goal::GoalState& g = goal->state();
    const auto body = [](const char* name, const goal::Body& b) {
      return std::string(name) +
             format("x %7.2f  y %7.2f  vel (%6.2f, %6.2f)\n", b.position.x, b.position.y, b.velocity.x, b.velocity.y);
    };
    out += body("striker ", g.striker) + body("keeper  ", g.keeper) + body("ball    ", g.ball);
  } else {
    out += "(this env keeps its state elsewhere: the observation is all it shows)\n";
  }
  return out;
}

}  // namespace pamdp::python
