// Loading a model for any subcommand: parse, elaborate, print diagnostics; compile and
// render compiler messages the same way.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "cli/common.h"
#include "runtime/batch/csv_util.h"
#include "runtime/program.h"
#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "stdlib/stdlib.h"

namespace kanesim::cli {

namespace {
// The last loaded program stays alive so compile messages can show source lines.
thread_local lang::Program* g_program = nullptr;
}  // namespace

std::string ReadFileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string StdlibHash() {
  std::string all;
  for (const auto& [name, text] : stdlib::Files()) all.append(name).append("\n").append(text).append("\n");
  return batch::Fnv1a64Hex(all);
}

bool LoadModel(const LoadOptions& options, flat::Mechanism* out) {
  thread_local lang::Program program;  // one per thread: sweeps load variants concurrently
  program = lang::Program{};
  g_program = &program;
  lang::Diagnostics diags(&program.sources);
  lang::ElaborateOptions eo;
  eo.model = options.model;
  for (const auto& s : options.sets) {
    size_t eq = s.find('=');
    if (eq == std::string::npos || eq == 0) {
      std::cerr << "kanesim: error[E210]: --set needs name=value, got '" << s << "'\n";
      return false;
    }
    eo.overrides.push_back({s.substr(0, eq), s.substr(eq + 1)});
  }
  bool ok = lang::LoadProgram(options.path, stdlib::Files(), &program, diags);
  if (ok) ok = lang::Elaborate(program, eo, out, diags);
  std::cerr << diags.RenderAll();
  if (!ok && diags.NumErrors() > 0)
    std::cerr << diags.NumErrors() << " error" << (diags.NumErrors() == 1 ? "" : "s") << "\n";
  return ok && !diags.HasErrors();
}

void PrintCompileMessage(const rt::CompileMessage& e, const char* severity) {
  std::string where = e.loc.file.empty() ? "kanesim"
                                         : e.loc.file + ":" + std::to_string(e.loc.line) + ":" +
                                               std::to_string(e.loc.col);
  std::cerr << where << ": " << severity << "[" << e.code << "]: " << e.message << "\n";
  if (g_program) {
    for (int f = 0; f < g_program->sources.NumFiles(); ++f) {
      if (g_program->sources.Name(f) != e.loc.file || e.loc.line <= 0) continue;
      std::string line = g_program->sources.LineText(f, e.loc.line);
      std::string num = std::to_string(e.loc.line);
      std::cerr << " " << num << " | " << line << "\n " << std::string(num.size(), ' ') << " | "
                << std::string(static_cast<size_t>(std::max(0, e.loc.col - 1)), ' ') << "^\n";
      break;
    }
  }
  for (const auto& [loc, msg] : e.notes)
    std::cerr << loc.file << ":" << loc.line << ":" << loc.col << ": note: " << msg << "\n";
  if (!e.hint.empty()) std::cerr << "  hint: " << e.hint << "\n";
}

bool CompileModel(const flat::Mechanism& mech, const rt::CompileOptions& options, rt::CompileResult* out) {
  *out = rt::Compile(mech, options);
  if (out->errors.empty()) return true;
  for (const auto& e : out->errors) PrintCompileMessage(e, "error");
  return false;
}

void WarnIndeterminate(const rt::Program& program, const std::vector<std::string>& signals) {
  if (rt::CompileMessage f = rt::FrictionIndeterminateWarning(program); !f.code.empty())
    PrintCompileMessage(f, "warning");
  if (program.options.indeterminate != rt::IndeterminateReactions::NaN) return;
  const std::vector<std::string> which = rt::IndeterminateSignals(program, signals);
  if (!which.empty()) PrintCompileMessage(rt::IndeterminateWarning(program, which), "warning");
}

bool ReactionsFromName(const std::string& name, rt::CompileOptions* options) {
  if (name != "nan" && name != "min-norm") return false;
  options->indeterminate = name == "nan" ? rt::IndeterminateReactions::NaN : rt::IndeterminateReactions::MinNorm;
  return true;
}

}  // namespace kanesim::cli
