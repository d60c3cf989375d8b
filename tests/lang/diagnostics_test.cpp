// Data-driven diagnostic tests: one file per diagnostic code in tests/lang/diagnostics/,
// named <CODE>_<short>.mech (.urdf for the URDF importer's U4xx, comments as <!-- -->), with the expected diagnostics written inline where they must
// point (see tests/README.md):
//
//   Revolute j(axs = {0, 0, 1});  // expect: E203 "did you mean 'axis'"
//   x = (1 + 2;                   // expect: P102 "opened here" col 13
//                                 // expect-global: E221        (any location, or none)
//   // set: N=abc                 (an ElaborateOptions override, like --set N=abc)
//   // model: Pkg.M               (the model to elaborate; default: the last one)
//   // pad-to-bytes: 4194305      (pads the text with spaces, for L005)
//   // repeat: CHAIN "+1" 100000  (replaces each @CHAIN@ in the text by "+1" 100000 times)
//   // stage: compile             (also compile, when elaboration succeeds: the compiler's
//                                 K3xx errors, and its W313/W314/W315 warnings for every signal)
//   // stage: inputs              (also check that every input is given, as a run without
//                                 --input-file or --set does: E239)
//   // mesh: part.stl open        (writes a test mesh beside the file, tests/support/mesh_fixtures.h;
//                                 the file is then loaded from that folder, named by its path)
//
// Each expected code must be reported on that line (and column, if given) of the file, with
// the quoted text somewhere in the rendered diagnostic (message, snippet, notes, hint). Every
// error must be expected; unexpected warnings are allowed. A failure means a diagnostic
// changed code or place, vanished, or a new spurious error appeared.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "lang/source.h"
#include "compiler/compiler.h"
#include "import/import.h"
#include "pipeline/pipeline.h"
#include "stdlib/stdlib.h"
#include "tests/support/mesh_fixtures.h"

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
  bool compile = false;
  bool inputs = false;  // stage: inputs
  std::vector<std::pair<std::string, std::string>> meshes;  // (file name, kind) to write first
};

std::vector<fs::path> DiagnosticFiles() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(KANESIM_DIAGNOSTICS_DIR))
    if (e.is_regular_file() && (e.path().extension() == ".mech" || e.path().extension() == ".urdf"))
      out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string Trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r");
  size_t e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

// "// key: value" -> value if `comment` is that directive, else "".
std::string Directive(const std::string& comment, const std::string& key) {
  std::string body = Trim(comment.substr(2));
  return body.rfind(key, 0) == 0 ? Trim(body.substr(key.size())) : "";
}

// Reads every "expect[-global]: CODE ["text"] [col N]" of one comment.
void ParseExpectations(const std::string& comment, int line, std::vector<Expectation>* out) {
  for (size_t p = comment.find("expect"); p != std::string::npos; p = comment.find("expect", p + 1)) {
    Expectation e;
    size_t i;
    if (comment.compare(p, 7, "expect:") == 0) {
      e.line = line;
      i = p + 7;
    } else if (comment.compare(p, 14, "expect-global:") == 0) {
      i = p + 14;
    } else {
      continue;
    }
    while (i < comment.size() && comment[i] == ' ') ++i;
    e.code = comment.substr(i, 4);
    i += 4;
    while (i < comment.size() && comment[i] == ' ') ++i;
    if (i < comment.size() && comment[i] == '"') {
      size_t close = comment.find('"', i + 1);
      if (close == std::string::npos) close = comment.size();
      e.text = comment.substr(i + 1, close - i - 1);
      i = close + 1;
      while (i < comment.size() && comment[i] == ' ') ++i;
    }
    if (comment.compare(i, 4, "col ") == 0) e.col = std::atoi(comment.c_str() + i + 4);
    out->push_back(e);
  }
}

// "NAME "text" COUNT": replaces every @NAME@ of `text` by the quoted text repeated COUNT
// times (a generated input too large to keep in the file: a 100 000-term chain). The
// quoted text holds no newline, so line numbers of the expectations do not move.
void Expand(const std::string& directive, std::string* text) {
  size_t q1 = directive.find('"'), q2 = directive.rfind('"');
  ASSERT_TRUE(q1 != std::string::npos && q2 > q1) << "bad repeat directive: " << directive;
  const std::string placeholder = "@" + Trim(directive.substr(0, q1)) + "@";
  const std::string unit = directive.substr(q1 + 1, q2 - q1 - 1);
  const size_t count = std::stoul(directive.substr(q2 + 1));
  std::string expansion;
  for (size_t i = 0; i < count; ++i) expansion += unit;
  for (size_t at = text->find(placeholder); at != std::string::npos; at = text->find(placeholder, at + expansion.size()))
    text->replace(at, placeholder.size(), expansion);
}

// Parses the inline expectations and directives of one file.
DiagFile LoadDiagFile(const fs::path& path) {
  DiagFile f;
  f.name = path.filename().string();
  f.text = ReadFile(path);
  std::istringstream lines(f.text);
  std::string line;
  size_t pad_to = 0;
  std::vector<std::string> repeats;
  for (int n = 1; std::getline(lines, line); ++n) {
    size_t slashes = line.find("//");
    const size_t xml = line.find("<!--");  // a URDF file's comment reads as a // comment
    if (xml != std::string::npos && xml < slashes) slashes = xml;
    if (slashes == std::string::npos) continue;
    std::string comment = line.substr(slashes);
    if (comment.rfind("<!--", 0) == 0) comment = "//" + comment.substr(4, comment.find("-->") - 4);
    ParseExpectations(comment, n, &f.expects);
    if (std::string set = Directive(comment, "set:"); !set.empty()) {
      size_t eq = set.find('=');
      f.overrides.emplace_back(Trim(set.substr(0, eq)), eq == std::string::npos ? "" : Trim(set.substr(eq + 1)));
    }
    if (std::string model = Directive(comment, "model:"); !model.empty()) f.model = model;
    if (std::string pad = Directive(comment, "pad-to-bytes:"); !pad.empty()) pad_to = std::stoul(pad);
    if (std::string rep = Directive(comment, "repeat:"); !rep.empty()) repeats.push_back(rep);
    if (Directive(comment, "stage:") == "compile") f.compile = true;
    if (Directive(comment, "stage:") == "inputs") f.inputs = true;
    if (std::string mesh = Directive(comment, "mesh:"); !mesh.empty()) {
      size_t sp = mesh.find(' ');
      f.meshes.emplace_back(Trim(mesh.substr(0, sp)), sp == std::string::npos ? "" : Trim(mesh.substr(sp)));
    }
  }
  if (f.text.size() < pad_to) f.text.append(pad_to - f.text.size(), ' ');
  for (const std::string& rep : repeats) Expand(rep, &f.text);
  return f;
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

// A URDF file (the importer's U4xx codes): translated as `kanesim check robot.urdf` does,
// its rendered diagnostics matched by their heads "NAME:LINE:COL: error[CODE]: ...".
std::string CheckUrdf(DiagFile& f) {
  import::Options o;
  o.notes = false;
  o.use_ros_package_path = false;
  const import::Result r = import::UrdfToMech(f.name, f.text, o);
  std::vector<std::string> blocks;
  std::istringstream in(r.diagnostics);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(f.name + ":", 0) == 0 || blocks.empty()) blocks.emplace_back();
    blocks.back() += line + "\n";
  }
  std::string failures;
  for (const std::string& b : blocks) {
    int line = 0, col = 0;
    char severity[16] = {0}, code[8] = {0};
    if (std::sscanf(b.c_str() + f.name.size(), ":%d:%d: %15[a-z][%7[A-Z0-9]]", &line, &col, severity, code) != 4) continue;
    bool matched = false;
    for (Expectation& e : f.expects) {
      if (e.matched || e.code != code || (e.line != 0 && e.line != line) || (e.col != 0 && e.col != col)) continue;
      if (!e.text.empty() && b.find(e.text) == std::string::npos) continue;
      e.matched = matched = true;
      break;
    }
    if (!matched && std::string(severity) == "error") failures += "unexpected diagnostic:\n" + b;
  }
  for (const Expectation& e : f.expects)
    if (!e.matched) failures += "missing: " + Describe(e) + "\n";
  if (!failures.empty()) failures += "all diagnostics:\n" + r.diagnostics;
  return failures;
}

class DiagnosticFileTest : public ::testing::TestWithParam<fs::path> {};

TEST_P(DiagnosticFileTest, ReportsExactlyTheExpectedDiagnostics) {
  DiagFile f = LoadDiagFile(GetParam());
  ASSERT_FALSE(f.expects.empty()) << f.name << " has no '// expect:' comment";
  if (GetParam().extension() == ".urdf") {
    EXPECT_EQ(CheckUrdf(f), "") << f.name;
    return;
  }
  const auto stdlib = kanesim::stdlib::Files();
  Program program;
  Diagnostics diags(&program.sources);
  std::string display = f.name;
  if (!f.meshes.empty()) {
    const std::string dir = meshfix::MeshFixtureDir(GetParam().stem().string());
    for (const auto& [file, kind] : f.meshes) ASSERT_TRUE(meshfix::WriteMeshFixture(dir + "/" + file, kind)) << kind;
    display = dir + "/" + f.name;
  }
  if (LoadProgramFromText(display, f.text, stdlib, &program, diags)) {
    ElaborateOptions options;
    options.model = f.model;
    for (const auto& [name, value] : f.overrides) options.overrides.push_back({name, value});
    flat::Mechanism mechanism;
    const bool elaborated = Elaborate(program, options, &mechanism, diags) && !diags.HasErrors();
    if (elaborated && f.inputs) {
      std::vector<std::string> all;  // a run given no input: every one is missing
      for (const flat::Input& in : mechanism.inputs) all.push_back(in.name);
      pipeline::AddUnconnectedInputs(mechanism, all, diags);
    }
    if (elaborated && f.compile) {
      // The compiler's messages through the pipeline's conversion, as `kanesim` reports them.
      rt::CompileResult r = rt::Compile(mechanism, {});
      for (const rt::CompileMessage& e : r.errors) pipeline::AddCompileMessage(e, Severity::Error, diags);
      if (r.program) {
        rt::CompileMessage friction = rt::FrictionIndeterminateWarning(*r.program);
        if (!friction.message.empty()) pipeline::AddCompileMessage(friction, Severity::Warning, diags);
        rt::CompileMessage start = rt::StartSpeedsWarning(*r.program);
        if (!start.message.empty()) pipeline::AddCompileMessage(start, Severity::Warning, diags);
        for (const rt::CompileMessage& w : rt::LockedJointWarnings(*r.program))
          pipeline::AddCompileMessage(w, Severity::Warning, diags);
        std::vector<std::string> which = rt::IndeterminateSignals(*r.program, rt::AvailableSignals(*r.program));
        if (!which.empty())
          pipeline::AddCompileMessage(rt::IndeterminateWarning(*r.program, which), Severity::Warning, diags);
      }
    }
  }
  int main_file = -1;
  for (int i = 0; i < program.sources.NumFiles(); ++i)
    if (program.sources.Name(i) == display) main_file = i;
  EXPECT_EQ(Check(f, diags, main_file), "") << f.name;
  if (!f.meshes.empty()) std::filesystem::remove_all(fs::path(display).parent_path());
}

std::string TestName(const ::testing::TestParamInfo<fs::path>& info) {
  std::string s = info.param.stem().string();
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Files, DiagnosticFileTest, ::testing::ValuesIn(DiagnosticFiles()), TestName);

// Every code of the one diagnostic table has its file, and each file is named after a code
// it expects: a new code without a test, or a misnamed file, fails here. Codes marked
// "internal:" (no model can cause them) are not: K300 is tested in
// tests/runtime/compile_test.cpp, K301 (there too) and K304 are the compiler's own checks
// of what the elaborator refuses first (E217, E215, E216), and K320 would take a failure
// of the sparse analysis itself.
TEST(DiagnosticFiles, EveryCodeOfTheTableHasAFile) {
  std::vector<std::string> codes, internal;
#define KANESIM_X(e, code, summary) \
  (std::string(summary).rfind("internal:", 0) == 0 ? internal : codes).push_back(code);
  KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
  std::vector<fs::path> files = DiagnosticFiles();
  for (const std::string& code : codes) {
    bool found = std::any_of(files.begin(), files.end(),
                             [&](const fs::path& p) { return p.filename().string().rfind(code + "_", 0) == 0; });
    EXPECT_TRUE(found) << "no tests/lang/diagnostics/" << code << "_<short>.mech (.urdf for U4xx)";
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
