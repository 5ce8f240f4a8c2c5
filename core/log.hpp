// The one header that includes spdlog. Everything else logs through these names, so the
// logging backend (and its formatting library) can change in one place.
#pragma once

#include <spdlog/spdlog.h>

#include <string_view>

namespace pamdp::log {

using spdlog::debug;
using spdlog::error;
using spdlog::info;
using spdlog::warn;

// Sets the global level from a name ("trace", "debug", "info", "warn", "error", "off").
// Returns false and changes nothing if the name is unknown.
bool set_level(std::string_view name);

// What --quiet asks of the log: warnings and errors only, unless a level was chosen with
// set_level (an explicit --log-level wins). Start-up only; not thread-safe with set_level.
void quiet();

}  // namespace pamdp::log
