#include "envs/hfo/state_io.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "envs/hfo/hfo_env.hpp"

namespace pamdp::hfo {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw std::runtime_error("cannot open '" + path + "': check the path and permissions");
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

double number(const nlohmann::json& obj, const char* group, const char* key, const std::string& src,
              std::optional<double> fallback) {
  if (!obj.contains(key)) {
    if (fallback) {
      return *fallback;
    }
    throw std::runtime_error(src + ": missing key '" + group + "." + key + "'");
  }
  const auto& v = obj.at(key);
  if (!v.is_number()) {
    throw std::runtime_error(src + ": '" + group + "." + key + "' must be a number");
  }
  return v.get<double>();
}

void reject_unknown(const nlohmann::json& obj, const char* group, std::initializer_list<const char*> known,
                    const std::string& src) {
  for (const auto& [k, v] : obj.items()) {
    bool ok = false;
    std::string valid;
    for (const char* name : known) {
      ok = ok || k == name;
      valid += std::string(valid.empty() ? "" : ", ") + name;
    }
    if (!ok) {
      throw std::runtime_error(src + ": unknown key '" + group + "." + k + "' (valid: " + valid + ")");
    }
  }
}

}  // namespace

InitialState parse_state_json(const std::string& text, const std::string& src) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(src + ": not valid JSON: " + e.what());
  }
  if (!j.is_object() || !j.contains("agent") || !j.contains("ball") || !j["agent"].is_object() ||
      !j["ball"].is_object()) {
    throw std::runtime_error(src + ": expected an object with \"agent\" and \"ball\" objects");
  }
  reject_unknown(j, "", {"agent", "ball", "goalie"}, src);
  const auto& a = j["agent"];
  const auto& b = j["ball"];
  reject_unknown(a, "agent", {"x", "y", "vx", "vy", "body_deg", "stamina"}, src);
  reject_unknown(b, "ball", {"x", "y", "vx", "vy"}, src);
  InitialState s;
  s.agent.pos = {number(a, "agent", "x", src, {}), number(a, "agent", "y", src, {})};
  s.agent.vel = {number(a, "agent", "vx", src, 0.0), number(a, "agent", "vy", src, 0.0)};
  s.agent.body_deg = number(a, "agent", "body_deg", src, 0.0);
  s.agent.stamina = number(a, "agent", "stamina", src, kStaminaMax);
  if (s.agent.stamina < 0.0 || s.agent.stamina > kStaminaMax) {
    throw std::runtime_error(src + ": agent.stamina must be within [0, 8000]");
  }
  s.ball.pos = {number(b, "ball", "x", src, {}), number(b, "ball", "y", src, {})};
  s.ball.vel = {number(b, "ball", "vx", src, 0.0), number(b, "ball", "vy", src, 0.0)};
  if (j.contains("goalie")) {
    const auto& g = j["goalie"];
    if (!g.is_object()) {
      throw std::runtime_error(src + ": \"goalie\" must be an object");
    }
    reject_unknown(g, "goalie", {"x", "y", "vx", "vy", "body_deg", "stamina", "since_catch", "tackle_cycles", "caught"},
                   src);
    s.has_goalie = true;
    s.goalie.pos = {number(g, "goalie", "x", src, kGoalieStart.x), number(g, "goalie", "y", src, kGoalieStart.y)};
    s.goalie.vel = {number(g, "goalie", "vx", src, 0.0), number(g, "goalie", "vy", src, 0.0)};
    s.goalie.body_deg = number(g, "goalie", "body_deg", src, kGoalieStartBodyDeg);
    s.goalie.stamina = number(g, "goalie", "stamina", src, kStaminaMax);
    if (s.goalie.stamina < 0.0 || s.goalie.stamina > kStaminaMax) {
      throw std::runtime_error(src + ": goalie.stamina must be within [0, 8000]");
    }
    const double since = number(g, "goalie", "since_catch", src, PlayerState::kNoCatchYet);
    if (since < 0.0 || since != std::floor(since)) {
      throw std::runtime_error(src + ": goalie.since_catch must be a whole number of cycles >= 0");
    }
    s.goalie.since_catch = static_cast<int>(std::min(since, static_cast<double>(PlayerState::kNoCatchYet)));
    const double frozen = number(g, "goalie", "tackle_cycles", src, 0.0);
    if (frozen < 0.0 || frozen > kTackleCycles || frozen != std::floor(frozen)) {
      throw std::runtime_error(src + ": goalie.tackle_cycles must be a whole number of cycles within [0, " +
                               std::to_string(kTackleCycles) + "]");
    }
    s.goalie.tackle_cycles = static_cast<int>(frozen);
    if (g.contains("caught")) {
      if (!g["caught"].is_boolean()) {
        throw std::runtime_error(src + ": goalie.caught must be true or false");
      }
      s.goalie.caught = g["caught"].get<bool>();
    }
  }
  return s;
}

InitialState load_state_json(const std::string& path) {
  return parse_state_json(read_file(path), path);
}

std::vector<ScriptedAction> parse_actions_csv(const std::string& text, const std::string& src) {
  std::vector<ScriptedAction> out;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) {
      line.pop_back();
    }
    const auto first_char = line.find_first_not_of(" \t");
    if (first_char == std::string::npos || line[first_char] == '#') {
      continue;
    }
    std::vector<std::string> cells;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) {
      const auto first = cell.find_first_not_of(" \t");
      const auto last = cell.find_last_not_of(" \t");
      cells.push_back(first == std::string::npos ? "" : cell.substr(first, last - first + 1));
    }
    if (line.back() == ',') {
      cells.emplace_back();  // a trailing comma is one more (empty) cell, so the arity check sees it
    }
    const std::string where = src + ":" + std::to_string(line_no) + ": ";
    auto num = [&](size_t i) {
      double v = 0.0;
      const std::string& c = cells[i];
      const auto [ptr, ec] = std::from_chars(c.data(), c.data() + c.size(), v);
      if (ec != std::errc() || ptr != c.data() + c.size()) {
        throw std::runtime_error(where + "'" + c + "' is not a number");
      }
      return static_cast<float>(v);
    };
    ScriptedAction a;
    const std::string& kind = cells.empty() ? line : cells[0];
    auto need = [&](size_t n, const char* form) {
      if (cells.size() != n) {
        throw std::runtime_error(where + "expected '" + form + "', got '" + line + "'");
      }
    };
    if (kind == "DASH") {
      need(3, "DASH,power,dir");
      a.id = kDash;
      a.params[param::kDashPower] = num(1);
      a.params[param::kDashDir] = num(2);
    } else if (kind == "TURN") {
      need(2, "TURN,dir");
      a.id = kTurn;
      a.params[param::kTurnDir] = num(1);
    } else if (kind == "TACKLE") {
      need(2, "TACKLE,dir");
      a.id = kTackle;
      a.params[param::kTackleDir] = num(1);
    } else if (kind == "KICK") {
      need(3, "KICK,power,dir");
      a.id = kKick;
      a.params[param::kKickPower] = num(1);
      a.params[param::kKickDir] = num(2);
    } else {
      throw std::runtime_error(where + "unknown action '" + kind + "' (valid: DASH, TURN, TACKLE, KICK)");
    }
    out.push_back(a);
  }
  return out;
}

std::vector<ScriptedAction> load_actions_csv(const std::string& path) {
  return parse_actions_csv(read_file(path), path);
}

}  // namespace pamdp::hfo
