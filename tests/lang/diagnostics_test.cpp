// Data-driven diagnostic tests: one file per diagnostic code in tests/lang/diagnostics/,
// named <CODE>_<short>.mech, with the expected diagnostics written inline where they must
// point (see tests/README.md):
//
//   Revolute j(axs = {0, 0, 1});  // expect: E203 "did you mean 'axis'"
//   x = (1 + 2;                   // expect: P102 "opened here" col 13
//                                 // expect-global: E221        (any location, or none)
//   // set: N=abc                 (an ElaborateOptions override, like --set N=abc)
//   // model: Pkg.M               (the model to elaborate; default: the last one)
//   // pad-to-bytes: 4194305      (pads the text with spaces, for L005)
//
// Each expected code must be reported on that line (and column, if given) of the file, with
// the quoted text somewhere in the rendered diagnostic (message, snippet, notes, hint). Every
// error must be expected; unexpected warnings are allowed. A failure means a diagnostic
// changed code or place, vanished, or a new spurious error appeared.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "lang/diagnostics.h"
#include "lang/parser.h"
#include "lang/source.h"
#include "stdlib/stdlib.h"
#ifdef KANESIM_HAVE_ELABORATE
#include "lang/elaborate.h"
#endif

namespace kanesim::lang {
namespace {

namespace fs = std::filesystem;

struct Expectation {
  std::string code;   // "E203"
  int line = 0;       // 1-based; 0 = anywhere (expect-global)
  int col = 0;        // 0 = any
  std::string text;   // substring of the rendered diagnostic; "" = any
  bool matched = false;
};

struct DiagFile {
  std::string name;  // file name, also the display name given to the loader
  std::string text;
  std::vector<Expectation> expects;
  std::vector<std::pair<std::string, std::string>> overrides;
  std::string model;
};

std::vector<fs::path> DiagnosticFiles() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(KANESIM_DIAGNOSTICS_DIR))
    if (e.is_regular_file() && e.path().extension() == ".mech") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Parses the inline expectations and directives of one file.
DiagFile LoadDiagFile(const fs::path& path) {
  DiagFile f;
  f.name = path.filename().string();
  f.text = ReadFile(path);
  static const std::regex expect_re(R"re(expect(-global)?:\s*([LPEW]\d{3})(?:\s+"([^"]*)")?(?:\s+col\s+(\d+))?)re");
  static const std::regex set_re(R"re(//\s*set:\s*([^=\s]+)\s*=\s*(.*\S))re");
  static const std::regex model_re(R"re(//\s*model:\s*(\S+))re");
  static const std::regex pad_re(R"re(//\s*pad-to-bytes:\s*(\d+))re");
  std::istringstream lines(f.text);
  std::string line;
  size_t pad_to = 0;
  for (int n = 1; std::getline(lines, line); ++n) {
    size_t comment = line.find("//");
    if (comment == std::string::npos) continue;
    std::string tail = line.substr(comment);
    for (std::sregex_iterator it(tail.begin(), tail.end(), expect_re), end; it != end; ++it) {
      Expectation e;
      e.code = (*it)[2];
      e.line = (*it)[1].matched ? 0 : n;
      e.text = (*it)[3];
      if ((*it)[4].matched) e.col = std::stoi((*it)[4]);
      f.expects.push_back(e);
    }
    std::smatch m;
    if (std::regex_search(tail, m, set_re)) f.overrides.emplace_back(m[1], m[2]);
    if (std::regex_search(tail, m, model_re)) f.model = m[1];
    if (std::regex_search(tail, m, pad_re)) pad_to = std::stoul(m[1]);
  }
  if (f.text.size() < pad_to) f.text.append(pad_to - f.text.size(), ' ');
  return f;
}

bool NeedsElaborator(const DiagFile& f) {
  for (const auto& e : f.expects)
    if (e.code[0] == 'E' || e.code[0] == 'W') return true;
  return false;
}

std::string Describe(const Expectation& e) {
  std::string s = e.code + (e.line ? " at line " + std::to_string(e.line) : " anywhere");
  if (e.col) s += " col " + std::to_string(e.col);
  if (!e.text.empty()) s += " containing \"" + e.text + "\"";
  return s;
}

// Matches diagnostics to expectations; returns the failures, one per line.
std::string Check(DiagFile& f, const Diagnostics& diags, int main_file) {
  std::string failures;
  const SourceManager& sm = diags.Sources();
  for (const Diagnostic& d : diags.All()) {
    std::string rendered = diags.Render(d);
    LineCol lc;
    bool in_main = d.span.valid() && d.span.file == main_file;
    if (in_main) lc = sm.Locate(d.span.file, d.span.begin);
    bool matched = false;
    for (Expectation& e : f.expects) {
      if (e.matched || e.code != DiagCodeString(d.code)) continue;
      if (e.line != 0 && (!in_main || lc.line != e.line)) continue;
      if (e.col != 0 && (!in_main || lc.col != e.col)) continue;
      if (!e.text.empty() && rendered.find(e.text) == std::string::npos) continue;
      e.matched = matched = true;
      break;
    }
    if (!matched && d.severity == Severity::Error) failures += "unexpected diagnostic:\n" + rendered;
  }
  for (const Expectation& e : f.expects)
    if (!e.matched) failures += "missing: " + Describe(e) + "\n";
  if (!failures.empty()) failures += "all diagnostics:\n" + diags.RenderAll();
  return failures;
}

class DiagnosticFileTest : public ::testing::TestWithParam<fs::path> {};

TEST_P(DiagnosticFileTest, ReportsExactlyTheExpectedDiagnostics) {
  DiagFile f = LoadDiagFile(GetParam());
  ASSERT_FALSE(f.expects.empty()) << f.name << " has no '// expect:' comment";
#ifdef KANESIM_HAVE_ELABORATE
  const auto stdlib = kanesim::stdlib::Files();
  if (NeedsElaborator(f) && stdlib.empty()) GTEST_SKIP() << "the standard library (stdlib/*.mech) is not written yet";
  Program program;
  Diagnostics diags(&program.sources);
  if (LoadProgramFromText(f.name, f.text, stdlib, &program, diags)) {
    ElaborateOptions options;
    options.model = f.model;
    for (const auto& [name, value] : f.overrides) options.overrides.push_back({name, value});
    flat::Mechanism mechanism;
    Elaborate(program, options, &mechanism, diags);
  }
  int main_file = -1;
  for (int i = 0; i < program.sources.NumFiles(); ++i)
    if (program.sources.Name(i) == f.name) main_file = i;
  EXPECT_EQ(Check(f, diags, main_file), "") << f.name;
#else
  if (NeedsElaborator(f)) GTEST_SKIP() << "lang/elaborate.cpp is not written yet";
  SourceManager sm;
  Diagnostics diags(&sm);
  int file = sm.Add(f.name, f.text);
  Parse(file, sm, diags);
  EXPECT_EQ(Check(f, diags, file), "") << f.name;
#endif
}

std::string TestName(const ::testing::TestParamInfo<fs::path>& info) {
  std::string s = info.param.stem().string();
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Files, DiagnosticFileTest, ::testing::ValuesIn(DiagnosticFiles()), TestName);

// Every code of the one diagnostic table has its file, and each file is named after a code
// it expects: a new code without a test, or a misnamed file, fails here.
TEST(DiagnosticFiles, EveryCodeOfTheTableHasAFile) {
  std::vector<std::string> codes;
#define KANESIM_X(e, code, summary) codes.push_back(code);
  KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
  std::vector<fs::path> files = DiagnosticFiles();
  for (const std::string& code : codes) {
    bool found = std::any_of(files.begin(), files.end(),
                             [&](const fs::path& p) { return p.filename().string().rfind(code + "_", 0) == 0; });
    EXPECT_TRUE(found) << "no tests/lang/diagnostics/" << code << "_<short>.mech";
  }
  for (const fs::path& p : files) {
    DiagFile f = LoadDiagFile(p);
    std::string code = f.name.substr(0, 4);
    EXPECT_NE(std::find(codes.begin(), codes.end(), code), codes.end()) << f.name << ": no such code";
    bool expects_own = std::any_of(f.expects.begin(), f.expects.end(),
                                   [&](const Expectation& e) { return e.code == code; });
    EXPECT_TRUE(expects_own) << f.name << " does not expect " << code;
  }
}

}  // namespace
}  // namespace kanesim::lang
