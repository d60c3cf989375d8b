// Loading a model for any subcommand through the pipeline (runtime/pipeline/pipeline.h),
// with its diagnostics on stderr.
#include <fstream>
#include <iostream>
#include <sstream>

#include "cli/common.h"
#include "runtime/batch/csv_util.h"
#include "lang/diagnostics.h"
#include "runtime/program/program.h"
#include "stdlib/stdlib.h"

namespace kanesim::cli {

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

std::unique_ptr<pipeline::Model> LoadAndCompile(const LoadOptions& options, const pipeline::RunSpec& spec,
                                                bool compile) {
  pipeline::LoadOptions lo;
  lo.model = options.model;
  lo.sets = options.sets;
  lo.compile = compile;
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(options.path), lo, spec);
  std::cerr << r.diagnostics;
  return std::move(r.model);
}

bool LoadModel(const LoadOptions& options, flat::Mechanism* out) {
  std::unique_ptr<pipeline::Model> m = LoadAndCompile(options, pipeline::RunSpec{}, false);
  if (!m) return false;
  *out = std::move(m->mech);
  return true;
}

bool CompileModel(const flat::Mechanism& mech, const rt::CompileOptions& options, rt::CompileResult* out) {
  *out = rt::Compile(mech, options);
  for (const rt::CompileMessage& e : out->errors) PrintCompileMessage(e, "error");
  return out->errors.empty();
}

// Without the model at hand, the files the message names are read again for its source lines.
void PrintCompileMessage(const rt::CompileMessage& message, const char* severity) {
  pipeline::Model files;
  lang::SourceManager& sm = files.source.sources;
  std::vector<std::string> names = {message.loc.file};
  for (const auto& [loc, text] : message.notes) names.push_back(loc.file);
  const auto stdlib_files = stdlib::Files();
  for (const std::string& name : names) {
    bool known = name.empty();
    for (int f = 0; f < sm.NumFiles() && !known; ++f) known = sm.Name(f) == name;
    if (known) continue;
    std::string text = ReadFileText(name);
    for (const auto& [lib_name, lib_text] : stdlib_files)
      if (lib_name == name) text = lib_text;
    sm.Add(name, std::move(text));
  }
  const bool error = std::string(severity) == "error";
  std::cerr << pipeline::RenderCompileMessage(files, message, error ? lang::Severity::Error : lang::Severity::Warning);
}

void WarnIndeterminate(const rt::Program& program, const std::vector<std::string>& signals) {
  if (rt::CompileMessage f = rt::FrictionIndeterminateWarning(program); !f.message.empty())
    PrintCompileMessage(f, "warning");
  if (program.options.indeterminate != rt::IndeterminateReactions::NaN) return;
  const std::vector<std::string> which = rt::IndeterminateSignals(program, signals);
  if (!which.empty()) PrintCompileMessage(rt::IndeterminateWarning(program, which), "warning");
}

bool ReactionsFromName(const std::string& name, rt::CompileOptions* options) {
  return pipeline::ReactionsFromName(name, &options->indeterminate);
}

}  // namespace kanesim::cli
