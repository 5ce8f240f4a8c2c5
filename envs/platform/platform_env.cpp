#include "envs/platform/platform_env.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "core/normal.hpp"

namespace pamdp::platform {
namespace {

// gym-platform's Constants (platform_env.py).
constexpr double kDt = 0.05;
constexpr double kPlatformHeight = 40.0;
constexpr double kWidth[3] = {250.0, 275.0, 50.0};
constexpr double kGap1 = 225.0;
constexpr double kGap2 = 235.0;
constexpr double kTotalWidth = kWidth[0] + kWidth[1] + kWidth[2] + kGap1 + kGap2;  // 1035
constexpr double kMaxPlatformWidth = 275.0;
constexpr double kMaxGap = 235.0;
constexpr double kMaxHeight = 1.0;  // max(1.0, HEIGHT1..3), the heights all 0
constexpr double kEnemySpeed = 30.0;
constexpr double kEnemyNoise = 0.5;
constexpr double kPlayerNoise = kEnemyNoise;
constexpr double kSizeX = 20.0;  // ENEMY_SIZE, which the player shares
constexpr double kSizeY = 30.0;
constexpr double kMaxDx = 100.0;
constexpr double kMaxDy = 200.0;
constexpr double kMaxDxOn = 70.0;
constexpr double kMaxDdx = (kMaxDx - kMaxDxOn) / kDt;  // 600
constexpr double kMaxDdy = kMaxDy / kDt;               // 4000
constexpr double kHopDev = 1.0;
constexpr double kLeapDev = 1.0;
constexpr double kHopDy = 35.0;   // Player.hop_to
constexpr double kLeapDy = 25.0;  // Player.leap_to
constexpr double kVelocityDecay = 0.99;
constexpr double kGravity = 9.8;
constexpr float kParamMax[3] = {30.0F, 720.0F, 430.0F};  // PARAMETERS_MAX (run, hop, leap); minima 0

// The platforms' lower-left corners (PlatformEnv.__init__): each starts where the previous
// one's gap ends; all at height 0, 40 high.
constexpr double kPlatformX[3] = {0.0, kWidth[0] + kGap1, kWidth[0] + kGap1 + kWidth[1] + kGap2};
constexpr double kRightBound = kPlatformX[2] + kWidth[2];  // _right_bound(): 1035

[[noreturn]] void misuse(const char* what) {
  std::fprintf(stderr, "PlatformEnv: %s\n", what);
  std::abort();
}

// Entity.colliding: strictly inside the other's box grown by this one's size.
bool overlaps(double x, double y, double ox, double oy, double ow, double oh) {
  return ox - kSizeX < x && oy - kSizeY < y && x < ox + ow && y < oy + oh;
}

}  // namespace

PlatformEnv::PlatformEnv(const PlatformConfig& config, uint64_t seed) : config_(config), rng_(seed) {
  if (config_.max_steps < 1) {
    throw std::invalid_argument("PlatformConfig.max_steps must be >= 1, got " + std::to_string(config_.max_steps));
  }
  done_ = true;  // reset() first
}

const ActionSpace& PlatformEnv::action_space() const {
  static const ActionSpace kSpace{
      .actions = {{"RUN", {0}}, {"HOP", {1}}, {"LEAP", {2}}},
      .params = {{"run_dx", 0.0F, kParamMax[0]}, {"hop_dx", 0.0F, kParamMax[1]}, {"leap_dx", 0.0F, kParamMax[2]}},
  };
  return kSpace;
}

std::string_view PlatformEnv::status_name(int status) const {
  switch (status) {
    case kInProgress: return "IN_PROGRESS";
    case kGoal: return "GOAL";
    case kEnemy: return "ENEMY";
    case kFell: return "FELL";
    case kOutOfTime: return "OUT_OF_TIME";
    default: return "UNKNOWN";
  }
}

std::span<const int> PlatformEnv::outcomes() const {
  static constexpr std::array<int, 5> kOutcomes{kInProgress, kGoal, kEnemy, kFell, kOutOfTime};
  return kOutcomes;
}

void PlatformEnv::reset(uint64_t seed, std::span<float> obs) {
  rng_.reseed(seed);
  reset(obs);
}

void PlatformEnv::reset(std::span<float> obs) {
  if (obs.size() != static_cast<size_t>(kObservationSize)) {
    misuse("reset: the observation span must hold 9 floats");
  }
  // Player.reset and Enemy.reset: the player on the left end, each enemy at its platform's right
  // end walking left.
  player_ = {0.0, kPlatformHeight, 0.0, 0.0};
  for (int i = 0; i < 2; ++i) {
    enemies_[static_cast<size_t>(i)] = {kPlatformX[i] + kWidth[i] - kSizeX, kPlatformHeight, -kEnemySpeed, 0.0};
  }
  steps_ = 0;
  last_ticks_ = 0;
  done_ = false;
  write_obs(obs);
}

double PlatformEnv::noise(double sd) {
  return config_.noise ? sd * ziggurat_normal(rng_) : 0.0;
}

bool PlatformEnv::on_platforms() const {
  // Player.on_platform: above it (its box overlaps the platform's span, edges included) and
  // standing exactly on its top.
  if (player_.y - 0.0 != kPlatformHeight) {  // every platform's top is at 40
    return false;
  }
  for (int i = 0; i < 3; ++i) {
    const double rel = player_.x - kPlatformX[i];
    if (-kSizeX <= rel && rel <= kWidth[i]) {
      return true;
    }
  }
  return false;
}

int PlatformEnv::enemy_index() const {
  return player_.x > kPlatformX[1] ? 1 : 0;
}

// Player.accelerate, always with dt = DT: the acceleration clipped, dx losing |N(0, 0.5 dt)|,
// the velocity clipped, dx never negative.
void PlatformEnv::accelerate(double ax, double ay) {
  ax = std::clamp(ax, -kMaxDdx, kMaxDdx);
  ay = std::clamp(ay, -kMaxDdy, kMaxDdy);
  player_.dx += ax * kDt;
  player_.dy += ay * kDt;
  player_.dx -= std::fabs(noise(kPlayerNoise * kDt));
  player_.dx = std::clamp(player_.dx, -kMaxDx, kMaxDx);
  player_.dy = std::clamp(player_.dy, -kMaxDy, kMaxDy);
  player_.dx = std::max(player_.dx, 0.0);
}

// Player.jump_to: the horizontal speed that covers diff_x in the jump's time, less the speed
// it has, with a launch of dy0 upward; both lose |N(0, dev)|.
void PlatformEnv::jump_to(double diff_x, double dy0, double dev) {
  const double time = 2.0 * dy0 / kGravity + 1.0;
  double dx0 = diff_x / time - player_.dx;
  dx0 = std::clamp(dx0, -kMaxDdx, kMaxDy - dy0);
  double nx = 0.0;
  double ny = 0.0;
  if (dev > 0.0) {
    nx = -std::fabs(noise(dev));
    ny = -std::fabs(noise(dev));
  }
  accelerate((dx0 + nx) / kDt, (dy0 + ny) / kDt);
}

// Enemy.update: turns at its platform's ends, its speed jittered and bounded, kept on the
// platform.
void PlatformEnv::update_enemy(Body& e, int platform) {
  const double left = kPlatformX[platform];
  const double right = left + kWidth[platform] - kSizeX;
  if (!(left < e.x && e.x < right)) {
    e.dx = -e.dx;
  }
  e.dx += noise(kEnemyNoise * kDt);
  e.dx = std::clamp(e.dx, -kEnemySpeed, kEnemySpeed);
  e.x += e.dx * kDt;
  e.x = std::clamp(e.x, left, right);
}

// PlatformEnv._update: one tick of dt.
PlatformEnv::Tick PlatformEnv::tick(int action, double param) {
  if (on_platforms()) {
    switch (action) {
      case kRun: accelerate(param / kDt, 0.0); break;  // Player.run(power, dt)
      case kHop: jump_to(param, kHopDy, kHopDev); break;
      default: jump_to(param, kLeapDy, kLeapDev); break;
    }
  } else {
    accelerate(0.0, -kGravity);  // Player.fall
  }
  if (on_platforms()) {
    player_.dx = std::clamp(player_.dx, 0.0, kMaxDxOn);  // Player.ground_bound
  }
  const int e = enemy_index();  // chosen before anything moves
  // Player.update.
  player_.x += player_.dx * kDt;
  player_.y += player_.dy * kDt;
  player_.x = std::clamp(player_.x, 0.0, kTotalWidth);
  player_.dx *= kVelocityDecay;
  update_enemy(enemies_[static_cast<size_t>(e)], e);
  // A platform the player overlaps pushes it out (Player.decollide) and stops it horizontally.
  // Every platform spans y in [0, 40], so only a player below 40 can overlap one.
  for (int i = 0; i < 3 && player_.y < kPlatformHeight; ++i) {
    const double ox = kPlatformX[i];
    const double oy = 0.0;
    if (!overlaps(player_.x, player_.y, ox, oy, kWidth[i], kPlatformHeight)) {
      continue;
    }
    double nx = player_.x;
    double ny = player_.y;
    if (player_.x < ox) {
      nx = ox - kSizeX;
    } else if (player_.x > ox + kWidth[i] - kSizeX) {
      nx = ox + kWidth[i];
    }
    if (player_.y < oy) {
      ny = oy - kSizeY;
    } else if (player_.y > oy + kPlatformHeight - kSizeY) {
      ny = oy + kPlatformHeight;
    }
    if (nx == player_.x) {
      player_.dy = 0.0;
      player_.y = ny;
    } else if (ny == player_.y) {
      player_.dx = 0.0;
      player_.x = nx;
    } else if (std::fabs(player_.x - nx) < std::fabs(player_.y - ny)) {
      player_.dx = 0.0;
      player_.x = nx;
    } else {
      player_.dy = 0.0;
      player_.y = ny;
    }
    player_.dx = 0.0;
  }
  // _terminal_check: the progress of the whole decision step so far; the end of the course
  // pays the rest of the way.
  Tick t;
  t.reward = (player_.x - step_start_x_) / kRightBound;
  if (player_.x >= kRightBound) {
    t.reward = (kRightBound - step_start_x_) / kRightBound;
    t.status = kGoal;
    return t;
  }
  // The enemies walk at y = 40, so only a player with 10 < y < 70 can touch one.
  if (kPlatformHeight - kSizeY < player_.y && player_.y < kPlatformHeight + kSizeY) {
    for (const Body& enemy : enemies_) {
      if (overlaps(player_.x, player_.y, enemy.x, enemy.y, kSizeX, kSizeY)) {
        t.status = kEnemy;
        return t;
      }
    }
  }
  if (player_.y < 0.0 + kPlatformHeight) {
    t.status = kFell;
  }
  return t;
}

StepResult PlatformEnv::step(const ParamAction& action, std::span<float> obs) {
  if (done_) {
    misuse("step() after a terminal status (or before reset()); call reset() first");
  }
  if (action.id < 0 || action.id > 2) {
    misuse("action id out of range (0 RUN, 1 HOP, 2 LEAP)");
  }
  if (action.params.size() <= static_cast<size_t>(action.id) || obs.size() != static_cast<size_t>(kObservationSize)) {
    misuse("step: the parameter vector must hold 3 values and the observation span 9 floats");
  }
  float p = action.params[static_cast<size_t>(action.id)];
  p = std::isnan(p) ? 0.0F : std::clamp(p, 0.0F, kParamMax[action.id]);
  const double param = p;
  step_start_x_ = player_.x;
  Tick t;
  // step(): RUN lasts while difft, from 1 down by dt, stays above 0 (20 ticks); a jump lasts
  // until the player stands on a platform again.
  double difft = 1.0;
  int ticks = 0;
  bool running = true;
  while (running) {
    t = tick(action.id, param);
    ++ticks;
    if (action.id == kRun) {
      difft -= kDt;
      running = difft > 0.0;
    } else {
      running = !on_platforms();
    }
    if (t.status != kInProgress || ticks >= kMaxTicksPerStep) {
      running = false;
    }
  }
  last_ticks_ = ticks;
  ++steps_;
  StepResult r;
  r.reward = static_cast<float>(t.reward);
  r.status = t.status;
  if (r.status == kInProgress && steps_ >= config_.max_steps) {
    r.status = kOutOfTime;
  }
  done_ = r.status != kInProgress;
  write_obs(obs);
  return r;
}

// get_state, _platform_features and _scale_state, then MP-DQN's ScaledStateWrapper (2 s - 1).
void PlatformEnv::write_obs(std::span<float> obs) const {
  const Body& e = enemies_[static_cast<size_t>(enemy_index())];
  double wd1 = kWidth[2];
  double wd2 = 0.0;
  double gap = 0.0;
  double pos = kPlatformX[2];
  if (player_.x < kWidth[0] + kGap1) {
    wd1 = kWidth[0];
    wd2 = kWidth[1];
    gap = kGap1;
    pos = 0.0;
  } else if (player_.x < kWidth[0] + kGap1 + kWidth[1] + kGap2) {
    wd1 = kWidth[1];
    wd2 = kWidth[2];
    gap = kGap2;
    pos = kPlatformX[1];
  }
  const double scaled[kObservationSize] = {
      (player_.x + kSizeX) / (kTotalWidth + kSizeX),
      player_.dx / kMaxDx,
      e.x / kTotalWidth,
      (e.dx + kEnemySpeed) / (2.0 * kEnemySpeed),
      wd1 / kMaxPlatformWidth,
      wd2 / kMaxPlatformWidth,
      gap / kMaxGap,
      pos / kTotalWidth,
      0.0 / kMaxHeight,
  };
  for (int i = 0; i < kObservationSize; ++i) {
    obs[static_cast<size_t>(i)] = static_cast<float>(2.0 * scaled[i] - 1.0);
  }
}

}  // namespace pamdp::platform
