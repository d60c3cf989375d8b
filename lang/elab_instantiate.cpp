// Instantiate: classes become a tree of instance nodes (lang/elab_instantiate.h).
#include <algorithm>
#include <cmath>
#include <utility>

#include "lang/elab_instantiate.h"

#include "lang/elab_eval.h"
#include "lang/elab_lookup.h"
#include "lang/elab_modifiers.h"

namespace kanesim::lang::elab {

Instantiator::Instantiator(const ClassLookup& lookup, Evaluator& eval, const SourcePlaces& places,
                           Diagnostics& diags, bool subscripted_sets, bool share_siblings, InstanceTree* tree)
    : lookup_(lookup),
      eval_(eval),
      places_(places),
      diags_(diags),
      subscripted_sets_(subscripted_sets),
      share_siblings_(share_siblings),
      tree_(*tree) {}

void Instantiator::Run(const ast::ClassDef* top) { Instantiate(tree_.root.get(), top); }

bool Instantiator::TooLarge() const { return too_large_ || eval_.OverBudget(); }

const ast::ClassDef* Instantiator::ResolveShort(const ast::ClassDef* cls, Node* node, Mod* mod) {
  int guard = 0;
  while (cls && cls->is_short) {
    if (++guard > kMaxExtendsDepth) {
      diags_.Error(DiagCode::RecursiveExtends, cls->name_span, "short class definitions form a cycle");
      return nullptr;
    }
    const ast::ClassDef* base = lookup_.FindClass(cls->short_base, cls);
    if (!base) {
      diags_.Error(DiagCode::UnknownClass, cls->span, "unknown class '" + ast::JoinName(cls->short_base) + "'");
      return nullptr;
    }
    if (cls->short_mod)
      MergeMods(*mod, BuildMod(cls->short_mod.get(), node, nullptr, diags_), node ? MergeWhat(node) : MergeWhat(cls->name), diags_);
    cls = base;
  }
  return cls;
}

long Instantiator::CollectedNames::Find(std::string_view name, const std::vector<Collected>& out) const {
  if (!index_.empty()) {
    auto it = index_.find(name);
    return it == index_.end() ? -1 : static_cast<long>(it->second);
  }
  for (size_t i = 0; i < out.size(); ++i)
    if (out[i].comp->name == name) return static_cast<long>(i);
  return -1;
}

void Instantiator::CollectedNames::Added(const std::vector<Collected>& out) {
  if (out.size() <= kScan) return;
  if (index_.empty()) {  // past the scan's size: every element so far
    index_.reserve(2 * out.size());
    for (size_t i = 0; i < out.size(); ++i) index_.emplace(out[i].comp->name, i);
    return;
  }
  index_.emplace(out.back().comp->name, out.size() - 1);
}

void Instantiator::Collect(const ast::ClassDef* cls, Node* node, const Mod* ext_mod, std::vector<Collected>& out,
                           CollectedNames& names, std::vector<Node::EqSource>& eqs, int depth) {
  for (const ast::ClassDef* c : extends_stack_) {
    if (c == cls) {
      auto& d = diags_.Error(DiagCode::RecursiveExtends, cls->name_span,
                             "class '" + cls->name + "' extends itself (directly or through its bases)");
      for (const ast::ClassDef* s : extends_stack_) d.notes.push_back({s->name_span, "'" + s->name + "' is in the chain"});
      return;
    }
  }
  if (depth > kMaxExtendsDepth) {
    diags_.Error(DiagCode::RecursiveExtends, cls->name_span, "extends chain deeper than " +
                                                                std::to_string(kMaxExtendsDepth));
    return;
  }
  extends_stack_.push_back(cls);
  for (const auto& el : cls->elements) {
    if (diags_.Full()) break;
    if (el.kind == ast::Element::kExtends) {
      const ast::Extends& ex = *el.extends;
      const ast::ClassDef* base = lookup_.FindClass(ex.base, cls);
      if (!base) {
        auto& d = diags_.Error(DiagCode::UnknownClass, ex.span, "unknown base class '" + ast::JoinName(ex.base) + "'");
        std::vector<std::string> classes;
        for (const std::string& k : lookup_.AllNames())  // the hint considers every class
          classes.push_back(k.rfind("Kanesim.", 0) == 0 ? k.substr(8) : k);
        std::string best = ClosestName(ast::JoinName(ex.base), classes);
        if (!best.empty()) d.hint = "did you mean '" + best + "'?";
        continue;
      }
      Mod em = BuildMod(ex.mod.get(), node, nullptr, diags_);
      Mod effective;
      if (ext_mod) effective = *ext_mod;
      MergeBuiltMod(effective, std::move(em), &ex.base, diags_);
      // Short class as a base: fold its modifiers in.
      base = ResolveShort(base, node, &effective);
      if (!base) continue;
      Collect(base, node, &effective, out, names, eqs, depth + 1);
      continue;
    }
    if (el.kind != ast::Element::kComponent) continue;
    const ast::Component& comp = *el.component;
    Collected c;
    c.comp = &comp;
    c.owner = cls;
    c.is_final = comp.is_final;
    c.replaceable = comp.replaceable;
    if (ext_mod) {
      auto it = ext_mod->sub.find(comp.name);
      if (it != ext_mod->sub.end()) c.ext_mod = it->second;
    }
    bool replaced = false;
    if (comp.redeclare) names.repeated = true;
    if (const long found = names.known_distinct ? -1 : names.Find(comp.name, out); found >= 0) {
      names.repeated = true;
      Collected& prev = out[static_cast<size_t>(found)];
      if (comp.redeclare) {
        if (!prev.replaceable) {
          auto& d = diags_.Error(DiagCode::NotReplaceable, comp.name_span,
                                 "'" + comp.name + "' is not replaceable");
          d.notes.push_back({prev.comp->name_span, "declared here without 'replaceable'"});
        }
        prev = c;
      } else {
        auto& d = diags_.Error(DiagCode::Duplicate, comp.name_span, "'" + comp.name + "' is declared twice");
        d.notes.push_back({prev.comp->name_span, "first declared here"});
      }
      replaced = true;
    }
    if (!replaced) {
      if (comp.redeclare)
        diags_.Error(DiagCode::NotReplaceable, comp.name_span,
                     "'redeclare " + comp.name + "' replaces nothing: no inherited element has that name");
      out.push_back(std::move(c));
      names.Added(out);
    }
  }
  for (const auto& eq : cls->equations) eqs.push_back({&eq, cls});
  extends_stack_.pop_back();
}

// "prefix.name", or "name" at the root; one allocation (paths are made for every instance).
static Prim PrimFromName(const std::string& s) {
  if (s == "frame") return Prim::Frame;
  if (s == "flange") return Prim::Flange;
  if (s == "world") return Prim::World;
  if (s == "body") return Prim::Body;
  if (s == "fixed") return Prim::Fixed;
  if (s == "joint") return Prim::Joint;
  if (s == "lineforce") return Prim::LineForce;
  if (s == "wrench") return Prim::Wrench;
  if (s == "contact") return Prim::Contact;
  if (s == "rotspring") return Prim::RotSpring;
  if (s == "coupling") return Prim::Coupling;
  if (s == "shape") return Prim::Shape;
  return Prim::None;
}

// Gives a frame, flange or joint its id (in the order of instantiation) and a joint its
// flat entry (completed by Emit).
void Instantiator::RegisterPrimitive(Node* node, const ast::ClassDef* cls) {
  if (node->prim == Prim::Frame) {
    node->prim_index = static_cast<int>(tree_.frames.size());
    tree_.frames.push_back(node);
  } else if (node->prim == Prim::Flange) {
    node->prim_index = static_cast<int>(tree_.flanges.size());
    tree_.flanges.push_back(node);
  } else if (node->prim == Prim::Joint) {
    node->prim_index = static_cast<int>(tree_.joints.size());
    flat::Joint j;
    j.name = node->Path();
    if (!flat::JointTypeFromName(node->prim_kind, &j.type))
      diags_.Error(DiagCode::BadPrimitive, cls->name_span, "unknown joint kind '" + node->prim_kind + "'");
    j.loc = places_.Loc(node->decl ? node->decl->name_span : cls->name_span);
    tree_.joints.push_back(std::move(j));
  }
}

// A class instance: its primitive (if any), its elements collected through extends, one
// child node each with its merged modifier, then each child expanded.
void Instantiator::Instantiate(Node* node, const ast::ClassDef* cls) {
  if (node->depth > kMaxExtendsDepth) {
    diags_.Error(DiagCode::RecursiveExtends, node->decl ? node->decl->span : cls->name_span,
                 "components nested deeper than " + std::to_string(kMaxExtendsDepth) +
                     " levels (a class that contains itself?)");
    return;
  }
  cls = ResolveShort(cls, node, &node->mod);
  if (!cls) return;
  node->cls = cls;
  if (cls->partial) {
    auto& d = diags_.Error(DiagCode::PartialInstance, node->decl ? node->decl->type_span : cls->name_span,
                           "'" + cls->name + "' is partial and cannot be instantiated");
    d.notes.push_back({cls->name_span, "declared partial here"});
    d.hint = "extend it in a class of your own";
  }
  const ClassPrim& ann = PrimitiveAnnotation(cls);
  if (ann.has_prim) node->prim = ann.prim;
  if (ann.kind) node->prim_kind = *ann.kind;
  RegisterPrimitive(node, cls);

  std::vector<Collected> elems;
  elems.reserve(cls->elements.size());  // enough unless cls extends another class
  node->equations.reserve(cls->equations.size());
  CollectedNames names;
  auto [distinct, first] = distinct_elements_.try_emplace(cls, false);
  names.known_distinct = distinct->second;
  Collect(cls, node, nullptr, elems, names, node->equations, 0);
  if (first) distinct->second = !names.repeated;
  CheckOuterModifiers(node, cls, elems, names);

  node->children.reserve(elems.size());
  for (auto& c : elems) node->children.push_back(MakeChild(node, c));
  for (size_t i = 0; i < elems.size() && i < node->children.size(); ++i) {
    if (diags_.Full() || TooLarge()) break;
    Expand(node, node->children[i].get(), elems[i]);
  }
}

// Primitive? annotation(__kanesim(primitive = "joint", kind = "revolute"))
// The same for every instance of cls: read once per class.
const Instantiator::ClassPrim& Instantiator::PrimitiveAnnotation(const ast::ClassDef* cls) {
  auto [ann, fresh] = primitive_annotation_.try_emplace(cls);
  if (!fresh) return ann->second;
  if (const ast::Modification* pm = lookup_.FindAnnotation(cls, "__kanesim")) {
    for (const auto& a : pm->args) {
      if (a.path.size() != 1 || !a.mod || !a.mod->value || a.mod->value->kind != ast::ExprKind::String) continue;
      if (a.path[0] == "primitive") ann->second.prim = PrimFromName(a.mod->value->text), ann->second.has_prim = true;
      if (a.path[0] == "kind") ann->second.kind = &a.mod->value->text;
    }
  }
  return ann->second;
}

// Every outer modifier must name an element, and not a protected one.
void Instantiator::CheckOuterModifiers(Node* node, const ast::ClassDef* cls, const std::vector<Collected>& elems,
                                       const CollectedNames& names) {
  for (const auto& key : node->mod.order) {
    bool found = false;
    if (const long at = names.Find(key, elems); at >= 0) {
      const Collected& c = elems[static_cast<size_t>(at)];
      found = true;
      const Mod& pm = node->mod.sub[key];
      if (c.comp->is_protected && !(pm.value && pm.value->from_set)) {
        auto& d = diags_.Error(DiagCode::UnknownModifier, pm.span,
                               "'" + key + "' is protected in '" + cls->name + "' and cannot be modified");
        d.notes.push_back({c.comp->name_span, "declared protected here"});
      }
    }
    if (found) continue;
    const Mod& sm = node->mod.sub[key];
    if (sm.set_only) continue;  // --set names are checked by SetOverrides::Bind
    std::vector<std::string> all;
    for (const auto& c : elems) all.push_back(c.comp->name);
    auto& d = diags_.Error(DiagCode::UnknownModifier, sm.span, "'" + cls->name + "' has no element '" + key + "'");
    std::string best = ClosestName(key, all);
    if (!best.empty()) d.hint = "did you mean '" + best + "'?";
    d.notes.push_back({cls->name_span, "'" + cls->name + "' is declared here"});
  }
}

// An outer modifier that gives a value and nothing else (`m = 2.5`): merged over a literal
// declaration's, it replaces the value and leaves the attributes as declared.
static bool OnlyAValue(const Mod& m) {
  return m.value && !m.value->is_final && m.sub.empty() && m.order.empty() && !m.each && !m.is_final &&
         !m.redeclare && !m.set_only;
}

// The child node of element c, its modifier merged: outer (the instance's) over the
// extends clause's over the declaration's.
NodePtr Instantiator::MakeChild(Node* node, Collected& c) {
  auto child = tree_.arena.New();
  child->parent = node;
  child->decl = c.comp;
  child->name = c.comp->name;
  child->depth = node->depth + 1;
  auto it = node->mod.sub.find(c.comp->name);
  const bool found = it != node->mod.sub.end();
  if ((!found || OnlyAValue(it->second)) && !c.is_final && c.ext_mod.empty() && !c.ext_mod.is_final &&
      !c.ext_mod.each) {
    if (const Mod* shared = DeclarationMod(node, *c.comp)) {
      child->shared_mod = shared;
      child->mod_from_decl = true;
      if (found) {  // the outer value over the declaration's attributes (Node::mod_over_decl)
        child->mod = std::move(it->second);
        child->mod_over_decl = true;
      }
      return child;
    }
  }
  Mod& outer = child->mod;  // merged in place (the merges read the child only for its path)
  if (it != node->mod.sub.end()) outer = std::move(it->second);  // read nowhere else: Collect dropped duplicates
  if (c.is_final && !outer.empty() && !(outer.value && outer.value->from_set)) {
    Span at = outer.value ? outer.value->span : outer.span;
    auto& d = diags_.Error(DiagCode::FinalOverride, at, "'" + child->Path() + "' is final and cannot be modified");
    d.notes.push_back({c.comp->span, "declared final here"});
    outer = Mod{};
  }
  MergeMods(outer, std::move(c.ext_mod), child.get(), diags_);  // Expand reads c's other fields only
  Mod decl = BuildMod(c.comp->mod.get(), node, nullptr, diags_);
  if (c.is_final) {
    decl.is_final = true;
    decl.final_span = c.comp->span;
    if (decl.value) decl.value->is_final = true;
  }
  MergeBuiltMod(outer, std::move(decl), child.get(), diags_);
  child->is_final_decl = c.is_final;
  return child;
}

// The builtin type `name` names (Real, Integer, Boolean, String), in *out; false if none.
// Compared as views, lengths first (every component's type comes here: a std::string
// compared with a literal measured the literal and called memcmp each time).
static bool BuiltinTypeNamed(std::string_view name, VType* out) {
  using namespace std::string_view_literals;
  if (name == "Real"sv) *out = VType::Real;
  else if (name == "Integer"sv) *out = VType::Integer;
  else if (name == "Boolean"sv) *out = VType::Boolean;
  else if (name == "String"sv) *out = VType::String;
  else return false;
  return true;
}

namespace {

// A literal (1, -2.5, "m", true, {0, 0, 1}): its value is the same in every instance, and
// evaluating it reads no scope.
bool IsPlainLiteral(const ast::Expr* e) {
  if (!e) return false;
  switch (e->kind) {
    case ast::ExprKind::Number:
    case ast::ExprKind::String:
    case ast::ExprKind::Bool:
      return true;
    case ast::ExprKind::Unary:
      return e->args.size() == 1 && e->args[0] && e->args[0]->kind == ast::ExprKind::Number;
    case ast::ExprKind::Array:
      for (const auto& a : e->args)
        if (!a || (a->kind != ast::ExprKind::Number && !IsPlainLiteral(a.get()))) return false;
      return e->named_args.empty() && e->parts.empty();
    default:
      return false;
  }
}

// A builtin variable's declaration whose modifier is literals only: a value and attributes
// (`parameter Real mu(min = 0) = 0`), each named once, none final, each or redeclared.
bool LiteralDeclaration(const ast::Component& comp) {
  VType ignored;
  if (comp.type_name.size() != 1 || !BuiltinTypeNamed(comp.type_name[0], &ignored) || !comp.mod) return false;
  const ast::Modification& m = *comp.mod;
  if (m.value && !IsPlainLiteral(m.value.get())) return false;
  for (size_t i = 0; i < m.args.size(); ++i) {
    const ast::Argument& a = m.args[i];
    if (a.each || a.is_final || a.redeclare || a.path.size() != 1 || !a.mod || !a.mod->args.empty() ||
        a.mod->has_args || !IsPlainLiteral(a.mod->value.get()))
      return false;
    for (size_t j = 0; j < i; ++j)
      if (m.args[j].path[0] == a.path[0]) return false;  // modified twice: reported per instance
  }
  return true;
}

}  // namespace

// A variable declared with literals only and not modified from outside has the same
// modifier in every instance: built once per declaration and shared (a model of a hundred
// joints builds each joint parameter's a hundred times otherwise). Null: not such a one.
const Mod* Instantiator::DeclarationMod(Node* node, const ast::Component& comp) {
  auto [slot, fresh] = decl_mods_.try_emplace(&comp, nullptr);
  if (!fresh) return slot->second;
  if (!LiteralDeclaration(comp)) return nullptr;
  // Evaluating a literal reads no scope; the first instance's is kept for messages.
  slot->second = &tree_.decl_mods.emplace_back(BuildMod(comp.mod.get(), node, nullptr, diags_));
  return slot->second;
}

// The declaration in the model being elaborated that (transitively) holds `node`.
static Span TopDeclSpan(Node* node, const ast::Component& fallback) {
  Node* n = node;
  while (n && n->parent && n->parent->parent) n = n->parent;
  return n && n->decl ? n->decl->span : fallback.span;
}

// "A.B.C" -> {"A", "B", "C"}.
static std::vector<std::string> SplitDotted(const std::string& t) {
  std::vector<std::string> parts;
  size_t p = 0;
  while (true) {
    size_t q = t.find('.', p);
    parts.push_back(t.substr(p, q == std::string::npos ? std::string::npos : q - p));
    if (q == std::string::npos) break;
    p = q + 1;
  }
  return parts;
}

// One declared component: dropped by its condition, or a variable, a component or an array
// of components, by its type.
void Instantiator::Expand(Node* node, Node* child, const Collected& c) {
  const ast::Component& comp = *c.comp;
  if (comp.condition && !ComponentEnabled(node, child, comp)) return;
  // Dimensions: type dims then declaration dims (Real[3] x[2] is 2x3 in Modelica: the
  // declaration dims come first).
  Dims dims;
  AppendDims(comp.dims, node, &dims);
  AppendDims(comp.type_dims, node, &dims);
  ComponentType type;
  if (!ResolveComponentType(node, child, c, &type)) return;
  if (type.is_builtin) ExpandVariable(child, comp, type.builtin, dims);
  else ExpandComponent(node, child, c, type, dims);
}

bool Instantiator::ComponentEnabled(Node* node, Node* child, const ast::Component& comp) {
  double cv = 0;
  Value v = eval_.Eval(*comp.condition, Ctx{node, nullptr});
  if (v.valid && v.type != VType::Boolean) {
    diags_.Error(DiagCode::TypeMismatch, comp.condition->span, "a component condition must be Boolean");
  } else if (eval_.Structural(v, comp.condition->span, &cv, "a component condition")) {
    child->enabled = cv != 0;
  }
  return child->enabled;
}

void Instantiator::AppendDims(const std::vector<ast::ExprPtr>& ds, Node* node, Dims* dims) {
  const Ctx ctx{node, nullptr};
  for (const auto& d : ds) {
    if (d->kind == ast::ExprKind::Colon) {
      dims->push_back(-1);
      continue;
    }
    long n = 0;
    if (!eval_.LiteralStructuralInt(*d, &n) &&
        !eval_.StructuralInt(eval_.Eval(*d, ctx), d->span, &n, "an array size")) {
      dims->push_back(0);
      continue;
    }
    if (n < 0 || n > kMaxArraySize) {
      diags_.Error(DiagCode::ArrayTooLarge, d->span,
                   "array size " + std::to_string(n) + " is outside 0.." + std::to_string(kMaxArraySize));
      n = 0;
    }
    dims->push_back(static_cast<int>(n));
  }
}

bool Instantiator::ResolveComponentType(Node* node, Node* child, const Collected& c, ComponentType* t) {
  const ast::Component& comp = *c.comp;
  t->is_builtin = comp.type_name.size() == 1 && BuiltinTypeNamed(comp.type_name[0], &t->builtin);
  if (child->mod.Redeclared() && !ApplyRedeclare(child, c, t)) return false;
  if (!t->is_builtin && !t->cls) {
    t->cls = DeclaredClass(comp, c.owner);
    if (!t->cls) {
      ReportUnknownType(comp, *t);
      return false;
    }
  }
  if (t->cls && t->cls->kind == ast::ClassKind::Type) return ShortTypeToBuiltin(node, child, comp, t);
  return true;
}

bool Instantiator::ApplyRedeclare(Node* child, const Collected& c, ComponentType* t) {
  if (!c.replaceable) {
    auto& d = diags_.Error(DiagCode::NotReplaceable, child->mod.redeclare->span,
                           "'" + child->Path() + "' is not replaceable");
    d.notes.push_back({c.comp->span, "declared here without 'replaceable'"});
    return true;
  }
  const std::string& name = child->mod.redeclare->type;
  std::vector<std::string> parts = SplitDotted(name);
  VType ignored;
  if (parts.size() == 1 && BuiltinTypeNamed(name, &ignored)) {
    t->redeclared_name = name;
    return true;
  }
  const ast::ClassDef* from = child->mod.redeclare->from ? child->mod.redeclare->from : c.owner;
  t->cls = lookup_.FindClass(parts, from);
  if (!t->cls) {
    diags_.Error(DiagCode::UnknownClass, child->mod.redeclare->span, "unknown class '" + name + "'");
    return false;
  }
  t->is_builtin = false;
  return true;
}

const ast::ClassDef* Instantiator::DeclaredClass(const ast::Component& comp, const ast::ClassDef* owner) {
  // The same for every instance of the class declaring comp.
  auto found = component_type_.find(&comp);
  if (found != component_type_.end() && found->second.first == owner) return found->second.second;
  const ast::ClassDef* cls = lookup_.FindClass(comp.type_name, owner);
  if (cls) component_type_[&comp] = {owner, cls};
  return cls;
}

void Instantiator::ReportUnknownType(const ast::Component& comp, const ComponentType& t) {
  const std::string name = t.Name(comp);
  auto& d = diags_.Error(DiagCode::UnknownClass, comp.type_span, "unknown class '" + name + "'");
  std::vector<std::string> names{"Real", "Integer", "Boolean", "String"};
  for (const std::string& k : lookup_.AllNames())  // the hint considers every class
    names.push_back(k.rfind("Kanesim.", 0) == 0 ? k.substr(8) : k);
  std::string best = ClosestName(name, names);
  if (!best.empty()) d.hint = "did you mean '" + best + "'?";
}

// A `type` that is a short definition of a builtin (type Angle = Real(unit = "rad")): its
// modifiers join the component's.
bool Instantiator::ShortTypeToBuiltin(Node* node, Node* child, const ast::Component& comp, ComponentType* t) {
  Mod tm;
  const ast::ClassDef* cls = t->cls;
  int guard = 0;
  while (cls && cls->is_short && ++guard < kMaxExtendsDepth) {
    if (cls->short_mod)
      MergeMods(tm, BuildMod(cls->short_mod.get(), node, nullptr, diags_), child, diags_);
    if (BuiltinTypeNamed(ast::JoinName(cls->short_base), &t->builtin)) {
      t->is_builtin = true;
      break;
    }
    cls = lookup_.FindClass(cls->short_base, cls);
  }
  if (!t->is_builtin) {
    diags_.Error(DiagCode::UnknownClass, comp.type_span,
                 "type '" + t->Name(comp) + "' is not a Real/Integer/Boolean/String");
    return false;
  }
  MergeMods(child->mod, tm, child, diags_);
  t->cls = nullptr;
  return true;
}

void Instantiator::ExpandVariable(Node* child, const ast::Component& comp, VType builtin,
                                  const Dims& dims) {
  child->kind = Node::kVar;
  child->vtype = builtin;
  child->variability = comp.variability;
  child->causality = comp.causality;
  child->shape.assign(dims.begin(), dims.end());
  long size = 1;
  for (int d : dims) size *= (d < 0 ? 1 : d);
  tree_.instances += size;
  if (tree_.instances > kMaxInstances && !TooLarge()) {
    too_large_ = true;
    diags_.Error(DiagCode::InstanceTooLarge, TopDeclSpan(child, comp),
                 "the model has more than " + std::to_string(kMaxInstances) + " variables")
        .hint = "reduce the array sizes";
  }
  CheckVarAttributes(child, builtin);
}

void Instantiator::CheckVarAttributes(Node* var, VType builtin) {
  const ModView mods = var->Modifiers();
  // A shared modifier's attributes are those of every instance sharing it: one check when
  // they are all sound (a wrong one is reported in each instance, as before).
  const Mod* shared = var->shared_mod;
  if (shared && attributes_ok_.count(shared)) return;
  bool ok = true;
  for (const auto& key : mods.order) {
    const Mod& sub = mods.sub.find(key)->second;
    if (IsVarAttribute(key) || sub.set_only) continue;
    ok = false;
    auto& d = diags_.Error(DiagCode::UnknownModifier, sub.span,
                           "'" + key + "' is not an attribute of " + std::string(VTypeName(builtin)) + " variable '" +
                               var->Path() + "'");
    std::string best = ClosestName(key, {"start", "fixed", "unit", "min", "max", "displayUnit", "quantity", "nominal"});
    d.hint = best.empty() ? "attributes are start, fixed, unit, min, max, displayUnit, quantity, nominal"
                          : "did you mean '" + best + "'?";
  }
  if (shared && ok) attributes_ok_.insert(shared);
}

// A component of class type (or an array of them).
void Instantiator::ExpandComponent(Node* node, Node* child, const Collected& c, const ComponentType& t,
                                   const Dims& dims) {
  const ast::Component& comp = *c.comp;
  if (t.cls->kind == ast::ClassKind::Package || t.cls->kind == ast::ClassKind::Function) {
    diags_.Error(DiagCode::TypeMismatch, comp.type_span, "'" + t.Name(comp) + "' is a package or function, not a model");
    return;
  }
  if (dims.size() > 1) {
    diags_.Error(DiagCode::SizeMismatch, comp.span, "arrays of components have one dimension");
    return;
  }
  tree_.instances += dims.empty() ? 1 : dims[0];
  if (tree_.instances > kMaxInstances && !TooLarge()) {
    too_large_ = true;
    diags_.Error(DiagCode::InstanceTooLarge, TopDeclSpan(child, comp),
                 "the model has more than " + std::to_string(kMaxInstances) + " components")
        .hint = "reduce the array sizes";
    return;
  }
  if (dims.empty()) {
    child->kind = Node::kClass;
    InstantiateScalar(node, child, t.cls);
    return;
  }
  child->kind = Node::kArray;
  child->cls = t.cls;
  int n = dims[0] < 0 ? 0 : dims[0];
  PreEvaluateMod(child->mod, n, eval_, diags_);
  InstantiateArray(node, child, comp, t.cls, n);
}

}  // namespace kanesim::lang::elab
