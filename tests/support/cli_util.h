// Running the kanesim binary from a test: its exit code, stdout and stderr, and files.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace kanesim::clitest {

inline std::string Bin() {
  const char* b = std::getenv("KANESIM_TEST_BIN");
  return b && *b ? b : KANESIM_BIN;
}
inline const std::string kSrc = KANESIM_SOURCE_DIR;

// A fresh folder under the build tree's work directory.
inline std::string Work(const std::string& name) {
  std::string d = std::string(KANESIM_WORK_DIR) + "/" + name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

inline std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void Write(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

struct Result {
  int rc = -1;
  std::string out, err;
};

// `kanesim ARGS` (a shell command line after the binary), run in `dir`. The captured streams
// go to files named by this process and call: tests run in parallel and many share the
// default folder (a shared ".stdout" once gave one test another test's output).
inline Result Kanesim(const std::string& args, const std::string& dir = KANESIM_WORK_DIR) {
  static int calls = 0;
  const std::string tag = std::to_string(::getpid()) + "." + std::to_string(++calls);
  const std::string out = dir + "/.stdout." + tag, err = dir + "/.stderr." + tag;
  // A time limit, so that a binary without the fixes fails instead of hanging.
  int rc = std::system(("cd '" + dir + "' && timeout 120 '" + Bin() + "' " + args + " >'" + out + "' 2>'" + err + "'")
                           .c_str());
  Result r;
  r.rc = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = Slurp(out);
  r.err = Slurp(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

inline bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Data rows of a CSV (lines after the header, '#' lines skipped).
inline int CsvRows(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  int n = -1;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#') ++n;
  return n < 0 ? 0 : n;
}

// Fields of one CSV line (quoted fields may hold commas; the quotes are dropped).
inline std::vector<std::string> CsvFields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) out.emplace_back();
    else out.back() += c;
  }
  return out;
}

}  // namespace kanesim::clitest
