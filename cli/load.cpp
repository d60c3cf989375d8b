// Loading a model for any subcommand: parse, elaborate, print diagnostics; compile and
// render compiler messages the same way.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "cli/common.h"
#include "runtime/batch/csv_util.h"
#include "runtime/program.h"
#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "lang/set_argument.h"
#include "lang/text.h"
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
    lang::ParamOverride o;
    if (!lang::ParseSetArgument(s, &o)) {
      std::cerr << "kanesim: error[E210]: --set needs name=value, got '" << lang::ClipMessage(s) << "'\n";
      return false;
    }
    eo.overrides.push_back(std::move(o));
  }
  bool ok = lang::LoadProgram(options.path, stdlib::Files(), &program, diags);
  if (ok) ok = lang::Elaborate(program, eo, out, diags);
  std::cerr << diags.RenderAll();
  if (!ok && diags.NumErrors() > 0)
    std::cerr << diags.NumErrors() << " error" << (diags.NumErrors() == 1 ? "" : "s") << "\n";
  return ok && !diags.HasErrors();
}

// The compiler's messages go through the language's renderer (lang/diagnostics.cpp): the
// same clipped, escaped source line and caret, and the same caps on notes.
void PrintCompileMessage(const rt::CompileMessage& e, const char* severity) {
  std::string where = e.loc.file.empty() ? "kanesim"
                                         : lang::ClipMessage(e.loc.file) + ":" + std::to_string(e.loc.line) + ":" +
                                               std::to_string(e.loc.col);
  std::cerr << where << ": " << severity << "[" << e.code << "]: " << lang::ClipMessage(e.message) << "\n";
  if (g_program) {
    const lang::SourceManager& sm = g_program->sources;
    for (int f = 0; f < sm.NumFiles(); ++f) {
      if (sm.Name(f) != e.loc.file || e.loc.line <= 0) continue;
      const std::int32_t at = sm.Offset(f, e.loc.line, e.loc.col);
      if (at >= 0) std::cerr << lang::RenderSnippet(sm, lang::Span{f, at, at + 1});
      break;
    }
  }
  const size_t shown = std::min(e.notes.size(), lang::Diagnostics::kMaxNotesShown);
  for (size_t i = 0; i < shown; ++i) {
    const auto& [loc, msg] = e.notes[i];
    std::cerr << lang::ClipMessage(loc.file) << ":" << loc.line << ":" << loc.col << ": note: " << lang::ClipMessage(msg)
              << "\n";
  }
  if (e.notes.size() > shown) std::cerr << "  note: " << e.notes.size() - shown << " more notes not shown\n";
  if (!e.hint.empty()) std::cerr << "  hint: " << lang::ClipMessage(e.hint) << "\n";
}

// The compiler's errors are capped like the language's (Diagnostics::kMaxErrors): a model
// with thousands of unconnected bodies gives 50 messages and a count, not thousands.
bool CompileModel(const flat::Mechanism& mech, const rt::CompileOptions& options, rt::CompileResult* out) {
  *out = rt::Compile(mech, options);
  if (out->errors.empty()) return true;
  const size_t shown = std::min(out->errors.size(), static_cast<size_t>(lang::Diagnostics::kMaxErrors));
  for (size_t i = 0; i < shown; ++i) PrintCompileMessage(out->errors[i], "error");
  if (out->errors.size() > shown)
    std::cerr << "kanesim: " << out->errors.size() - shown << " more errors like these are not shown\n";
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
