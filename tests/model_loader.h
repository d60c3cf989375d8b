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

// Null, with `diagnostics` filled in the returned object's place via *error, on failure.
inline std::unique_ptr<LoadedMech> LoadMech(const std::string& path, std::vector<lang::ParamOverride> sets = {},
                                            std::string* error = nullptr) {
  auto l = std::make_unique<LoadedMech>();
  lang::Diagnostics diags(&l->program.sources);
  lang::ElaborateOptions eo;
  eo.overrides = std::move(sets);
  if (lang::LoadProgram(path, stdlib::Files(), &l->program, diags) && lang::Elaborate(l->program, eo, &l->mech, diags))
    return l;
  if (error) *error = diags.RenderAll();
  return nullptr;
}

}  // namespace kanesim::test
