// Rows of a CSV file with a header line, cells looked up by column name (the recorded
// real-server data in tests/data). Empty or missing cells read as 0 through num().
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

namespace pamdp::testing {

struct CsvRow {
  std::unordered_map<std::string, std::string> cells;
  [[nodiscard]] double num(const std::string& key) const {
    const auto it = cells.find(key);
    if (it == cells.end() || it->second.empty()) {
      return 0.0;
    }
    return std::stod(it->second);
  }
  [[nodiscard]] bool empty(const std::string& key) const {
    const auto it = cells.find(key);
    return it == cells.end() || it->second.empty();
  }
  [[nodiscard]] const std::string& str(const std::string& key) const { return cells.at(key); }
};

inline std::vector<CsvRow> load_csv_rows(const std::string& path) {
  std::ifstream in(path);
  std::vector<CsvRow> rows;
  if (!in) {
    return rows;
  }
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
      header.push_back(cell);
    }
  }
  while (std::getline(in, line)) {
    if (line.empty()) {
      continue;
    }
    CsvRow r;
    std::stringstream ss(line);
    std::string cell;
    size_t i = 0;
    while (std::getline(ss, cell, ',') && i < header.size()) {
      r.cells[header[i++]] = cell;
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

}  // namespace pamdp::testing
