// The unit check (lang/elab_units.h): shown each variable by the emitter's walk, it gives
// each binding's expression a unit (lang/elab_units_expr.cpp) and compares it with the
// variable's, declared or inferred.
#include "lang/elab_units.h"

#include "lang/elab_units_checker.h"

namespace kanesim::lang::elab {

void UnitChecker::Show(Node* var) {
  if ((var->vtype != VType::Real && var->vtype != VType::Integer) || diags_.Full()) return;
  if (var->mod_from_decl) {
    // The declaration's literals (Instantiator::DeclarationMod): a number, string or array of
    // numbers has no unit to check and infers none; only the declared unit is parsed (E236),
    // once per declaration (the other instances share the modifier; read when named). A value
    // given from outside (Node::mod_over_decl) is checked.
    auto& seen = seen_decl_[(reinterpret_cast<std::uintptr_t>(var->shared_mod) >> 4) % seen_decl_.size()];
    if (seen != var->shared_mod) {
      DeclaredUnit(var);
      seen = var->shared_mod;
    }
    if (const ModValue* v = var->mod_over_decl ? var->Modifiers().value : nullptr) Pend(var, v, "the value of", false);
  } else if (!var->shared_mod) {  // (an array element's shared with element 1: checked there, lang/elab_share.cpp)
    DeclaredUnit(var);  // parses a declared unit (E236) even when nothing is bound
    const ModView mods = var->Modifiers();
    const ModValue* attrs[3] = {};  // start, min, max: one pass over the few attributes
    for (const auto& [key, sub] : mods.sub) {
      if (!sub.value) continue;
      if (Is(key, "start")) attrs[0] = &*sub.value;
      else if (Is(key, "min")) attrs[1] = &*sub.value;
      else if (Is(key, "max")) attrs[2] = &*sub.value;
    }
    if (mods.value) Pend(var, &*mods.value, "the value of", false);
    if (attrs[0]) Pend(var, attrs[0], "start", false);
    if (attrs[1]) Pend(var, attrs[1], "min", false);
    if (attrs[2]) Pend(var, attrs[2], "max", false);
  }
  if (var->eq_binding) Pend(var, &*var->eq_binding, "", true);
  if (!var->eq_elem_binding.empty())
    for (const auto& [k, mv] : var->eq_elem_binding) Pend(var, &mv, "", !mv.from_set);
  if (!var->shape.empty() && (Is(var->name, "q") || Is(var->name, "u")) && var->parent &&
      var->parent->prim == Prim::Joint)
    pending_.push_back({var, nullptr, nullptr, false});  // its coordinates, unless it declares one unit
  if (pending_.size() >= kBatch) Flush();
}

void UnitChecker::Pend(Node* var, const ModValue* mv, const char* what, bool is_equation) {
  // A number takes the unit it is given (min = 0), numbers in an array none: nothing to
  // check, nothing to infer (a variable's own binding is read by its first value checked).
  if (!mv->expr || IsNumber(*mv->expr)) return;
  if ((mv->expr->kind != ast::ExprKind::Array && mv->expr->kind != ast::ExprKind::Matrix) || !IsLiteral(*mv->expr))
    pending_.push_back({var, mv, what, is_equation});
}

void UnitChecker::Flush() {
  if (flushing_) return;
  flushing_ = true;
  for (const Pending& p : pending_) {
    if (p.mv) CheckBinding(p.var, *p.mv, p.what, p.is_equation);
    else if (!diags_.Full() && !DeclaredUnit(p.var)) CheckCoordinates(p.var);
  }
  pending_.clear();
  flushing_ = false;
}

void UnitChecker::CheckCoordinates(Node* var) {
  if (auto it = var->Modifiers().sub.find("start"); it != var->Modifiers().sub.end() && it->second.value) {
    const ModValue& mv = *it->second.value;
    if (mv.expr && mv.expr->kind == ast::ExprKind::Array)
      for (size_t k = 0; k < mv.expr->args.size(); ++k) CheckElement(var, *mv.expr->args[k], mv, static_cast<int>(k), "start");
  }
  for (const auto& [k, mv] : var->eq_elem_binding)
    if (mv.expr) CheckElement(var, *mv.expr, mv, k, "");
}

void UnitChecker::CheckElement(Node* var, const ast::Expr& e, const ModValue& mv, int k, const char* what) {
  const Node* joint = var->parent;
  const bool quaternion = joint->prim_kind == "free" ? var->shape[0] == 7 : var->shape[0] == 4;
  const std::string text = JointCoordinateUnit(joint->prim_kind, quaternion, k, var->name == "u");
  Unit want;
  std::string error;
  if (text.empty() || !ParseUnit(text, &want, &error)) return;
  const UVal got = Bound(e, mv, *what != 0);
  if (got.kind != UVal::Known || got.soft || got.unit.Agrees(want)) return;
  const std::string name = "'" + var->Path() + "[" + std::to_string(k + 1) + "]'";
  auto& d = diags_.Error(DiagCode::UnitMismatch, e.span,
                         (*what ? std::string("the start value of ") + name : "the equation of " + name) + " has unit " +
                             Shown(got) + ", not \"" + text + "\"");
  NoteOrigin(d, got);
  d.hint = "coordinate " + std::to_string(k + 1) + " of a " + joint->prim_kind + " joint's " + var->name + " is in \"" +
           text + "\"";
}

// A spring or damper on flanges (Prim::RotSpring) connected to a joint's drive or support:
// its stiffness, damping and unstretched coordinate in the joint's units.
void UnitChecker::SpringUnits(const InstanceTree& tree, const Links& links) {
  auto joint_of = [&](int flange) -> const Node* {
    if (flange < 0 || static_cast<size_t>(flange) >= tree.flanges.size()) return nullptr;
    const Node* p = tree.flanges[static_cast<size_t>(flange)]->parent;
    return p && p->prim == Prim::Joint ? p : nullptr;
  };
  auto spring_of = [&](int flange) -> const Node* {
    if (flange < 0 || static_cast<size_t>(flange) >= tree.flanges.size()) return nullptr;
    const Node* p = tree.flanges[static_cast<size_t>(flange)]->parent;
    return p && p->prim == Prim::RotSpring ? p : nullptr;
  };
  for (const auto& [a, b] : links.flanges) {
    const Node* spring = spring_of(a) ? spring_of(a) : spring_of(b);
    const Node* joint = joint_of(a) ? joint_of(a) : joint_of(b);
    if (!spring || !joint) continue;
    const std::string q = JointCoordinateUnit(joint->prim_kind, false, 0, false);
    if (q.empty() || joint->prim_kind == "cylindrical" || joint->prim_kind == "planar" || joint->prim_kind == "free")
      continue;  // several coordinates: no one unit
    const char* force = q == "m" ? "N" : "N.m";
    for (const auto& [field, text] : {std::pair<const char*, std::string>{"c", std::string(force) + "/" + q},
                                      {"d", std::string(force) + ".s/" + q}, {"phi_rel0", q}}) {
      const Node* v = spring->Child(field);
      if (!v || v->kind != Node::kVar || DeclaredUnit(v)) continue;
      Declared& slot = implied_[v];
      slot.text = text;
      std::string error;
      slot.ok = ParseUnit(text, &slot.unit, &error);
    }
  }
}

void UnitChecker::CheckBinding(Node* var, const ModValue& mv, const char* what, bool is_equation) {
  // A number takes the unit it is given (min = 0): nothing to check, nothing to infer.
  if (!mv.expr || diags_.Full() || IsNumber(*mv.expr)) return;
  const UVal want = VarUnit(var);  // an undeclared scalar: its binding checked inside, once
  const bool own = &mv == (var->Modifiers().value ? &*var->Modifiers().value : var->eq_binding ? &*var->eq_binding : nullptr);
  if (want.kind != UVal::Known && own && var->shape.empty()) return;
  // Where the answer may be reused: the scope of a slice, or the copy id (negative).
  // Else, inside an instance of a class (not the model's root), that class: a binding written
  // in a library model reads the same declared units in each of its instances.
  const Node* cls = nullptr;
  std::intptr_t where = 0;
  if (mv.pre) {
    where = reinterpret_cast<std::intptr_t>(mv.scope);
  } else if (mv.scope && mv.scope->kind == Node::kClass && mv.scope->unit_slot >= 0) {
    where = -1 - static_cast<std::intptr_t>(mv.scope->unit_slot);
  } else if (mv.scope && mv.scope->kind == Node::kClass && mv.scope->parent && mv.scope->cls) {
    cls = mv.scope;
    where = reinterpret_cast<std::intptr_t>(cls->cls);
  }
  bool reused = false;
  UVal got = where ? BoundOnce(mv, !is_equation, where, cls, &reused) : Bound(*mv.expr, mv, !is_equation);
  if (want.kind != UVal::Known) return;
  if (got.kind != UVal::Known) {
    InferDown(mv.expr, want, mv.scope, mv.expr->span);
    return;
  }
  if (got.soft) return;
  if (want.unit.Agrees(got.unit)) return;
  if (reused && (where < 0 || cls)) {  // read again: the notes name this instance's declarations
    got = Bound(*mv.expr, mv, !is_equation);
    if (got.kind != UVal::Known) {
      InferDown(mv.expr, want, mv.scope, mv.expr->span);
      return;
    }
    if (got.soft || want.unit.Agrees(got.unit)) return;
  }
  const std::string name = "'" + var->Path() + "'";
  std::string msg = is_equation ? "the two sides of the equation have different units: " + name + " is " + Shown(want) +
                                      ", the right side " + Shown(got)
                    : std::string(what) == "the value of"
                        ? name + " has unit " + Shown(want) + " but its value has unit " + Shown(got)
                        : "the " + std::string(what) + " value of " + name + " has unit " + Shown(got) +
                              ", not " + Shown(want);
  auto& d = diags_.Error(DiagCode::UnitMismatch, is_equation ? mv.span : mv.expr->span, msg);
  if (var->decl) d.notes.push_back({var->decl->name_span, name + " is declared with unit " + Shown(want) + " here"});
  NoteOrigin(d, got);
  d.hint = want.unit.SameDimension(got.unit)
               ? "same dimension, different scale: convert the value to " + Shown(want)
               : "the value must be in " + Shown(want) + (got.origin ? "; check the unit of '" + got.origin->Path() + "'" : "");
}

void UnitChecker::NoteOrigin(Diagnostic& d, const UVal& v) {
  if (!v.origin || !v.origin->decl) return;
  auto it = inferred_.find(v.origin);
  const std::string how = it != inferred_.end() ? " (inferred)" : "";
  d.notes.push_back({v.origin->decl->name_span, "'" + v.origin->Path() + "' has unit " + Shown(VarUnit(v.origin)) + how});
}

const UnitChecker::Declared* UnitChecker::DeclaredUnit(const Node* var) {
  // Kept on the node: a variable is read by every binding that names it.
  if (var->unit_slot >= 0) return table_[static_cast<size_t>(var->unit_slot)];
  if (var->unit_slot <= kNoUnit) return nullptr;
  const Declared* d = FindDeclaredUnit(var);
  var->unit_slot = d ? d->index : kNoUnit;
  return d;
}

const UnitChecker::Declared* UnitChecker::FindDeclaredUnit(const Node* var) {
  const Mod* unit = UnitMod(var->Modifiers().sub);
  if (!unit || !unit->value || !unit->value->expr) return nullptr;
  const ast::Expr* e = unit->value->expr;
  // A direct-mapped cache in front of declared_: a model has a few dozen unit strings.
  auto& recent = recent_[(reinterpret_cast<std::uintptr_t>(e) >> 4) % recent_.size()];
  if (recent.first == e) return recent.second;
  if (e->kind != ast::ExprKind::String || e->text.empty()) return nullptr;
  // A unit string not seen yet may be reported (E236): the values shown before are checked
  // first, so that the messages come in the order of the walk.
  if (!flushing_ && !pending_.empty() && !declared_.count(e)) Flush();
  auto [slot, fresh] = declared_.try_emplace(e);
  if (fresh) {
    slot->second.index = static_cast<int>(table_.size());
    table_.push_back(&slot->second);
    std::string error;
    slot->second.ok = ParseUnit(e->text, &slot->second.unit, &error);
    slot->second.text = e->text;
    if (!slot->second.ok)
      diags_.Error(DiagCode::BadUnit, e->span, "\"" + e->text + "\" is not a unit: " + error)
          .hint = "Modelica unit syntax: \"N.m/rad\", \"kg.m2\", \"m/s2\", \"1\"; prefixes m, k, M, u, n, G...";
  }
  recent = {e, slot->second.ok ? &slot->second : nullptr};
  return recent.second;
}

UVal UnitChecker::VarUnit(const Node* var) {
  const Declared* d = DeclaredUnit(var);
  if (!d && !implied_.empty())
    if (auto it = implied_.find(var); it != implied_.end() && it->second.ok) {
      d = &it->second;
      ++impure_;  // from the joint the spring acts on: may differ between array elements
    }
  if (d) {
    if (within_ && !ReadInClass(var)) ++impure_;
    UVal v = UVal::Of(d->unit);
    v.origin = var;
    v.text = &d->text;
    return v;
  }
  // An array of no unit has none (nothing is inferred for arrays).
  if (!within_ || var->shape.empty() || !ReadInClass(var)) ++impure_;
  const int state = var->unit_slot;
  if (state == kInferredNothing || state == kInferring) return UVal{};
  if (state == kInferred) {
    const Inferred& slot = inferred_.find(var)->second;
    return slot.busy ? UVal{} : slot.val;
  }
  // Inferred from the binding, once: an output's unit from its expression.
  const ModValue* b = var->Modifiers().value ? &*var->Modifiers().value : var->eq_binding ? &*var->eq_binding : nullptr;
  if (chain_ >= kMaxInferChain) return UVal{};  // tried again where the chain is shorter
  if (!b || !b->expr || !var->shape.empty() || IsNumber(*b->expr)) {
    var->unit_slot = kInferredNothing;
    return UVal{};
  }
  var->unit_slot = kInferring;
  ++chain_;
  UVal v = Bound(*b->expr, *b, var->Modifiers().value && b == &*var->Modifiers().value);
  --chain_;
  if (v.kind == UVal::Known) v.origin = var;
  if (var->unit_slot == kInferred) {  // a use inside its own binding gave it a unit meanwhile
    Inferred& slot = inferred_[var];
    slot.busy = false;
    if (v.kind == UVal::Known) slot.val = v;
    return slot.val;
  }
  if (v.kind != UVal::Known) {
    var->unit_slot = kInferredNothing;  // no entry in inferred_: most undeclared variables
    return UVal{};
  }
  inferred_[var].val = v;
  var->unit_slot = kInferred;
  return v;
}

UnitChecker::ByPath UnitChecker::InferredByPath() const {
  ByPath out;
  for (const auto& [n, slot] : inferred_)
    if (slot.val.kind == UVal::Known && !slot.val.soft && n->shape.empty())
      out.emplace(n->Path(), slot.val.text ? *slot.val.text : slot.val.unit.ToString());
  return out;
}

void UnitChecker::InferDown(const ast::Expr* e, const UVal& u, const Node* scope, Span at, int depth) {
  if (!e || depth + depth_ >= kMaxCheckDepth) return;  // as deep as Expr went, no deeper
  const Tok op = static_cast<Tok>(e->op);
  switch (e->kind) {
    case ast::ExprKind::Ref: InferFromUse(e, u, scope, at, depth == 0); return;
    case ast::ExprKind::Unary:
      if (op == Tok::Minus || op == Tok::Plus)
        for (const auto& x : e->args) InferDown(x.get(), u, scope, at, depth + 1);
      return;
    case ast::ExprKind::Binary:
      if (op == Tok::Plus || op == Tok::Minus)
        for (const auto& x : e->args) InferDown(x.get(), u, scope, at, depth + 1);
      return;
    case ast::ExprKind::If:  // the branches (odd positions and the last), not the conditions
      for (size_t i = 0; i < e->args.size(); ++i)
        if (i % 2 == 1 || i + 1 == e->args.size()) InferDown(e->args[i].get(), u, scope, at, depth + 1);
      return;
    default: return;
  }
}

void UnitChecker::InferFromUse(const ast::Expr* e, const UVal& u, const Node* scope, Span at, bool report) {
  if (!e || e->kind != ast::ExprKind::Ref || u.kind != UVal::Known || !scope) return;
  const Node* n = scope;
  for (const auto& p : e->parts) {
    if (n->kind != Node::kClass) return;
    n = n->Child(p.name);
    if (!n) return;
    if (n->kind == Node::kArray) {
      if (n->elems.empty()) return;
      n = n->elems[0].get();
    }
  }
  if (n->kind != Node::kVar || !n->shape.empty() || DeclaredUnit(n)) return;
  ++impure_;
  Inferred& slot = inferred_[n];
  if (n->unit_slot == kInferring) slot.busy = true;
  n->unit_slot = kInferred;
  if (slot.val.kind == UVal::Known) {
    if (!slot.from_use || slot.val.unit.Agrees(u.unit) || !report) return;
    auto& d = diags_.Error(DiagCode::UnitConflict, at,
                           "'" + n->Path() + "' has no unit and is used here as " + Shown(u) + ", but earlier as " +
                               Shown(slot.val));
    d.notes.push_back({slot.where, "used as " + Shown(slot.val) + " here"});
    d.hint = "declare its unit: " + n->name + "(unit = \"...\")";
    return;
  }
  slot.val = u;
  slot.val.origin = n;
  // u.text stays: the unit as declared where it came from ("N", not "m.kg/s2")
  slot.from_use = true;
  slot.where = at;
}

// A binding's unit found once for several variables: a slice of an array's modifier
// (`Revolute j[N](axis = {...})`) is the whole array's expression, read in the same scope by
// every element; a binding read inside an array element copied from element 1 reads names
// of the same declared units in every copy (Node::unit_slot). Reused while it read only
// declared units and reported nothing (inferred units may change, implied ones differ).
UVal UnitChecker::BoundOnce(const ModValue& mv, bool binding, std::intptr_t where, const Node* within, bool* hit) {
  Reuse& r = reused_[{mv.expr, where}];
  *hit = r.valid && r.iters == mv.iters.get() && r.binding == binding;
  if (*hit && within) {  // this instance's variables read there: their units from the class too
    const auto& kids = within->children;
    for (const auto& [k, decl] : r.reads) {
      const Node* var = static_cast<size_t>(k) < kids.size() ? kids[static_cast<size_t>(k)].get() : nullptr;
      if (!var || var->decl != decl || !UnitFromClass(var, within)) *hit = false;
    }
  }
  if (*hit) return r.val;
  const long impure = impure_;
  const size_t reported = diags_.All().size();
  within_ = within;
  reads_.clear();
  const UVal v = Bound(*mv.expr, mv, binding);
  within_ = nullptr;
  r.val = v;
  r.iters = mv.iters.get();
  r.binding = binding;
  r.valid = impure_ == impure && diags_.All().size() == reported;
  if (within) r.reads = reads_;
  return v;
}

bool UnitChecker::ReadInClass(const Node* var) {
  if (var->parent != within_ || !UnitFromClass(var, within_)) return false;
  const auto& kids = within_->children;
  for (size_t k = 0; k < kids.size(); ++k)
    if (kids[k].get() == var) {
      for (const auto& r : reads_)
        if (r.first == static_cast<int>(k)) return true;  // c[1] * c[2]: once
      reads_.emplace_back(static_cast<int>(k), var->decl);
      return true;
    }
  return false;
}

UVal UnitChecker::Bound(const ast::Expr& e, const ModValue& mv, bool binding) {
  const bool outer = factors_;
  factors_ = binding;
  const UVal v = Expr(e, mv.scope, mv.iters.get());
  factors_ = outer;
  return v;
}

UnitCheck::UnitCheck(const InstanceTree& tree, const Links& links, const SourceManager* sources)
    : found_(sources), checker_(std::make_unique<UnitChecker>(found_)) {
  checker_->SpringUnits(tree, links);
}

UnitCheck::~UnitCheck() = default;

void UnitCheck::Visit(Node* var) { checker_->Show(var); }

void UnitCheck::Finish(const InstanceTree& tree, Diagnostics& diags, flat::Mechanism* m) {
  checker_->Flush();
  if (diags.HasErrors()) return;
  // The messages, in the order found (the cap's message P105 becomes diags' own).
  for (const Diagnostic& d : found_.All()) {
    Diagnostic& copy = d.severity == Severity::Error ? diags.Error(d.code, d.span, d.message)
                                                     : diags.Warning(d.code, d.span, d.message);
    copy.notes = d.notes;
    copy.hint = d.hint;
  }
  // Outputs' units (for --units-in-header): the top-level model's output variables, named
  // by path, array elements "path[k]" (lang/elab_emit.cpp).
  const Node* root = tree.root.get();
  size_t i = 0;
  for (const auto& c : root->children) {
    if (!c->enabled || c->kind != Node::kVar || c->causality != ast::Causality::Output) continue;
    const UVal u = checker_->VarUnit(c.get());
    const std::string path = c->Path();
    auto named = [&](const std::string& n) {
      return n == path || (n.size() > path.size() && n.compare(0, path.size(), path) == 0 && n[path.size()] == '[');
    };
    for (; i < m->outputs.size() && named(m->outputs[i].name); ++i)
      if (u.kind == UVal::Known) m->outputs[i].unit = u.text ? *u.text : u.unit.ToString();
  }
  // Parameters and inputs that declare no unit take the inferred one (an FMU's variables and
  // UnitDefinitions, --emit flat, check): one pass, and only when something was inferred.
  const auto inferred = checker_->InferredByPath();
  if (inferred.empty()) return;
  for (size_t k = 0; k < m->params.size(); ++k) {
    flat::Param& p = m->params[k];
    if (!p.unit.empty() || p.type != flat::ParamType::Real) continue;
    if (auto it = inferred.find(m->ParamName(k)); it != inferred.end()) p.unit = it->second;
  }
  for (flat::Input& in : m->inputs)
    if (auto it = inferred.find(in.name); in.unit.empty() && it != inferred.end()) in.unit = it->second;
}

}  // namespace kanesim::lang::elab
