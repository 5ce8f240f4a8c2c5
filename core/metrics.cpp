#include "core/metrics.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace pamdp::metrics {
namespace {

bool valid_name(std::string_view s, bool allow_colon) {
  if (s.empty()) {
    return false;
  }
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || (allow_colon && c == ':');
    if (!alpha && !(i > 0 && c >= '0' && c <= '9')) {
      return false;
    }
  }
  return true;
}

void escape_into(std::string& out, std::string_view s, bool quote) {
  for (const char c : s) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (quote && c == '"') {
      out += "\\\"";
    } else {
      out += c;
    }
  }
}

bool is_space(char c) {
  return c == ' ' || c == '\t';
}

}  // namespace

std::string format_value(double v) {
  if (std::isnan(v)) {
    return "NaN";
  }
  if (std::isinf(v)) {
    return v > 0 ? "+Inf" : "-Inf";
  }
  char buf[32];
  if (v == std::trunc(v) && std::fabs(v) < 1e15) {
    std::snprintf(buf, sizeof(buf), "%.0f", v);
  } else {
    std::snprintf(buf, sizeof(buf), "%.15g", v);
  }
  return buf;
}

size_t Registry::family(const std::string& name, const std::string& help, Kind kind) {
  if (!valid_name(name, /*allow_colon=*/true)) {
    throw std::invalid_argument("metrics: '" + name + "' is not a valid metric name ([a-zA-Z_:][a-zA-Z0-9_:]*)");
  }
  if (kind == Kind::kCounter && (name.size() < 6 || name.compare(name.size() - 6, 6, "_total") != 0)) {
    throw std::invalid_argument("metrics: counter '" + name + "' must be named *_total");
  }
  for (size_t i = 0; i < families_.size(); ++i) {
    if (families_[i].name == name) {
      if (families_[i].kind != kind) {
        throw std::invalid_argument("metrics: '" + name + "' registered both as a counter and as a gauge");
      }
      return i;
    }
  }
  families_.push_back({name, help, kind});
  return families_.size() - 1;
}

std::string Registry::add_series(size_t fam, const Labels& labels) {
  std::string rendered;
  for (const auto& [k, v] : labels) {
    if (!valid_name(k, /*allow_colon=*/false) || k.rfind("__", 0) == 0) {
      throw std::invalid_argument("metrics: '" + k + "' is not a valid label name");
    }
    rendered += rendered.empty() ? "{" : ",";
    rendered += k;
    rendered += "=\"";
    escape_into(rendered, v, /*quote=*/true);
    rendered += '"';
  }
  if (!rendered.empty()) {
    rendered += '}';
  }
  for (const Series& s : series_) {
    if (s.family == fam && s.labels == rendered) {
      throw std::invalid_argument("metrics: '" + families_[fam].name + rendered + "' registered twice");
    }
  }
  return rendered;
}

Counter& Registry::counter(const std::string& name, const std::string& help, const Labels& labels) {
  const std::lock_guard lock(mutex_);
  const size_t fam = family(name, help, Kind::kCounter);
  std::string rendered = add_series(fam, labels);
  Counter& c = counters_.emplace_back();
  series_.push_back({fam, std::move(rendered), &c, nullptr});
  return c;
}

Gauge& Registry::gauge(const std::string& name, const std::string& help, const Labels& labels) {
  const std::lock_guard lock(mutex_);
  const size_t fam = family(name, help, Kind::kGauge);
  std::string rendered = add_series(fam, labels);
  Gauge& g = gauges_.emplace_back();
  series_.push_back({fam, std::move(rendered), nullptr, &g});
  return g;
}

void Registry::on_collect(std::function<void()> hook) {
  const std::lock_guard lock(mutex_);
  hooks_.push_back(std::move(hook));
}

std::string Registry::render() const {
  const std::lock_guard lock(mutex_);
  for (const auto& hook : hooks_) {
    hook();
  }
  std::string out;
  out.reserve(series_.size() * 96 + families_.size() * 128);
  for (size_t f = 0; f < families_.size(); ++f) {
    const Family& fam = families_[f];
    out += "# HELP ";
    out += fam.name;
    out += ' ';
    escape_into(out, fam.help, /*quote=*/false);
    out += "\n# TYPE ";
    out += fam.name;
    out += fam.kind == Kind::kCounter ? " counter\n" : " gauge\n";
    for (const Series& s : series_) {
      if (s.family != f) {
        continue;
      }
      out += fam.name;
      out += s.labels;
      out += ' ';
      out += s.counter != nullptr ? std::to_string(s.counter->value()) : format_value(s.gauge->value());
      out += '\n';
    }
  }
  return out;
}

const std::string* Sample::label(std::string_view key) const {
  for (const auto& [k, v] : labels) {
    if (k == key) {
      return &v;
    }
  }
  return nullptr;
}

std::vector<Sample> parse_exposition(std::string_view text, int* bad_lines) {
  std::vector<Sample> out;
  int bad = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) {
      end = text.size();
    }
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    while (!line.empty() && (is_space(line.front()) || line.front() == '\r')) {
      line.remove_prefix(1);
    }
    while (!line.empty() && (is_space(line.back()) || line.back() == '\r')) {
      line.remove_suffix(1);
    }
    if (line.empty() || line.front() == '#') {
      continue;
    }
    Sample s;
    size_t i = 0;
    while (i < line.size() && !is_space(line[i]) && line[i] != '{') {
      ++i;
    }
    s.name = std::string(line.substr(0, i));
    bool ok = valid_name(s.name, /*allow_colon=*/true);
    if (ok && i < line.size() && line[i] == '{') {
      ++i;
      while (ok) {
        while (i < line.size() && (is_space(line[i]) || line[i] == ',')) {
          ++i;
        }
        if (i < line.size() && line[i] == '}') {
          ++i;
          break;
        }
        const size_t eq = line.find('=', i);
        if (eq == std::string_view::npos || eq + 1 >= line.size() || line[eq + 1] != '"') {
          ok = false;
          break;
        }
        std::string key(line.substr(i, eq - i));
        while (!key.empty() && is_space(key.back())) {
          key.pop_back();
        }
        std::string value;
        size_t j = eq + 2;
        for (; j < line.size() && line[j] != '"'; ++j) {
          if (line[j] == '\\' && j + 1 < line.size()) {
            ++j;
            value += line[j] == 'n' ? '\n' : line[j];
          } else {
            value += line[j];
          }
        }
        if (j >= line.size()) {
          ok = false;
          break;
        }
        s.labels.emplace_back(std::move(key), std::move(value));
        i = j + 1;
      }
    }
    while (ok && i < line.size() && is_space(line[i])) {
      ++i;
    }
    if (ok) {
      std::string value(line.substr(i, line.find_first_of(" \t", i) - i));
      if (value == "+Inf" || value == "Inf") {
        s.value = INFINITY;
      } else if (value == "-Inf") {
        s.value = -INFINITY;
      } else if (value == "NaN") {
        s.value = NAN;
      } else {
        char* stop = nullptr;
        s.value = std::strtod(value.c_str(), &stop);
        ok = !value.empty() && stop == value.c_str() + value.size();
      }
    }
    if (ok) {
      out.push_back(std::move(s));
    } else {
      ++bad;
    }
  }
  if (bad_lines != nullptr) {
    *bad_lines = bad;
  }
  return out;
}

}  // namespace pamdp::metrics
