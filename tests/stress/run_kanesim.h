// Runs the built `kanesim` binary for the stress suite and reads what it wrote: the exit
// code, stderr and the CSV (header + rows of numbers).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace kanesim::stress {

struct RunResult {
  int exit_code = -1;
  std::string stderr_text;
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  double wall_seconds = 0.0;
  // The column named `name`; fails the calling test (and returns an empty vector) if absent.
  std::vector<double> Column(const std::string& name) const;
  // The row whose time is closest to t.
  const std::vector<double>& RowAt(double t) const;
  int Index(const std::string& name) const;  // -1 if absent
  // The events `--stats` listed on stderr ("  t = 0.16...  j[3]: slips, ..."): (time, element).
  std::vector<std::pair<double, std::string>> Events() const;
};

// `kanesim run <model> <args...> -o <tmp.csv>`; model is relative to the source tree.
RunResult RunKanesim(const std::string& model, const std::vector<std::string>& args);

// Reads a reference CSV of the source tree (header + numeric rows).
RunResult ReadCsv(const std::string& path_in_source);

std::string SourcePath(const std::string& rel);

}  // namespace kanesim::stress
