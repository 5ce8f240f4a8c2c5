#include "core/log.hpp"

#include <array>

namespace pamdp::log {

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
      return true;
    }
  }
  return false;
}

}  // namespace pamdp::log
