// Variables' values, evaluated on first use from their bindings (GetVar), a parameter's
// flat parameters made then, and a component reference resolved to the instance node it
// names (ResolveNode): the evaluator's reading of the instance tree (lang/elab_eval.h).
#include <algorithm>
#include <charconv>
#include <cmath>

#include "lang/elab_eval.h"

namespace kanesim::lang::elab {

namespace {

// Number of elements of a shape; a ':' dimension not yet known counts as 0.
size_t ElementCount(const Dims& shape) {
  size_t count = 1;
  for (int d : shape) count *= static_cast<size_t>(d < 0 ? 0 : d);
  return count;
}

// "scalar", or "[2, 3]".
std::string ShapeText(const Dims& shape) {
  if (shape.empty()) return "scalar";
  std::string s = "[";
  for (size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

// An attribute written as a literal (min = 0, unit = "m": nearly all) is read from the
// syntax; evaluating it would give the same value through a pool node nothing reads.
bool IsLiteral(const ModValue& mv, ast::ExprKind kind) {
  return !mv.pre && mv.expr && mv.expr->kind == kind &&
         (kind != ast::ExprKind::Number || std::isfinite(mv.expr->number));
}

flat::ParamType ParamTypeOf(VType t) {
  return t == VType::Real      ? flat::ParamType::Real
         : t == VType::Integer ? flat::ParamType::Integer
         : t == VType::Boolean ? flat::ParamType::Boolean
                               : flat::ParamType::String;
}

// The decimal digits of v >= 0 at p; returns their end. Subscripts are nearly all below
// 100: written without std::to_chars's general path.
char* WriteIndex(char* p, int v) {
  if (v < 10) {
    *p++ = static_cast<char>('0' + v);
    return p;
  }
  if (v < 100) {
    *p++ = static_cast<char>('0' + v / 10);
    *p++ = static_cast<char>('0' + v % 10);
    return p;
  }
  return std::to_chars(p, p + 12, v).ptr;
}

// The subscript of element k (row-major) of an array of `shape`, "[1,2]" (1-based),
// appended to `name`; nothing for a scalar. `idx` is scratch of shape.size() entries.
void AppendSubscript(std::string& name, const Dims& shape, size_t k, Dims& idx) {
  if (shape.empty()) return;
  char buf[64];
  char* p = buf;
  if (shape.size() == 1) {  // a vector (most arrays): its index is k + 1
    *p++ = '[';
    p = WriteIndex(p, static_cast<int>(k) + 1);
    *p++ = ']';
    name.append(buf, static_cast<size_t>(p - buf));
    return;
  }
  size_t rem = k;
  for (size_t d = shape.size(); d-- > 0;) {
    idx[d] = static_cast<int>(rem % static_cast<size_t>(shape[d])) + 1;
    rem /= static_cast<size_t>(shape[d]);
  }
  // Written into a buffer and appended at once (a name per element: thousands of them).
  *p++ = '[';
  for (size_t d = 0; d < idx.size(); ++d) {
    if (p > buf + sizeof buf - 13) {  // room for ',' and an int, then ']'
      name.append(buf, static_cast<size_t>(p - buf));
      p = buf;
    }
    if (d) *p++ = ',';
    p = WriteIndex(p, idx[d]);
  }
  *p++ = ']';
  name.append(buf, static_cast<size_t>(p - buf));
}

// The flat name of element k of variable `var` of `shape`: "p" or "p[1,2]".
std::string ElementName(const Node* var, const Dims& shape, size_t k, Dims& idx) {
  std::string name;
  var->AppendPath(name);
  AppendSubscript(name, shape, k, idx);
  return name;
}

}  // namespace

Value Evaluator::EvalModValue(const ModValue& mv, Span* where) {
  if (where) *where = mv.span;
  if (mv.pre) return *mv.pre;
  if (!mv.expr) return Value::Invalid();
  Ctx ctx{mv.scope, mv.iters.get()};
  return Eval(*mv.expr, ctx);
}


void Evaluator::ReserveParams(size_t n) {
  // About two pool nodes per instance by the end of the emitter (Talos 6,596 for 3,638
  // instances, the chain of 100 9,422 for 5,909): pushed without the vector's regrowth.
  m_->exprs.Reserve(m_->exprs.size() + 2 * n);
  param_eval_.Reserve(m_->exprs.size() + 2 * n);
  m_->params.reserve(n);
  m_->param_names.reserve(n * 24);  // about a name's length in the library's parts
  pvals_.reserve(n);
}

const Value& Evaluator::GetVar(Node* var, Span use_span) {
  if (var->state == EvalState::Done) return var->value;
  if (var->state == EvalState::Evaluating) {
    auto& d = diags_.Error(DiagCode::Circular, use_span, "'" + var->Path() + "' is defined in terms of itself");
    if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
    var->state = EvalState::Done;
    var->value = Value::Invalid();
    return var->value;
  }
  var->state = EvalState::Evaluating;
  var->value = EvaluateVar(var, use_span);
  var->state = EvalState::Done;
  return var->value;
}

Value Evaluator::EvaluateVar(Node* var, Span use_span) {
  Node* owner = var->parent;
  // Joint coordinates and speeds are the mechanism's state.
  if (owner && owner->prim == Prim::Joint && var->variability == ast::Variability::None &&
      (var->name == "q" || var->name == "u"))
    return JointStateValue(var);
  const ModValue* binding = VarBinding(var);
  // A top-level input without a value (none in the file, none from --set) is the model's.
  if (!binding && var->causality == ast::Causality::Input && owner && !owner->parent &&
      var->variability == ast::Variability::None && var->eq_elem_binding.empty())
    return InputValue(var, use_span);
  Value v = binding ? BoundValue(var, *binding) : UnboundValue(var, use_span);
  if (!v.valid) return v;
  ApplyElementEquations(var, v);
  if (var->variability == ast::Variability::None) return v;
  return ParameterValue(var, binding, use_span, std::move(v));
}

Value Evaluator::JointStateValue(Node* var) {
  Value v;
  v.shape = var->shape;
  const size_t count = ElementCount(var->shape);
  const auto kind = var->name == "q" ? flat::StateKind::JointQ : flat::StateKind::JointU;
  for (size_t k = 0; k < count; ++k)
    v.elements.push_back(
        m_->exprs.State(m_->AddStateRef({kind, var->parent->prim_index, static_cast<int>(k)})));
  return v;
}

Value Evaluator::InputValue(Node* var, Span use_span) {
  const Span at = var->decl ? var->decl->name_span : use_span;
  if (var->vtype != VType::Real) {
    diags_.Error(DiagCode::TypeMismatch, at, "input '" + var->Path() + "' is " + VTypeName(var->vtype) + "; inputs are Real")
        .hint = "declare it 'input Real " + var->name + ";'";
    return Value::Invalid();
  }
  for (long d : var->shape)
    if (d < 0) {
      diags_.Error(DiagCode::SizeMismatch, at, "input '" + var->Path() + "' needs a fixed size")
          .hint = "give its size, as in 'input Real f[3];'";
      return Value::Invalid();
    }
  Value v;
  v.type = VType::Real;
  v.shape = var->shape;
  const size_t count = ElementCount(var->shape);
  Dims idx;
  idx.assign(var->shape.size(), 0);
  const flat::SourceLoc loc = places_.Loc(at);
  const std::string unit = ReadParamAttributes(var).unit;  // the unit check reads it from the declaration too
  for (size_t k = 0; k < count; ++k) {
    m_->inputs.push_back({ElementName(var, var->shape, k, idx), loc, unit});
    v.elements.push_back(m_->exprs.Input(static_cast<int>(m_->inputs.size() - 1)));
  }
  return v;
}

const ModValue* Evaluator::VarBinding(Node* var) {
  const ModValue* binding = nullptr;
  if (var->eq_binding) binding = &*var->eq_binding;
  if (const ModView mods = var->Modifiers(); mods.value) {
    if (binding) {
      auto& d = diags_.Error(DiagCode::ConflictingEquation, var->eq_binding->span,
                             "'" + var->Path() + "' already has a value from its declaration or a modifier");
      d.notes.push_back({mods.value->span, "value given here"});
    }
    binding = &*mods.value;
  }
  return binding;
}

Value Evaluator::UnboundValue(Node* var, Span use_span) {
  Node* owner = var->parent;
  const bool is_param = var->variability != ast::Variability::None;
  const bool is_primitive_field = owner && owner->prim != Prim::None;
  const size_t count = ElementCount(var->shape);
  const bool any_elem = !var->eq_elem_binding.empty();
  if (any_elem && !is_primitive_field && var->eq_elem_binding.size() != count) {
    for (size_t k = 0; k < count; ++k) {
      if (var->eq_elem_binding.count(static_cast<int>(k))) continue;
      auto& d = diags_.Error(DiagCode::MissingValue, var->decl ? var->decl->name_span : use_span,
                             "element " + std::to_string(k + 1) + " of '" + var->Path() + "' has no equation");
      d.hint = "give every element an equation, or bind the whole variable";
      break;
    }
    return Value::Invalid();
  }
  if ((is_primitive_field && !is_param) || any_elem) {
    Value v;
    v.type = var->vtype;
    v.shape = var->shape;
    v.elements.assign(count, m_->exprs.Constant(0));
    return v;
  }
  auto& d = diags_.Error(DiagCode::MissingValue, var->decl ? var->decl->name_span : use_span,
                         std::string(is_param ? "parameter" : "variable") + " '" + var->Path() + "' has no value");
  d.hint = is_param ? "give it a binding (parameter Real x = 1;), a modifier, or --set " + var->Path() + "=..."
                    : "bind it in its declaration (Real x = ...;) or with an equation 'x = ...;'";
  if (use_span.valid() && var->decl && use_span.begin != var->decl->name_span.begin)
    d.notes.push_back({use_span, "used here"});
  return Value::Invalid();
}

Value Evaluator::BoundValue(Node* var, const ModValue& binding) {
  Span where;
  Value v = EvalModValue(binding, &where);
  if (!v.valid) return v;
  if (!CheckValueType(var, binding, v, where)) return Value::Invalid();
  if (v.type == VType::Integer && var->vtype == VType::Real) v.type = VType::Real;
  // Shape: ':' dims adopt the value's size.
  bool shape_ok = v.shape.size() == var->shape.size();
  for (size_t i = 0; shape_ok && i < v.shape.size(); ++i) {
    if (var->shape[i] < 0) var->shape[i] = v.shape[i];
    shape_ok = var->shape[i] == v.shape[i];
  }
  if (!shape_ok) {
    auto& d = diags_.Error(binding.from_set ? DiagCode::BadSet : DiagCode::SizeMismatch, where,
                           "'" + var->Path() + "' has size " + ShapeText(var->shape) + " but its value has size " +
                               ShapeText(v.shape));
    if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
    return Value::Invalid();
  }
  return v;
}

bool Evaluator::CheckValueType(Node* var, const ModValue& binding, const Value& v, Span where) {
  bool ok = true;
  if (var->vtype == VType::String || v.type == VType::String) ok = var->vtype == v.type;
  else if (var->vtype == VType::Boolean || v.type == VType::Boolean) ok = var->vtype == v.type;
  else if (var->vtype == VType::Integer && v.type == VType::Real) {
    // Accept Real values that are whole numbers only from literal folding.
    ok = false;
  }
  if (ok) return true;
  auto& d = diags_.Error(binding.from_set ? DiagCode::BadSet : DiagCode::TypeMismatch, where,
                         "'" + var->Path() + "' is " + VTypeName(var->vtype) + " but its value is " + VTypeName(v.type));
  if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
  if (var->vtype == VType::Integer) d.hint = "use a whole number, or integer(...)";
  return false;
}

void Evaluator::ApplyElementEquations(Node* var, Value& v) {
  for (const auto& [k, mv] : var->eq_elem_binding) {
    if (k < 0 || static_cast<size_t>(k) >= v.elements.size()) continue;
    Value ev = EvalModValue(mv, nullptr);
    if (!ev.valid) continue;
    if (!ev.shape.empty()) {
      diags_.Error(DiagCode::SizeMismatch, mv.span, "an element equation needs a scalar value");
      continue;
    }
    v.elements[static_cast<size_t>(k)] = ev.elements[0];
  }
}

Value Evaluator::ParameterValue(Node* var, const ModValue* binding, Span use_span, Value v) {
  // Parameters and constants: no time, no state.
  for (ExprId x : v.elements) {
    if (x >= 0 && m_->exprs.DependsOnTimeOrState(x)) {
      auto& d = diags_.Error(DiagCode::NotConstantExpr, binding ? binding->span : use_span,
                             "the value of parameter '" + var->Path() + "' depends on time or on the motion");
      d.hint = "parameters are fixed before the simulation; use a variable (Real x = ...) instead";
      return Value::Invalid();
    }
  }
  const ParamAttributes attrs = ReadParamAttributes(var);
  const Span value_span = binding ? binding->span : use_span;
  const flat::SourceLoc loc = places_.Loc(var->decl ? var->decl->name_span : use_span);
  Dims idx;
  idx.assign(var->shape.size(), 0);
  // A constant is folded (no flat parameter); the others are made in place in the table.
  const bool folded = var->vtype != VType::String && var->variability == ast::Variability::Constant;
  std::string folded_name;
  // The variable's path, walked up the tree once for all its elements. Nothing below
  // evaluates (the attributes were read above), so the scratch is not reused meanwhile.
  std::string& path = path_scratch_;
  path.clear();
  var->AppendPath(path);
  flat::Param folded_param;  // a constant's element: reset for each (made once, not per element)
  for (size_t k = 0; k < v.elements.size(); ++k) {  // element k is read before it is replaced
    if (folded) folded_param = flat::Param{};
    auto write_name = [&](std::string& out) {
      out += path;
      AppendSubscript(out, var->shape, k, idx);
    };
    if (folded) folded_name.clear(), write_name(folded_name);
    flat::Param& p = folded ? folded_param : m_->AddParamWith(write_name);
    p.type = ParamTypeOf(var->vtype);
    p.unit = attrs.unit;
    p.min = attrs.min;
    p.max = attrs.max;
    p.is_constant = var->variability == ast::Variability::Constant;
    p.user_set = binding && binding->from_set;
    p.loc = loc;
    if (var->vtype == VType::String) {
      p.string_value = v.strings.empty() ? "" : v.strings[k];
      pvals_.push_back(0.0);
      continue;
    }
    const std::string_view name = folded ? std::string_view(folded_name) : m_->ParamName(m_->params.size() - 1);
    v.elements[k] = AddParamElement(var, p, name, v.elements[k], value_span);
  }
  return v;
}

Evaluator::ParamAttributes Evaluator::ReadParamAttributes(Node* var) {
  ParamAttributes attrs;
  const ModView mods = var->Modifiers();
  // One pass over the few modifiers a variable has, instead of a search per attribute
  // (every parameter element of the model comes here); read in the order min, max, unit.
  const ModValue* min = nullptr;
  const ModValue* max = nullptr;
  const ModValue* unit = nullptr;
  for (const auto& [key, sub] : mods.sub) {
    if (!sub.value) continue;
    const std::string_view k = key;
    if (k == "min") min = &*sub.value;
    else if (k == "max") max = &*sub.value;
    else if (k == "unit") unit = &*sub.value;
  }
  auto attr_num = [&](const ModValue* mv, const char* key, double* out) {
    if (!mv) return;
    if (IsLiteral(*mv, ast::ExprKind::Number)) {
      *out = mv->expr->number;
      return;
    }
    Value a = EvalModValue(*mv, nullptr);
    if (a.valid && a.shape.empty() && a.type != VType::String) Structural(a, mv->span, out, key);
  };
  attr_num(min, "min", &attrs.min);
  attr_num(max, "max", &attrs.max);
  if (unit) {
    if (IsLiteral(*unit, ast::ExprKind::String)) {
      attrs.unit = unit->expr->text;
    } else {
      Value a = EvalModValue(*unit, nullptr);
      if (a.valid && a.type == VType::String && !a.strings.empty()) attrs.unit = a.strings[0];
    }
  }
  return attrs;
}

ExprId Evaluator::AddParamElement(Node* var, flat::Param& p, std::string_view name, ExprId x, Span value_span) {
  double val = param_eval_.Eval(x);
  p.value = val;
  p.binding = m_->exprs.IsConstant(x) ? flat::kNoExpr : x;
  if (!std::isfinite(val)) {
    auto& d = diags_.Error(DiagCode::BadValue, value_span, "parameter '" + std::string(name) + "' evaluates to " + std::to_string(val));
    if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
  } else if (val < p.min || val > p.max) {
    auto& d = diags_.Error(DiagCode::BadValue, value_span,
                           "parameter '" + std::string(name) + "' = " + std::to_string(val) + " is outside its range [" +
                               (p.min <= -1e299 ? std::string("-inf") : std::to_string(p.min)) + ", " +
                               (p.max >= 1e299 ? std::string("inf") : std::to_string(p.max)) + "]");
    if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
  }
  if (p.is_constant) return m_->exprs.Constant(val);
  pvals_.push_back(val);  // p is already the last of m_->params
  return m_->exprs.Parameter(static_cast<int>(m_->params.size() - 1));
}

Node* Evaluator::ResolveNode(const ast::Expr& ref, const Ctx& ctx, int* elem) {
  if (elem) *elem = -1;
  if (ref.kind != ast::ExprKind::Ref || ref.parts.empty()) {
    diags_.Error(DiagCode::BadEquation, ref.span, "expected a component reference");
    return nullptr;
  }
  Node* n = nullptr;
  for (size_t pi = 0; pi < ref.parts.size(); ++pi) {
    const ast::RefPart& part = ref.parts[pi];
    if (pi > 0 && n->kind == Node::kArray) {
      auto& d = diags_.Error(DiagCode::TypeMismatch, ref.parts[pi - 1].span,
                             "'" + n->Path() + "' is an array of components; index it before '." + part.name + "'");
      d.hint = "write " + ref.parts[pi - 1].name + "[i]." + part.name + " inside a for-loop";
      return nullptr;
    }
    Node* next = pi == 0 ? (ctx.scope ? ctx.scope->Child(part.name) : nullptr)
                         : (n->kind == Node::kClass ? n->Child(part.name) : nullptr);
    if (!next) {
      std::vector<std::string> cands;
      Node* where = pi == 0 ? ctx.scope : n;
      if (where)
        for (auto& c : where->children) cands.push_back(c->name);
      auto& d = diags_.Error(DiagCode::UnknownName, part.span,
                             pi == 0 ? "unknown name '" + part.name + "'"
                                     : "'" + n->Path() + "' has no member '" + part.name + "'");
      std::string best = ClosestName(part.name, cands);
      if (!best.empty()) d.hint = "did you mean '" + best + "'?";
      return nullptr;
    }
    n = next;
    if (!n->enabled) return n;  // callers skip disabled components
    if (!part.subscripts.empty()) {
      if (n->kind == Node::kArray) {
        if (part.subscripts.size() != 1) {
          diags_.Error(DiagCode::TypeMismatch, part.span, "arrays of components take one subscript");
          return nullptr;
        }
        long k = 0;
        if (!StructuralInt(Eval(*part.subscripts[0], ctx), part.subscripts[0]->span, &k, "a subscript")) return nullptr;
        if (k < 1 || k > static_cast<long>(n->elems.size())) {
          diags_.Error(DiagCode::IndexOutOfRange, part.subscripts[0]->span,
                       "index " + std::to_string(k) + " is out of range 1.." + std::to_string(n->elems.size()) +
                           " of '" + n->Path() + "'");
          return nullptr;
        }
        n = n->elems[static_cast<size_t>(k - 1)].get();
      } else if (n->kind == Node::kVar && pi + 1 == ref.parts.size()) {
        size_t flatk = 0, stride = 1;
        if (part.subscripts.size() != n->shape.size()) {
          diags_.Error(DiagCode::IndexOutOfRange, part.span, "'" + n->Path() + "' needs " +
                                                                std::to_string(n->shape.size()) + " subscript(s)");
          return nullptr;
        }
        for (size_t d = part.subscripts.size(); d-- > 0;) {
          long k = 0;
          if (!StructuralInt(Eval(*part.subscripts[d], ctx), part.subscripts[d]->span, &k, "a subscript"))
            return nullptr;
          if (k < 1 || k > n->shape[d]) {
            diags_.Error(DiagCode::IndexOutOfRange, part.subscripts[d]->span,
                         "index " + std::to_string(k) + " is out of range 1.." + std::to_string(n->shape[d]));
            return nullptr;
          }
          flatk += static_cast<size_t>(k - 1) * stride;
          stride *= static_cast<size_t>(n->shape[d]);
        }
        if (elem) *elem = static_cast<int>(flatk);
      } else {
        diags_.Error(DiagCode::TypeMismatch, part.span, "'" + n->Path() + "' is not an array");
        return nullptr;
      }
    }
  }
  return n;
}

}  // namespace kanesim::lang::elab
