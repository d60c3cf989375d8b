// --set overrides, in two steps around instantiation. Parse: every name is parsed (dotted
// parts, 1-based integer subscripts) and its value as a .mech expression; a name without
// subscripts becomes the outermost modifier of the root (it wins over everything but
// final). Bind, after instantiation: every target is checked (it exists, indices are in
// range, it is a parameter that may be set) and subscripted names are bound on the instance
// they name. Mistakes in a name are reported in "<--set>", a pseudo-file holding
// `name=value`, with a caret under the offending part.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lang/elab_internal.h"
#include "lang/units.h"

namespace kanesim::lang::elab {

// One part of a --set name: `g[2]` of `world.g[2]`; offsets into the name.
struct SetPart {
  std::string name;
  std::vector<long> subs;                      // 1-based indices as written
  int begin = 0, end = 0;                      // the identifier
  std::vector<std::pair<int, int>> sub_spans;  // each index
};

// A parsed --set: its name, its value, and the "<--set>" pseudo-file holding `name=value`.
struct SetOverride {
  std::string name;
  std::vector<SetPart> parts;
  const ast::Expr* value = nullptr;
  int file = -1;
  bool subscripted = false;
  // A value written with its unit, 5[N/mm]: the unit, and the factor node of the value
  // `(5) * factor`, set by Bind to convert into the target's declared unit.
  bool has_unit = false;
  Unit unit;
  Span unit_span;
  ast::Expr* factor = nullptr;
};

class SetOverrides {
 public:
  explicit SetOverrides(Diagnostics& diags) : diags_(diags) {}
  // Parses `overrides` (their text joins program's sources) into root's modifier; false
  // after a diagnostic.
  bool Parse(const std::vector<ParamOverride>& overrides, const Program& program, Node* root);
  // After instantiation: checks every target and binds the subscripted ones.
  void Bind();
  // Whether a --set names an array element (bound by Bind, after instantiation).
  bool AnySubscripted() const { return any_subscripted_; }

 private:
  Node* ResolveTarget(const SetOverride& so, int* elem, bool* start);
  static bool IsStartPart(const SetOverride& so, size_t i);
  void BindStart(const SetOverride& so, Node* var, Span whole);
  Node* Member(const SetOverride& so, size_t i, Node* n);
  Node* ArrayElement(const SetOverride& so, size_t i, Node* array);
  bool VarElement(const SetOverride& so, size_t i, const Node* n, int* elem);
  ModValue Binding(const SetOverride& so) const;
  // 5[N/mm]: splits the unit off `value` (false after a diagnostic); ConvertUnit (in Bind)
  // sets the factor to the target's declared unit.
  bool SplitUnit(const ParamOverride& ov, const Program& program, SetOverride* so, std::string* value);
  bool ConvertUnit(const SetOverride& so, Node* var);
  static Span At(const SetOverride& so, int begin, int end);

  Diagnostics& diags_;
  Node* root_ = nullptr;
  std::vector<SetOverride> sets_;
  std::vector<std::unique_ptr<ast::Expr>> values_;  // the parsed values, which bindings point into
  bool any_subscripted_ = false;
};

}  // namespace kanesim::lang::elab
