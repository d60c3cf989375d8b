// Shared by the language fuzz targets: a lang::Program whose standard library is parsed
// once per process. Each input replaces only the main file (file 0, as LoadProgramFromText
// lays a program out) and drops the files a previous elaboration added (--set values), so
// an execution costs the input's own parse and elaboration, not the library's.
#pragma once

#include <string>

#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "lang/parser.h"
#include "stdlib/stdlib.h"

namespace kanesim::fuzz {

class StdlibOnce {
 public:
  StdlibOnce() {
    lang::Diagnostics diags(&program_.sources);
    program_.sources.Add("fuzz.mech", "");
    program_.files.push_back(lang::Parse(0, program_.sources, diags));
    for (const auto& [name, text] : stdlib::Files()) {
      const int f = program_.sources.Add(name, text);
      program_.files.push_back(lang::Parse(f, program_.sources, diags));
    }
    num_files_ = program_.sources.NumFiles();
    if (diags.HasErrors()) __builtin_trap();  // the embedded library must parse
  }

  // Parses `text` as the main file (diagnostics into `diags`, made on Sources()).
  lang::Program& Load(const std::string& text, lang::Diagnostics& diags) {
    Reset();
    program_.sources.Replace(0, text);
    program_.files[0] = lang::Parse(0, program_.sources, diags);
    return program_;
  }
  // Drops the files the last elaboration added; the main file stays.
  lang::Program& Reset() {
    program_.sources.Truncate(num_files_);
    return program_;
  }
  const lang::SourceManager& Sources() const { return program_.sources; }

 private:
  lang::Program program_;
  int num_files_ = 0;
};

}  // namespace kanesim::fuzz
