// Loading a .mech file through the language front end into a flat mechanism, for tests
// and benchmarks that read models from the source tree (no GoogleTest dependency).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lang/elaborate.h"
#include "stdlib/stdlib.h"

namespace kanesim::test {

struct LoadedMech {
  lang::Program program;  // owns the sources the mechanism's locations point into
  flat::Mechanism mech;
  std::string diagnostics;  // rendered, when loading failed
};

// Loads and elaborates into *l: a file, or `text` itself when is_text (named model.mech).
// False, with the rendered diagnostics in *error, on failure.
inline bool LoadInto(LoadedMech* l, const std::string& path_or_text, std::vector<lang::ParamOverride> sets,
                     bool is_text, std::string* error) {
  lang::Diagnostics diags(&l->program.sources);
  lang::ElaborateOptions eo;
  eo.overrides = std::move(sets);
  const bool loaded = is_text ? lang::LoadProgramFromText("model.mech", path_or_text, stdlib::Files(), &l->program, diags)
                              : lang::LoadProgram(path_or_text, stdlib::Files(), &l->program, diags);
  if (loaded && lang::Elaborate(l->program, eo, &l->mech, diags)) return true;
  if (error) *error = diags.RenderAll();
  return false;
}

// A .mech file's mechanism, or null (diagnostics in *error).
inline std::unique_ptr<LoadedMech> LoadMech(const std::string& path, std::vector<lang::ParamOverride> sets = {},
                                            std::string* error = nullptr) {
  auto l = std::make_unique<LoadedMech>();
  return LoadInto(l.get(), path, std::move(sets), false, error) ? std::move(l) : nullptr;
}

}  // namespace kanesim::test
