// --set overrides: parsed before instantiation, checked and bound after it
// (lang/elab_set.h).
#include "lang/elab_set.h"

#include <algorithm>
#include <cctype>
#include <sstream>

#include "lang/lexer.h"
#include "lang/parser.h"

namespace kanesim::lang::elab {

namespace {

std::string PartText(const std::vector<SetPart>& parts, size_t upto) {
  std::string s;
  for (size_t i = 0; i <= upto && i < parts.size(); ++i) s += (i ? "." : "") + parts[i].name;
  return s;
}

// name := part { '.' part };  part := IDENT [ '[' INT { ',' INT } ']' ];  INT := ['-'] digit {digit}
// On failure *bad is the offset of the offending character and *why says what was expected.
bool ParseSetName(const std::string& s, std::vector<SetPart>* parts, size_t* bad, std::string* why) {
  size_t i = 0;
  auto fail = [&](const char* what) {
    *bad = i;
    *why = what;
    return false;
  };
  while (true) {
    SetPart p;
    p.begin = static_cast<int>(i);
    if (i >= s.size() || !(std::isalpha(static_cast<unsigned char>(s[i])) || s[i] == '_'))
      return fail("expected a name");
    while (i < s.size() && (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_')) p.name += s[i++];
    p.end = static_cast<int>(i);
    if (i < s.size() && s[i] == '[') {
      ++i;
      while (true) {
        size_t b = i;
        if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
        size_t digits = i;
        while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
        if (i == digits) {
          i = b;
          return fail("expected an integer index");
        }
        if (i - digits > 15) {
          i = b;
          return fail("the index is too large");
        }
        p.subs.push_back(std::stol(s.substr(b, i - b)));
        p.sub_spans.push_back({static_cast<int>(b), static_cast<int>(i)});
        if (i < s.size() && s[i] == ',') {
          ++i;
          continue;
        }
        if (i < s.size() && s[i] == ']') {
          ++i;
          break;
        }
        return fail("expected ',' or ']'");
      }
    }
    parts->push_back(std::move(p));
    if (i == s.size()) return true;
    if (s[i] != '.') return fail("expected '.' or '='");
    ++i;
  }
}

}  // namespace

// Part i is `start`, unindexed and last: the start attribute of the variable before it.
bool SetOverrides::IsStartPart(const SetOverride& so, size_t i) {
  return i > 0 && i + 1 == so.parts.size() && so.parts[i].name == "start" && so.parts[i].subs.empty();
}

Span SetOverrides::At(const SetOverride& so, int begin, int end) {
  return Span{so.file, begin, std::max(end, begin + 1)};
}

// Before instantiation: parse every --set; names without subscripts become the
// outermost modifiers (they win over everything but final).
bool SetOverrides::Parse(const std::vector<ParamOverride>& overrides, const Program& program, Node* root) {
  root_ = root;
  for (const auto& ov : overrides) {
    SetOverride so;
    so.name = ov.name;
    so.file = program.sources.Add("<--set>", ov.name + "=" + ov.value);
    size_t bad = 0;
    std::string why;
    if (!ParseSetName(ov.name, &so.parts, &bad, &why)) {
      auto& d = diags_.Error(DiagCode::BadSet, At(so, static_cast<int>(bad), static_cast<int>(bad) + 1),
                             "--set " + ov.name + ": " + why);
      d.hint = "write a dotted parameter name with 1-based indices: N=5, rod.L=0.3, world.g[2]=-1.6, I[1,2]=0";
      continue;
    }
    std::string value_text = ov.value;
    if (!SplitUnit(ov, program, &so, &value_text)) continue;
    int value_file = program.sources.Add("<--set " + ov.name + ">", value_text);
    int before = diags_.NumErrors();
    auto expr = ParseExpression(value_file, program.sources, diags_);
    if (diags_.NumErrors() > before) {
      diags_.Error(DiagCode::BadSet, Span{value_file, 0, static_cast<int32_t>(ov.value.size())},
                   "cannot parse the value of --set " + ov.name + "=" + ov.value)
          .hint = "values are .mech expressions: 2.5, {0, -9.81, 0}, true, \"text\"";
      continue;
    }
    if (so.has_unit) {  // (value) * factor, the factor set by Bind
      auto product = std::make_unique<ast::Expr>();
      product->kind = ast::ExprKind::Binary;
      product->op = static_cast<int>(Tok::Star);
      product->span = expr->span;
      auto factor = std::make_unique<ast::Expr>();
      factor->number = 1;
      factor->span = expr->span;
      so.factor = factor.get();
      product->depth = expr->depth + 1;
      product->args.push_back(std::move(expr));
      product->args.push_back(std::move(factor));
      expr = std::move(product);
    }
    so.value = expr.get();
    values_.push_back(std::move(expr));
    for (const auto& p : so.parts) so.subscripted = so.subscripted || !p.subs.empty();
    any_subscripted_ = any_subscripted_ || so.subscripted;
    // Subscripted names (world.g[2], links[3].m) are bound after instantiation, on the
    // instance they name: modifiers cannot address single array elements.
    if (!so.subscripted) {
      Mod* target = &root->mod;
      for (const auto& p : so.parts) {
        if (!target->sub.count(p.name)) {
          target->order.push_back(p.name);
          target->sub[p.name].set_only = true;
        }
        target = &target->sub[p.name];
        target->span = so.value->span;
      }
      target->value = Binding(so);
    }
    sets_.push_back(std::move(so));
  }
  return !diags_.HasErrors();
}

ModValue SetOverrides::Binding(const SetOverride& so) const {
  ModValue mv;
  mv.expr = so.value;
  mv.scope = root_;
  mv.span = so.value->span;
  mv.from_set = true;
  return mv;
}

// The instance a parsed --set name denotes, with a diagnostic when there is none: an
// unknown part, an index out of range, an index on something that is not an array, or
// the wrong number of indices. *elem receives the row-major element of an indexed
// variable (-1: the whole variable). A last part `start` after a variable (j.q.start)
// names that attribute: *start is set and the variable is returned.
Node* SetOverrides::ResolveTarget(const SetOverride& so, int* elem, bool* start) {
  *elem = -1;
  *start = false;
  Node* n = root_;
  for (size_t i = 0; i < so.parts.size(); ++i) {
    if (n->kind == Node::kVar && *elem < 0 && IsStartPart(so, i)) {
      *start = true;
      return n;
    }
    n = Member(so, i, n);
    if (!n) return nullptr;
    if (n->kind == Node::kArray) {
      n = ArrayElement(so, i, n);
      if (!n) return nullptr;
      continue;
    }
    if (so.parts[i].subs.empty()) continue;
    if (!VarElement(so, i, n, elem)) return nullptr;
  }
  return n;
}

// Part i of the --set name, looked up in n; null after a diagnostic.
Node* SetOverrides::Member(const SetOverride& so, size_t i, Node* n) {
  const SetPart& p = so.parts[i];
  Span at = At(so, p.begin, p.end);
  if (n->kind != Node::kClass) {
    diags_.Error(DiagCode::UnknownName, at,
                 "--set " + so.name + ": '" + n->Path() + "' is a variable and has no member '" + p.name + "'");
    return nullptr;
  }
  Node* next = n->Child(p.name);
  if (next) return next;
  std::vector<std::string> names;
  for (const auto& c : n->children) names.push_back(c->name);
  auto& d = diags_.Error(DiagCode::UnknownName, at,
                         "--set " + so.name + ": no such parameter" +
                             (n == root_ ? "" : " ('" + n->Path() + "' has no element '" + p.name + "')"));
  std::string best = ClosestName(p.name, names);
  if (!best.empty()) d.hint = "did you mean '" + (i == 0 ? best : PartText(so.parts, i - 1) + "." + best) + "'?";
  return nullptr;
}

// Part i indexing an array of components: the element (the array itself when not
// indexed); null after a diagnostic.
Node* SetOverrides::ArrayElement(const SetOverride& so, size_t i, Node* array) {
  const SetPart& p = so.parts[i];
  if (p.subs.empty()) {
    // j.axis = {...}: a modifier of the whole array; check the name on an element.
    const bool last = i + 1 == so.parts.size();
    return !last && !array->elems.empty() ? array->elems[0].get() : array;
  }
  if (p.subs.size() != 1) {
    diags_.Error(DiagCode::BadSet, At(so, p.sub_spans[1].first, p.sub_spans.back().second),
                 "--set " + so.name + ": '" + array->Path() + "' is an array of components and takes one index");
    return nullptr;
  }
  long k = p.subs[0];
  if (k < 1 || k > static_cast<long>(array->elems.size())) {
    diags_.Error(DiagCode::IndexOutOfRange, At(so, p.sub_spans[0].first, p.sub_spans[0].second),
                 "--set " + so.name + ": index " + std::to_string(k) + " is out of range 1.." +
                     std::to_string(array->elems.size()) + " of '" + array->Path() + "'")
        .hint = "indices are 1-based";
    return nullptr;
  }
  return array->elems[static_cast<size_t>(k - 1)].get();
}

// Part i indexing an array variable n: the row-major element in *elem; it must be the
// name's last part. False after a diagnostic.
bool SetOverrides::VarElement(const SetOverride& so, size_t i, const Node* n, int* elem) {
  const SetPart& p = so.parts[i];
  const std::string& full = so.name;
  const Span subs_span = At(so, p.sub_spans[0].first, p.sub_spans.back().second);
  if (n->kind != Node::kVar) {
    diags_.Error(DiagCode::BadSet, subs_span, "--set " + full + ": '" + n->Path() + "' is not an array and takes no index");
    return false;
  }
  if (n->shape.empty()) {
    diags_.Error(DiagCode::BadSet, subs_span, "--set " + full + ": '" + n->Path() + "' is a scalar and takes no index");
    return false;
  }
  if (p.subs.size() != n->shape.size()) {
    diags_.Error(DiagCode::BadSet, subs_span,
                 "--set " + full + ": '" + n->Path() + "' has " + std::to_string(n->shape.size()) +
                     " dimension(s) but " + std::to_string(p.subs.size()) + " indices are given");
    return false;
  }
  long flat = 0;
  for (size_t d = 0; d < p.subs.size(); ++d) {
    long k = p.subs[d];
    long size = n->shape[d];
    if (k < 1 || k > size) {
      diags_.Error(DiagCode::IndexOutOfRange, At(so, p.sub_spans[d].first, p.sub_spans[d].second),
                   "--set " + full + ": index " + std::to_string(k) + " is out of range 1.." + std::to_string(size) +
                       " of '" + n->Path() + "'")
          .hint = "indices are 1-based";
      return false;
    }
    flat = flat * size + (k - 1);
  }
  if (i + 1 != so.parts.size()) {
    diags_.Error(DiagCode::UnknownName, At(so, so.parts[i + 1].begin, so.parts[i + 1].end),
                 "--set " + full + ": '" + n->Path() + "' is a variable and has no members");
    return false;
  }
  *elem = static_cast<int>(flat);
  return true;
}

// After instantiation: every target must be a settable parameter; subscripted ones are
// bound here, as element equations of the parameter or as its whole value.
void SetOverrides::Bind() {
  for (const SetOverride& so : sets_) {
    if (diags_.Full()) return;
    const std::string& full = so.name;
    Span whole = At(so, 0, so.parts.back().sub_spans.empty() ? so.parts.back().end
                                                                     : so.parts.back().sub_spans.back().second + 1);
    int elem = -1;
    bool start = false;
    Node* n = ResolveTarget(so, &elem, &start);
    if (!n) continue;
    if (so.has_unit && !ConvertUnit(so, n)) continue;
    if (start) {
      BindStart(so, n, whole);
      continue;
    }
    // A top-level input may be set as a parameter is: it then has that value for the run.
    const bool model_input = n->kind == Node::kVar && n->causality == ast::Causality::Input &&
                             n->variability == ast::Variability::None && n->parent && !n->parent->parent;
    if (!model_input && (n->kind != Node::kVar || n->variability != ast::Variability::Parameter)) {
      auto& d = diags_.Error(DiagCode::NotParameter, whole,
                             "--set " + full + ": '" + n->Path() + "' is not a parameter" +
                                 (n->variability == ast::Variability::Constant ? " (it is a constant)" : ""));
      if (n->decl) d.notes.push_back({n->decl->name_span, "declared here"});
      continue;
    }
    if (n->decl && n->decl->is_protected) {
      auto& d = diags_.Error(DiagCode::NotParameter, whole, "--set " + full + ": '" + n->Path() + "' is protected");
      d.notes.push_back({n->decl->name_span, "declared protected here"});
      continue;
    }
    if (n->is_final_decl || n->Modifiers().is_final) {
      auto& d = diags_.Error(DiagCode::FinalOverride, whole, "--set " + full + ": '" + n->Path() + "' is final");
      if (n->decl) d.notes.push_back({n->decl->name_span, "declared final here"});
      continue;
    }
    if (!so.subscripted) continue;  // bound as a modifier before instantiation
    if (n->state == EvalState::Done) {
      diags_.Error(DiagCode::BadSet, so.value->span,
                   "--set " + full + ": '" + n->Path() + "' sizes the model and was fixed before this override")
          .hint = "set the parameter it depends on instead";
      continue;
    }
    if (elem >= 0) n->eq_elem_binding[elem] = Binding(so);
    else n->OwnMod().value = Binding(so);  // its own copy, to change
  }
}

// j.q.start=0.3: the start value of a (non-parameter) variable, as if written as a
// modifier in the file; unsubscripted names were bound as modifiers by Parse.
void SetOverrides::BindStart(const SetOverride& so, Node* var, Span whole) {
  if (var->variability == ast::Variability::Parameter || var->variability == ast::Variability::Constant) {
    auto& d = diags_.Error(DiagCode::NotParameter, whole,
                           "--set " + so.name + ": '" + var->Path() + "' is a " +
                               (var->variability == ast::Variability::Constant ? "constant" : "parameter") +
                               "; set its value, not its start");
    d.hint = "--set " + var->Path() + "=VALUE";
    if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
    return;
  }
  if (var->decl && var->decl->is_protected) {
    auto& d = diags_.Error(DiagCode::NotParameter, whole, "--set " + so.name + ": '" + var->Path() + "' is protected");
    d.notes.push_back({var->decl->name_span, "declared protected here"});
    return;
  }
  if (!so.subscripted) return;
  Mod& m = var->OwnMod().sub["start"];  // its own copy, to change
  m.value = Binding(so);
  m.span = so.value->span;
}

// `VALUE[UNIT]`: the last bracket holds a unit (not an index: "2" and "k" are no units).
bool SetOverrides::SplitUnit(const ParamOverride& ov, const Program& program, SetOverride* so, std::string* value) {
  const std::string& v = ov.value;
  const size_t open = v.rfind('[');
  if (v.empty() || v.back() != ']' || open == std::string::npos || open == 0) return true;
  const std::string text = v.substr(open + 1, v.size() - open - 2);
  std::string error;
  if (!ParseUnit(text, &so->unit, &error)) return true;  // an index, or a matrix: the value as written
  so->has_unit = true;
  const int file = program.sources.Add("<--set " + ov.name + " unit>", text);
  so->unit_span = Span{file, 0, static_cast<std::int32_t>(std::max<size_t>(text.size(), 1))};
  *value = v.substr(0, open);
  return true;
}

// The factor from the written unit to the target's declared one (same dimension).
bool SetOverrides::ConvertUnit(const SetOverride& so, Node* var) {
  const ModView mods = var->Modifiers();
  auto it = mods.sub.find("unit");
  const ast::Expr* ue = it != mods.sub.end() && it->second.value ? it->second.value->expr : nullptr;
  Unit declared;
  std::string error;
  if (var->kind != Node::kVar || !ue || ue->kind != ast::ExprKind::String || !ParseUnit(ue->text, &declared, &error)) {
    auto& d = diags_.Error(DiagCode::UnitMismatch, so.unit_span,
                           "--set " + so.name + ": '" + var->Path() + "' declares no unit to convert to");
    d.hint = "give the value in the unit the model uses, without [..]";
    if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
    return false;
  }
  if (!declared.SameDimension(so.unit)) {
    auto& d = diags_.Error(DiagCode::UnitMismatch, so.unit_span,
                           "--set " + so.name + ": '" + var->Path() + "' has unit \"" + ue->text +
                               "\", which \"" + diags_.Sources().Text(so.unit_span.file) + "\" cannot be converted to");
    d.notes.push_back({ue->span, "unit declared here"});
    d.hint = "SI form: \"" + declared.ToString() + "\" against \"" + so.unit.ToString() + "\"";
    return false;
  }
  if (var->state == EvalState::Done && declared.scale != so.unit.scale) {
    diags_.Error(DiagCode::BadSet, so.unit_span,
                 "--set " + so.name + ": '" + var->Path() + "' sizes the model and was fixed before its unit was converted")
        .hint = "give the value in \"" + ue->text + "\"";
    return false;
  }
  so.factor->number = so.unit.scale / declared.scale;
  return true;
}

}  // namespace kanesim::lang::elab
