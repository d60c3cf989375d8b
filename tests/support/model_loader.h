// Loading a .mech file through the pipeline's first two stages (pipeline/
// pipeline.h: parse, elaborate) into a flat mechanism, for tests and benchmarks that read
// models from the source tree (no GoogleTest dependency).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/pipeline.h"

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
  pipeline::LoadOptions lo;
  lo.compile = false;
  for (const lang::ParamOverride& o : sets) lo.sets.push_back(o.name + "=" + o.value);
  pipeline::LoadResult r = pipeline::LoadModel(
      is_text ? pipeline::Source::Text("model.mech", path_or_text) : pipeline::Source::File(path_or_text), lo, {});
  if (!r.model) {
    l->diagnostics = r.diagnostics;
    if (error) *error = r.diagnostics;
    return false;
  }
  l->program = std::move(r.model->source);
  l->mech = *r.model->mech;  // a copy: the model shares its mechanism as const
  return true;
}

// A .mech file's mechanism, or null (diagnostics in *error).
inline std::unique_ptr<LoadedMech> LoadMech(const std::string& path, std::vector<lang::ParamOverride> sets = {},
                                            std::string* error = nullptr) {
  auto l = std::make_unique<LoadedMech>();
  return LoadInto(l.get(), path, std::move(sets), false, error) ? std::move(l) : nullptr;
}

}  // namespace kanesim::test
