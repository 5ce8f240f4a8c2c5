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

PlayerState offense_player(const nlohmann::json& a, const char* group, const std::string& src) {
  reject_unknown(a, group, {"x", "y", "vx", "vy", "body_deg", "stamina"}, src);
  PlayerState p;
  p.pos = {number(a, group, "x", src, {}), number(a, group, "y", src, {})};
  p.vel = {number(a, group, "vx", src, 0.0), number(a, group, "vy", src, 0.0)};
  p.body_deg = number(a, group, "body_deg", src, 0.0);
  p.stamina = number(a, group, "stamina", src, kStaminaMax);
  if (p.stamina < 0.0 || p.stamina > kStaminaMax) {
    throw std::runtime_error(src + ": " + group + ".stamina must be within [0, 8000]");
  }
  return p;
}

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  const auto last = s.find_last_not_of(" \t");
  return first == std::string::npos ? "" : s.substr(first, last - first + 1);
}

// One action, "KIND,p1[,p2]"; `where` starts every error ("file:line: ").
ScriptedAction parse_action(const std::string& text, const std::string& where) {
  std::vector<std::string> cells;
  std::stringstream ls(text);
  std::string cell;
  while (std::getline(ls, cell, ',')) {
    cells.push_back(trimmed(cell));
  }
  if (!text.empty() && text.back() == ',') {
    cells.emplace_back();  // a trailing comma is one more (empty) cell, so the arity check sees it
  }
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
  const std::string kind = cells.empty() ? trimmed(text) : cells[0];
  auto need = [&](size_t n, const char* form) {
    if (cells.size() != n) {
      throw std::runtime_error(where + "expected '" + form + "', got '" + text + "'");
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
  return a;
}

// A field defender's memory: {"kind": "dribble" | "turn_to_forward", "x", "y", "turns", "dashes"},
// queued the cycle before the state's (PlayerState::Intention).
PlayerState::Intention parse_intention(const nlohmann::json& j, const std::string& group, const std::string& src) {
  const char* g = group.c_str();
  if (!j.is_object()) {
    throw std::runtime_error(src + ": \"" + group + "\" must be an object");
  }
  reject_unknown(j, g, {"kind", "x", "y", "turns", "dashes"}, src);
  PlayerState::Intention in;
  const std::string kind = j.contains("kind") && j["kind"].is_string() ? j["kind"].get<std::string>() : "";
  if (kind == "dribble") {
    in.kind = PlayerState::Intention::Kind::kDribble;
  } else if (kind == "turn_to_forward") {
    in.kind = PlayerState::Intention::Kind::kTurnToForward;
  } else {
    throw std::runtime_error(src + ": " + group + ".kind must be \"dribble\" (the self-pass's queued turns and " +
                             "dashes) or \"turn_to_forward\" (the turn after a keep kick)");
  }
  in.target = {number(j, g, "x", src, {}), number(j, g, "y", src, {})};
  for (const char* key : {"turns", "dashes"}) {
    const double v = number(j, g, key, src, 0.0);
    if (v < 0.0 || v > 30.0 || v != std::floor(v)) {
      throw std::runtime_error(src + ": " + group + "." + key + " must be a whole number within [0, 30]");
    }
    (std::string(key) == "turns" ? in.turns : in.dashes) = static_cast<int>(v);
  }
  in.last_cycle = -1;  // queued the cycle before the state's first, cycle 0
  return in;
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
  reject_unknown(j, "", {"agent", "ball", "teammates", "goalie", "defenders"}, src);
  const auto& b = j["ball"];
  reject_unknown(b, "ball", {"x", "y", "vx", "vy"}, src);
  InitialState s;
  s.agent = offense_player(j["agent"], "agent", src);
  if (j.contains("teammates")) {
    const auto& mates = j["teammates"];
    if (!mates.is_array() || mates.size() > static_cast<size_t>(kMaxOffenseAgents - 1)) {
      throw std::runtime_error(src + ": \"teammates\" must be an array of at most " +
                               std::to_string(kMaxOffenseAgents - 1) + " objects (the agent is player 0)");
    }
    for (size_t i = 0; i < mates.size(); ++i) {
      const std::string group = "teammates[" + std::to_string(i) + "]";
      if (!mates[i].is_object()) {
        throw std::runtime_error(src + ": \"" + group + "\" must be an object");
      }
      s.teammates.push_back(offense_player(mates[i], group.c_str(), src));
    }
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
  if (j.contains("defenders")) {
    const auto& ds = j["defenders"];
    if (!ds.is_array() || ds.size() > static_cast<size_t>(kMaxFieldDefenders)) {
      throw std::runtime_error(src + ": \"defenders\" must be an array of at most " +
                               std::to_string(kMaxFieldDefenders) +
                               " objects (agent2d's field defenders, unums 2 and 3)");
    }
    for (size_t i = 0; i < ds.size(); ++i) {
      const std::string group = "defenders[" + std::to_string(i) + "]";
      const char* g = group.c_str();
      if (!ds[i].is_object()) {
        throw std::runtime_error(src + ": \"" + group + "\" must be an object");
      }
      reject_unknown(ds[i], g,
                     {"x", "y", "vx", "vy", "body_deg", "stamina", "tackle_cycles", "intention", "recover_mode"}, src);
      PlayerState d;
      d.pos = {number(ds[i], g, "x", src, {}), number(ds[i], g, "y", src, {})};
      d.vel = {number(ds[i], g, "vx", src, 0.0), number(ds[i], g, "vy", src, 0.0)};
      d.body_deg = number(ds[i], g, "body_deg", src, kGoalieStartBodyDeg);
      d.stamina = number(ds[i], g, "stamina", src, kStaminaMax);
      if (d.stamina < 0.0 || d.stamina > kStaminaMax) {
        throw std::runtime_error(src + ": " + group + ".stamina must be within [0, 8000]");
      }
      const double frozen = number(ds[i], g, "tackle_cycles", src, 0.0);
      if (frozen < 0.0 || frozen > kTackleCycles || frozen != std::floor(frozen)) {
        throw std::runtime_error(src + ": " + group + ".tackle_cycles must be a whole number of cycles within [0, " +
                                 std::to_string(kTackleCycles) + "]");
      }
      d.tackle_cycles = static_cast<int>(frozen);
      if (ds[i].contains("recover_mode")) {
        if (!ds[i]["recover_mode"].is_boolean()) {
          throw std::runtime_error(src + ": " + group + ".recover_mode must be true or false");
        }
        d.recover_mode = ds[i]["recover_mode"].get<bool>();
      }
      if (ds[i].contains("intention")) {
        d.intention = parse_intention(ds[i]["intention"], group + ".intention", src);
      }
      s.defenders.push_back(d);
    }
  }
  return s;
}

InitialState load_state_json(const std::string& path) {
  return parse_state_json(read_file(path), path);
}

std::vector<TeamActions> parse_team_actions_csv(const std::string& text, const std::string& src, int players) {
  if (players < 1) {
    throw std::invalid_argument("parse_team_actions_csv: players must be >= 1");
  }
  std::vector<TeamActions> out;
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
    const std::string where = src + ":" + std::to_string(line_no) + ": ";
    TeamActions row;
    size_t from = 0;
    while (true) {
      const size_t bar = line.find('|', from);
      row.push_back(parse_action(line.substr(from, bar == std::string::npos ? std::string::npos : bar - from), where));
      if (bar == std::string::npos) {
        break;
      }
      from = bar + 1;
    }
    if (static_cast<int>(row.size()) != players) {
      throw std::runtime_error(where + "expected " + std::to_string(players) + " action" + (players == 1 ? "" : "s") +
                               " separated by '|' (one per offense player), got " + std::to_string(row.size()));
    }
    out.push_back(std::move(row));
  }
  return out;
}

std::vector<TeamActions> load_team_actions_csv(const std::string& path, int players) {
  return parse_team_actions_csv(read_file(path), path, players);
}

std::vector<ScriptedAction> parse_actions_csv(const std::string& text, const std::string& src) {
  std::vector<ScriptedAction> out;
  for (auto& row : parse_team_actions_csv(text, src, 1)) {
    out.push_back(row[0]);
  }
  return out;
}

std::vector<ScriptedAction> load_actions_csv(const std::string& path) {
  return parse_actions_csv(read_file(path), path);
}

}  // namespace pamdp::hfo
