#include "run_kanesim.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <utility>

namespace kanesim::stress {
namespace {

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Splits a CSV line at commas outside double quotes (kanesim quotes signal names such as
// "s.body.R[1,2]"; no name holds a quote).
std::vector<std::string> SplitComma(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
      continue;
    }
    if (c == ',' && !quoted) {
      out.emplace_back();
      continue;
    }
    out.back() += c;
  }
  return out;
}

void ParseCsv(const std::string& path, RunResult* r) {
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return;
  r->header = SplitComma(line);
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    for (const std::string& c : SplitComma(line)) row.push_back(std::strtod(c.c_str(), nullptr));
    r->rows.push_back(std::move(row));
  }
}

}  // namespace

std::string SourcePath(const std::string& rel) { return std::string(KANESIM_SOURCE_DIR) + "/" + rel; }

int RunResult::Index(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

std::vector<double> RunResult::Column(const std::string& name) const {
  const int i = Index(name);
  EXPECT_GE(i, 0) << "no column '" << name << "'";
  std::vector<double> out;
  if (i < 0) return out;
  for (const auto& row : rows) out.push_back(row[static_cast<size_t>(i)]);
  return out;
}

std::vector<std::pair<double, std::string>> RunResult::Events() const {
  std::vector<std::pair<double, std::string>> events;
  const std::regex line("t = ([0-9.eE+-]+)\\s+(\\S+):");
  for (auto it = std::sregex_iterator(stderr_text.begin(), stderr_text.end(), line); it != std::sregex_iterator(); ++it)
    events.push_back({std::stod((*it)[1]), (*it)[2]});
  return events;
}

const std::vector<double>& RunResult::RowAt(double t) const {
  size_t best = 0;
  for (size_t k = 0; k < rows.size(); ++k)
    if (std::fabs(rows[k][0] - t) < std::fabs(rows[best][0] - t)) best = k;
  return rows.at(best);
}

RunResult RunKanesim(const std::string& model, const std::vector<std::string>& args) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string id = std::string(info->test_suite_name()) + "_" + info->name();
  for (char& c : id)
    if (c == '/') c = '_';  // parameterized names: "AllPaths/Suite.Name/3"
  // The process id too: several builds' suites (CI beside a developer's) share /tmp.
  const std::string stem = ::testing::TempDir() + "kanesim_stress_" + id + "_" + std::to_string(::getpid());
  const std::string csv = stem + ".csv", err = stem + ".err";
  std::remove(csv.c_str());
  std::string cmd = Quote(KANESIM_EXE) + " run " + Quote(SourcePath(model));
  for (const std::string& a : args) cmd += " " + Quote(a);
  cmd += " -o " + Quote(csv) + " 2> " + Quote(err);
  RunResult r;
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err);
  std::stringstream ss;
  ss << e.rdbuf();
  r.stderr_text = ss.str();
  ParseCsv(csv, &r);
  std::remove(csv.c_str());
  std::remove(err.c_str());
  return r;
}

RunResult ReadCsv(const std::string& path_in_source) {
  RunResult r;
  r.exit_code = 0;
  ParseCsv(SourcePath(path_in_source), &r);
  EXPECT_FALSE(r.rows.empty()) << "cannot read " << path_in_source;
  return r;
}

}  // namespace kanesim::stress
