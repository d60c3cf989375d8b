// Elaborating a model given as text, for the elaborator's tests: the mechanism, the
// parameter values, and the rendered diagnostics with their codes.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lang/elaborate.h"
#include "stdlib/stdlib.h"

namespace kanesim::lang::test {

struct Elaborated {
  Program program;
  flat::Mechanism mech;
  std::vector<double> values;     // flat::EvaluateParams(mech) when ok
  std::string errors;             // every diagnostic, rendered
  std::vector<std::string> codes;  // codes of the errors, in order ("E219")
  bool ok = false;
  // Value of a flat parameter by name; NaN when there is none.
  double P(const std::string& name) const {
    const int i = mech.FindParam(name);
    return i >= 0 ? values[static_cast<size_t>(i)] : std::nan("");
  }
  bool HasCode(const std::string& code) const {
    for (const auto& c : codes)
      if (c == code) return true;
    return false;
  }
};

// `share_siblings` off: every scalar component instantiated (ElaborateOptions), the
// reference of tests/elab/sibling_share_test.cpp.
inline std::unique_ptr<Elaborated> ElaborateText(const std::string& text, std::vector<ParamOverride> sets = {},
                                                 bool share_siblings = true) {
  auto e = std::make_unique<Elaborated>();
  Diagnostics diags(&e->program.sources);
  ElaborateOptions options;
  options.overrides = std::move(sets);
  options.share_siblings = share_siblings;
  const bool loaded = LoadProgramFromText("test.mech", text, stdlib::Files(), &e->program, diags);
  e->ok = loaded && Elaborate(e->program, options, &e->mech, diags);
  e->errors = diags.RenderAll();
  for (const auto& d : diags.All())
    if (d.severity == Severity::Error) e->codes.push_back(DiagCodeString(d.code));
  if (e->ok) e->values = flat::EvaluateParams(e->mech);
  return e;
}

// A model holding a World and `declarations` (the smallest model that elaborates).
inline std::string ModelWith(const std::string& declarations) {
  return "model M\n  World world;\n" + declarations + "\nend M;\n";
}

// `count` copies of `term` joined by `op`: Chain("1", "+", 3) = "1 + 1 + 1".
inline std::string Chain(const std::string& term, const std::string& op, int count) {
  std::string s;
  s.reserve(static_cast<size_t>(count) * (term.size() + op.size() + 2));
  for (int i = 0; i < count; ++i) {
    if (i) s += " " + op + " ";
    s += term;
  }
  return s;
}

}  // namespace kanesim::lang::test
