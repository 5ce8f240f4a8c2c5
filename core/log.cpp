#include "core/log.hpp"

#include <array>

namespace pamdp::log {
namespace {

bool g_level_chosen = false;  // set_level was called: --quiet leaves the level alone

}  // namespace

bool set_level(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, spdlog::level::level_enum>, 6> kLevels{{
      {"trace", spdlog::level::trace},
      {"debug", spdlog::level::debug},
      {"info", spdlog::level::info},
      {"warn", spdlog::level::warn},
      {"error", spdlog::level::err},
      {"off", spdlog::level::off},
  }};
  for (const auto& [n, level] : kLevels) {
    if (n == name) {
      spdlog::set_level(level);
      g_level_chosen = true;
      return true;
    }
  }
  return false;
}

void quiet() {
  if (!g_level_chosen && spdlog::get_level() < spdlog::level::warn) {
    spdlog::set_level(spdlog::level::warn);
  }
}

}  // namespace pamdp::log
