// A CSV file of numbers under a header line of column names (what `kanesim run` writes, and
// the reference trajectories in tests/*/data), read for tests that compare runs with them.
// sim/csv.h writes such files; this reads them back.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace kanesim::test {

struct CsvTable {
  std::vector<std::string> names;           // the header's fields
  std::vector<std::vector<double>> rows;    // one per line after it
  // The index of column `name`, or -1.
  int Column(const std::string& name) const {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return static_cast<int>(i);
    return -1;
  }
};

// Empty when the file cannot be opened; a field that is not a number reads as NaN.
inline CsvTable ReadCsvTable(const std::string& path) {
  CsvTable t;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return t;
  std::istringstream header(line);
  for (std::string f; std::getline(header, f, ',');) t.names.push_back(f);
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    std::istringstream ls(line);
    for (std::string f; std::getline(ls, f, ',');) {
      char* end = nullptr;
      const double x = std::strtod(f.c_str(), &end);
      row.push_back(end != f.c_str() ? x : std::numeric_limits<double>::quiet_NaN());
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

}  // namespace kanesim::test
