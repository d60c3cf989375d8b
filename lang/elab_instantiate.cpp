// Instantiation: classes become a tree of instance nodes. Modifiers are merged with the
// outer one winning (Modelica 3.5 §7.2); `final` elements refuse outer modification;
// extends copies the base's elements and equations; arrays of components slice array
// modifiers unless `each` is given; conditional components are dropped when false.
#include <algorithm>
#include <cmath>
#include <functional>

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

bool IsVarAttribute(const std::string& n) {
  return n == "start" || n == "fixed" || n == "unit" || n == "min" || n == "max" || n == "displayUnit" ||
         n == "quantity" || n == "nominal" || n == "stateSelect";
}

flat::SourceLoc Elaborator::Loc(Span s) const {
  flat::SourceLoc l;
  const SourceManager& sm = program_.sources;
  if (!s.valid() || s.file >= sm.NumFiles()) return l;
  LineCol lc = sm.Locate(s.file, s.begin);
  l.file = sm.Name(s.file);
  l.line = lc.line;
  l.col = lc.col;
  return l;
}

Mod Elaborator::BuildMod(const ast::Modification* m, Node* scope, const std::shared_ptr<const Iters>& iters) {
  Mod out;
  if (!m) return out;
  out.span = m->span;
  if (m->value) {
    ModValue v;
    v.expr = m->value.get();
    v.scope = scope;
    v.iters = iters;
    v.span = m->value->span;
    out.value = v;
  }
  for (const auto& a : m->args) {
    // a.b.c = x  ==  a(b(c = x))
    Mod* target = &out;
    for (size_t i = 0; i < a.path.size(); ++i) {
      const std::string& key = a.path[i];
      if (!target->sub.count(key)) target->order.push_back(key);
      Mod& next = target->sub[key];
      if (i + 1 < a.path.size()) {
        if (!next.span.valid()) next.span = a.name_span;
        target = &next;
        continue;
      }
      Mod built = BuildMod(a.mod.get(), scope, iters);
      built.span = a.name_span;
      built.each = a.each;
      if (a.is_final) {
        built.is_final = true;
        built.final_span = a.span;
        if (built.value) built.value->is_final = true;
      }
      if (a.redeclare) {
        built.redeclare_type = a.redeclare_type;
        built.redeclare_from = scope && scope->cls ? scope->cls : nullptr;
        built.redeclare_span = a.span;
      }
      if (next.value || !next.sub.empty()) {
        auto& d = diags_.Error(DiagCode::Duplicate, a.name_span, "'" + ast::JoinName(a.path) + "' is modified twice");
        d.notes.push_back({next.span, "first modified here"});
      }
      next = std::move(built);
    }
  }
  return out;
}

// outer wins over inner; `what` names the element for messages.
void Elaborator::MergeInto(Mod& outer, const Mod& inner, const std::string& what) {
  std::vector<const std::string*> keys;
  MergeMods(outer, inner, what, keys);
}

// The recursion of MergeInto (as deep as the modifier is written). The name for messages
// is `what` followed by `keys`, built only when a message needs it.
void Elaborator::MergeMods(Mod& outer, const Mod& inner, const std::string& what,
                           std::vector<const std::string*>& keys) {
  auto name = [&] {
    std::string s = what;
    for (const std::string* k : keys) s += "." + *k;
    return s;
  };
  // --set on a final parameter is reported once by Elaborator::Run.
  if (outer.value && outer.value->from_set && inner.is_final) {
    outer.value.reset();
  }
  if (inner.is_final && (outer.value || !outer.sub.empty() || !outer.redeclare_type.empty())) {
    Span at = outer.value ? outer.value->span : outer.span;
    auto& d = diags_.Error(DiagCode::FinalOverride, at, "'" + name() + "' is final and cannot be modified");
    d.notes.push_back({inner.final_span.valid() ? inner.final_span : inner.span, "declared final here"});
    outer.value.reset();
    outer.sub.clear();
  }
  if (!outer.value && inner.value) outer.value = inner.value;
  else if (outer.value && inner.value && inner.value->is_final) {
    auto& d = diags_.Error(DiagCode::FinalOverride, outer.value->span, "'" + name() + "' is final and cannot be modified");
    d.notes.push_back({inner.value->span, "final value given here"});
    outer.value = inner.value;
  }
  if (inner.is_final) {
    outer.is_final = true;
    outer.final_span = inner.final_span;
  }
  if (outer.redeclare_type.empty() && !inner.redeclare_type.empty()) {
    outer.redeclare_type = inner.redeclare_type;
    outer.redeclare_from = inner.redeclare_from;
    outer.redeclare_span = inner.redeclare_span;
  }
  if (!outer.span.valid()) outer.span = inner.span;
  outer.each = outer.each || inner.each;
  if (!inner.empty() && !inner.set_only) outer.set_only = false;
  for (const auto& key : inner.order) {
    auto it = inner.sub.find(key);
    if (it == inner.sub.end()) continue;
    auto [slot, added] = outer.sub.try_emplace(key);
    if (added) outer.order.push_back(key);
    keys.push_back(&key);
    MergeMods(slot->second, it->second, what, keys);
    keys.pop_back();
  }
}

// Breadth-first over the class and its bases (each visited once, so cyclic extends
// cannot loop; the cycle itself is reported by Collect).
const ast::Modification* Elaborator::FindAnnotation(const ast::ClassDef* cls, const std::string& key) const {
  std::vector<const ast::ClassDef*> queue{cls};
  for (size_t i = 0; i < queue.size() && i < 256; ++i) {
    const ast::ClassDef* c = queue[i];
    if (c->annotation)
      for (const auto& a : c->annotation->args)
        if (a.path.size() == 1 && a.path[0] == key) return a.mod.get();
    auto push = [&](const ast::ClassDef* b) {
      if (b && std::find(queue.begin(), queue.end(), b) == queue.end()) queue.push_back(b);
    };
    for (const auto& el : c->elements)
      if (el.kind == ast::Element::kExtends) push(FindClass(el.extends->base, c));
    if (c->is_short) push(FindClass(c->short_base, c));
  }
  return nullptr;
}

const ast::ClassDef* Elaborator::ResolveShort(const ast::ClassDef* cls, Node* node, Mod* mod) {
  int guard = 0;
  while (cls && cls->is_short) {
    if (++guard > kMaxExtendsDepth) {
      diags_.Error(DiagCode::RecursiveExtends, cls->name_span, "short class definitions form a cycle");
      return nullptr;
    }
    const ast::ClassDef* base = FindClass(cls->short_base, cls);
    if (!base) {
      diags_.Error(DiagCode::UnknownClass, cls->span, "unknown class '" + ast::JoinName(cls->short_base) + "'");
      return nullptr;
    }
    if (cls->short_mod) MergeInto(*mod, BuildMod(cls->short_mod.get(), node, nullptr), node ? node->path : cls->name);
    cls = base;
  }
  return cls;
}

void Elaborator::Collect(const ast::ClassDef* cls, Node* node, const Mod* ext_mod, std::vector<Collected>& out,
                         std::vector<Node::EqSource>& eqs, int depth) {
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
      const ast::ClassDef* base = FindClass(ex.base, cls);
      if (!base) {
        auto& d = diags_.Error(DiagCode::UnknownClass, ex.span, "unknown base class '" + ast::JoinName(ex.base) + "'");
        std::vector<std::string> names;
        for (auto& [k, v] : classes_) names.push_back(k.rfind("Kanesim.", 0) == 0 ? k.substr(8) : k);
        std::string best = ClosestName(ast::JoinName(ex.base), names);
        if (!best.empty()) d.hint = "did you mean '" + best + "'?";
        continue;
      }
      Mod em = BuildMod(ex.mod.get(), node, nullptr);
      Mod effective;
      if (ext_mod) effective = *ext_mod;
      MergeInto(effective, em, ast::JoinName(ex.base));
      // Short class as a base: fold its modifiers in.
      base = ResolveShort(base, node, &effective);
      if (!base) continue;
      Collect(base, node, &effective, out, eqs, depth + 1);
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
    for (auto& prev : out) {
      if (prev.comp->name != comp.name) continue;
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
      break;
    }
    if (!replaced) {
      if (comp.redeclare)
        diags_.Error(DiagCode::NotReplaceable, comp.name_span,
                     "'redeclare " + comp.name + "' replaces nothing: no inherited element has that name");
      out.push_back(std::move(c));
    }
  }
  for (const auto& eq : cls->equations) eqs.push_back({&eq, cls});
  extends_stack_.pop_back();
}

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
  if (s == "shape") return Prim::Shape;
  return Prim::None;
}

void Elaborator::Instantiate(Node* node, const ast::ClassDef* cls, const ast::ClassDef* lookup_from) {
  (void)lookup_from;
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
  // Primitive? annotation(__kanesim(primitive = "joint", kind = "revolute"))
  if (const ast::Modification* pm = FindAnnotation(cls, "__kanesim")) {
    for (const auto& a : pm->args) {
      if (a.path.size() != 1 || !a.mod || !a.mod->value || a.mod->value->kind != ast::ExprKind::String) continue;
      if (a.path[0] == "primitive") node->prim = PrimFromName(a.mod->value->text);
      if (a.path[0] == "kind") node->prim_kind = a.mod->value->text;
    }
  }
  if (node->prim == Prim::Frame) {
    node->prim_index = static_cast<int>(frame_nodes_.size());
    frame_nodes_.push_back(node);
  } else if (node->prim == Prim::Flange) {
    node->prim_index = static_cast<int>(flange_nodes_.size());
    flange_nodes_.push_back(node);
  } else if (node->prim == Prim::Joint) {
    node->prim_index = static_cast<int>(joint_nodes_.size());
    joint_nodes_.push_back(node);
    flat::Joint j;
    j.name = node->path;
    if (!flat::JointTypeFromName(node->prim_kind, &j.type))
      diags_.Error(DiagCode::BadPrimitive, cls->name_span, "unknown joint kind '" + node->prim_kind + "'");
    j.loc = Loc(node->decl ? node->decl->name_span : cls->name_span);
    m_->joints.push_back(j);
  }

  std::vector<Collected> elems;
  Collect(cls, node, nullptr, elems, node->equations, 0);

  // Every outer modifier must name an element.
  for (const auto& key : node->mod.order) {
    bool found = false;
    for (const auto& c : elems) {
      if (c.comp->name != key) continue;
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
    if (sm.set_only) continue;  // --set names are checked by BindSetOverrides
    std::vector<std::string> names;
    for (const auto& c : elems) names.push_back(c.comp->name);
    auto& d = diags_.Error(DiagCode::UnknownModifier, sm.span,
                           "'" + cls->name + "' has no element '" + key + "'");
    std::string best = ClosestName(key, names);
    if (!best.empty()) d.hint = "did you mean '" + best + "'?";
    d.notes.push_back({cls->name_span, "'" + cls->name + "' is declared here"});
  }

  for (auto& c : elems) {
    auto child = std::make_unique<Node>();
    child->parent = node;
    child->decl = c.comp;
    child->name = c.comp->name;
    child->path = node->path.empty() ? c.comp->name : node->path + "." + c.comp->name;
    child->depth = node->depth + 1;
    Mod outer;
    auto it = node->mod.sub.find(c.comp->name);
    if (it != node->mod.sub.end()) outer = it->second;
    if (c.is_final && !outer.empty() && !(outer.value && outer.value->from_set)) {
      Span at = outer.value ? outer.value->span : outer.span;
      auto& d = diags_.Error(DiagCode::FinalOverride, at, "'" + child->path + "' is final and cannot be modified");
      d.notes.push_back({c.comp->span, "declared final here"});
      outer = Mod{};
    }
    MergeInto(outer, c.ext_mod, child->path);
    Mod decl = BuildMod(c.comp->mod.get(), node, nullptr);
    if (c.is_final) {
      decl.is_final = true;
      decl.final_span = c.comp->span;
      if (decl.value) decl.value->is_final = true;
    }
    MergeInto(outer, decl, child->path);
    child->mod = std::move(outer);
    child->is_final_decl = c.is_final;
    node->children.push_back(std::move(child));
  }
  for (size_t i = 0; i < elems.size() && i < node->children.size(); ++i) {
    if (diags_.Full() || too_large_) break;
    Expand(node, node->children[i].get(), elems[i]);
  }
}

// Evaluates the non-`each` values of an array component's modifier once, checking their
// leading size, so that slicing per element neither re-evaluates nor repeats errors.
static void PreEvaluate(Elaborator& el, Mod& mod, int count, Diagnostics& diags) {
  if (mod.each) return;
  if (mod.value && !mod.value->pre) {
    Value v = el.EvalModValue(*mod.value, nullptr);
    if (!v.valid) {
      mod.value.reset();
    } else if (v.shape.empty() || v.shape[0] != count) {
      auto& d = diags.Error(DiagCode::SizeMismatch, mod.value->span,
                            "modifier of an array of " + std::to_string(count) + " components needs " +
                                std::to_string(count) + " values");
      d.hint = mod.value->from_set ? "set one element (--set name[k].x=...), or give " + std::to_string(count) + " values"
                                   : "write 'each' before the name to give every element the same value";
      mod.value.reset();
    } else {
      mod.value->pre = v;
    }
  }
  for (auto& [k, sm] : mod.sub) PreEvaluate(el, sm, count, diags);
}

// Element `index` of an array component's modifier. Copies everything but the values,
// and of a value only the slice: copying the whole array value for every element would
// cost O(count^2) time and memory.
Mod Elaborator::SliceMod(const Mod& mod, int index, int count, Span where) {
  if (mod.each) return mod;  // `each` applies the whole modifier to every element
  Mod out;
  out.order = mod.order;
  out.each = mod.each;
  out.is_final = mod.is_final;
  out.final_span = mod.final_span;
  out.span = mod.span;
  out.redeclare_type = mod.redeclare_type;
  out.redeclare_from = mod.redeclare_from;
  out.redeclare_span = mod.redeclare_span;
  out.set_only = mod.set_only;
  if (mod.value) {
    std::optional<Value> evaluated;
    if (!mod.value->pre) evaluated = EvalModValue(*mod.value, nullptr);
    const Value& v = mod.value->pre ? *mod.value->pre : *evaluated;
    if (v.valid && (v.shape.empty() || v.shape[0] != count)) {
      auto& d = diags_.Error(DiagCode::SizeMismatch, mod.value->span,
                             "modifier of an array of " + std::to_string(count) + " components needs " +
                                 std::to_string(count) + " values");
      d.hint = "write 'each' before the name to give every element the same value";
    } else if (v.valid) {
      ModValue mv;
      mv.expr = mod.value->expr;
      mv.scope = mod.value->scope;
      mv.iters = mod.value->iters;
      mv.span = mod.value->span;
      mv.is_final = mod.value->is_final;
      mv.from_set = mod.value->from_set;
      Value s;
      s.type = v.type;
      s.shape.assign(v.shape.begin() + 1, v.shape.end());
      size_t stride = v.Size() / static_cast<size_t>(count);
      for (size_t k = 0; k < stride; ++k) {
        s.e.push_back(v.e[static_cast<size_t>(index) * stride + k]);
        if (v.type == VType::String) s.s.push_back(v.s[static_cast<size_t>(index) * stride + k]);
      }
      mv.pre = std::move(s);
      out.value = std::move(mv);
    }
  }
  for (const auto& [k, sm] : mod.sub) out.sub[k] = SliceMod(sm, index, count, where);
  return out;
}

// The declaration in the model being elaborated that (transitively) holds `node`.
static Span TopDeclSpan(Node* node, const ast::Component& fallback) {
  Node* n = node;
  while (n && n->parent && n->parent->parent) n = n->parent;
  return n && n->decl ? n->decl->span : fallback.span;
}

void Elaborator::Expand(Node* node, Node* child, const Collected& c) {
  const ast::Component& comp = *c.comp;
  Ctx ctx{node, nullptr};
  if (comp.condition) {
    double cv = 0;
    Value v = Eval(*comp.condition, ctx);
    if (v.valid && v.type != VType::Boolean) {
      diags_.Error(DiagCode::TypeMismatch, comp.condition->span, "a component condition must be Boolean");
    } else if (Structural(v, comp.condition->span, &cv, "a component condition")) {
      child->enabled = cv != 0;
    }
    if (!child->enabled) return;
  }
  // Dimensions: type dims then declaration dims (Real[3] x[2] is 2x3 in Modelica: the
  // declaration dims come first).
  std::vector<int> dims;
  auto add_dims = [&](const std::vector<ast::ExprPtr>& ds) {
    for (const auto& d : ds) {
      if (d->kind == ast::ExprKind::Colon) {
        dims.push_back(-1);
        continue;
      }
      long n = 0;
      if (!StructuralInt(Eval(*d, ctx), d->span, &n, "an array size")) {
        dims.push_back(0);
        continue;
      }
      if (n < 0 || n > kMaxArraySize) {
        diags_.Error(DiagCode::ArrayTooLarge, d->span,
                     "array size " + std::to_string(n) + " is outside 0.." + std::to_string(kMaxArraySize));
        n = 0;
      }
      dims.push_back(static_cast<int>(n));
    }
  };
  add_dims(comp.dims);
  add_dims(comp.type_dims);

  std::string tname = ast::JoinName(comp.type_name);
  const ast::ClassDef* tcls = nullptr;
  VType builtin = VType::Real;
  bool is_builtin = true;
  if (tname == "Real") builtin = VType::Real;
  else if (tname == "Integer") builtin = VType::Integer;
  else if (tname == "Boolean") builtin = VType::Boolean;
  else if (tname == "String") builtin = VType::String;
  else is_builtin = false;

  if (!child->mod.redeclare_type.empty()) {
    if (!c.replaceable) {
      auto& d = diags_.Error(DiagCode::NotReplaceable, child->mod.redeclare_span,
                             "'" + child->path + "' is not replaceable");
      d.notes.push_back({comp.span, "declared here without 'replaceable'"});
    } else {
      std::vector<std::string> parts;
      std::string t = child->mod.redeclare_type;
      size_t p = 0;
      while (true) {
        size_t q = t.find('.', p);
        parts.push_back(t.substr(p, q == std::string::npos ? std::string::npos : q - p));
        if (q == std::string::npos) break;
        p = q + 1;
      }
      const ast::ClassDef* from = child->mod.redeclare_from ? child->mod.redeclare_from : c.owner;
      if (parts.size() == 1 && (t == "Real" || t == "Integer" || t == "Boolean" || t == "String")) {
        tname = t;
      } else {
        tcls = FindClass(parts, from);
        if (!tcls) {
          diags_.Error(DiagCode::UnknownClass, child->mod.redeclare_span, "unknown class '" + t + "'");
          return;
        }
        is_builtin = false;
      }
    }
  }
  if (!is_builtin && !tcls) {
    tcls = FindClass(comp.type_name, c.owner);
    if (!tcls) {
      auto& d = diags_.Error(DiagCode::UnknownClass, comp.type_span, "unknown class '" + tname + "'");
      std::vector<std::string> names{"Real", "Integer", "Boolean", "String"};
      for (auto& [k, v] : classes_) names.push_back(k.rfind("Kanesim.", 0) == 0 ? k.substr(8) : k);
      std::string best = ClosestName(tname, names);
      if (!best.empty()) d.hint = "did you mean '" + best + "'?";
      return;
    }
  }
  // A `type` that is a short definition of a builtin (type Angle = Real(unit = "rad")).
  if (tcls && tcls->kind == ast::ClassKind::Type) {
    Mod tm;
    const ast::ClassDef* t = tcls;
    int guard = 0;
    while (t && t->is_short && ++guard < kMaxExtendsDepth) {
      if (t->short_mod) MergeInto(tm, BuildMod(t->short_mod.get(), node, nullptr), child->path);
      std::string b = ast::JoinName(t->short_base);
      if (b == "Real" || b == "Integer" || b == "Boolean" || b == "String") {
        builtin = b == "Real" ? VType::Real : b == "Integer" ? VType::Integer : b == "Boolean" ? VType::Boolean
                                                                                             : VType::String;
        is_builtin = true;
        break;
      }
      t = FindClass(t->short_base, t);
    }
    if (!is_builtin) {
      diags_.Error(DiagCode::UnknownClass, comp.type_span, "type '" + tname + "' is not a Real/Integer/Boolean/String");
      return;
    }
    MergeInto(child->mod, tm, child->path);
    tcls = nullptr;
  }

  if (is_builtin) {
    child->kind = Node::kVar;
    child->vtype = builtin;
    child->variability = comp.variability;
    child->causality = comp.causality;
    child->shape = dims;
    long size = 1;
    for (int d : dims) size *= (d < 0 ? 1 : d);
    instances_ += size;
    if (instances_ > kMaxInstances && !too_large_) {
      too_large_ = true;
      diags_.Error(DiagCode::InstanceTooLarge, TopDeclSpan(child, comp),
                   "the model has more than " + std::to_string(kMaxInstances) + " variables")
          .hint = "reduce the array sizes";
    }
    for (const auto& key : child->mod.order) {
      if (IsVarAttribute(key) || child->mod.sub[key].set_only) continue;
      auto& d = diags_.Error(DiagCode::UnknownModifier, child->mod.sub[key].span,
                             "'" + key + "' is not an attribute of " + std::string(VTypeName(builtin)) + " variable '" +
                                 child->path + "'");
      std::string best =
          ClosestName(key, {"start", "fixed", "unit", "min", "max", "displayUnit", "quantity", "nominal"});
      d.hint = best.empty() ? "attributes are start, fixed, unit, min, max, displayUnit, quantity, nominal"
                            : "did you mean '" + best + "'?";
    }
    return;
  }
  // A component of class type (or an array of them).
  if (tcls->kind == ast::ClassKind::Package || tcls->kind == ast::ClassKind::Function) {
    diags_.Error(DiagCode::TypeMismatch, comp.type_span, "'" + tname + "' is a package or function, not a model");
    return;
  }
  if (dims.size() > 1) {
    diags_.Error(DiagCode::SizeMismatch, comp.span, "arrays of components have one dimension");
    return;
  }
  instances_ += dims.empty() ? 1 : dims[0];
  if (instances_ > kMaxInstances && !too_large_) {
    too_large_ = true;
    diags_.Error(DiagCode::InstanceTooLarge, TopDeclSpan(child, comp),
                 "the model has more than " + std::to_string(kMaxInstances) + " components")
        .hint = "reduce the array sizes";
    return;
  }
  if (dims.empty()) {
    child->kind = Node::kClass;
    Instantiate(child, tcls, c.owner);
    return;
  }
  child->kind = Node::kArray;
  child->cls = tcls;
  int n = dims[0] < 0 ? 0 : dims[0];
  PreEvaluate(*this, child->mod, n, diags_);
  for (int i = 0; i < n && !diags_.Full() && !too_large_; ++i) {
    auto el = std::make_unique<Node>();
    el->parent = node;  // elements resolve names in the same scope as the array
    el->decl = &comp;
    el->name = comp.name + "[" + std::to_string(i + 1) + "]";
    el->path = (node->path.empty() ? "" : node->path + ".") + el->name;
    el->depth = child->depth;
    el->mod = SliceMod(child->mod, i, n, comp.span);
    el->kind = Node::kClass;
    Node* raw = el.get();
    child->elems.push_back(std::move(el));
    Instantiate(raw, tcls, c.owner);
  }
}

// ---------------------------------------------------------------------------------------

Value Elaborator::EvalModValue(const ModValue& mv, Span* where) {
  if (where) *where = mv.span;
  if (mv.pre) return *mv.pre;
  if (!mv.expr) return Value::Invalid();
  Ctx ctx{mv.scope, mv.iters.get()};
  return Eval(*mv.expr, ctx);
}

Value Elaborator::GetVar(Node* var, Span use_span) {
  if (var->state == 2) return var->value;
  if (var->state == 1) {
    auto& d = diags_.Error(DiagCode::Circular, use_span, "'" + var->path + "' is defined in terms of itself");
    if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
    var->state = 2;
    var->value = Value::Invalid();
    return var->value;
  }
  var->state = 1;
  auto finish = [&](Value v) {
    var->value = std::move(v);
    var->state = 2;
    return var->value;
  };
  Node* owner = var->parent;
  bool is_param = var->variability != ast::Variability::None;
  size_t count = 1;
  for (int d : var->shape) count *= static_cast<size_t>(d < 0 ? 0 : d);

  // Joint coordinates and speeds are the mechanism's state.
  if (owner && owner->prim == Prim::Joint && !is_param && (var->name == "q" || var->name == "u")) {
    Value v;
    v.shape = var->shape;
    for (size_t k = 0; k < count; ++k)
      v.e.push_back(m_->exprs.State(m_->AddStateRef(
          {var->name == "q" ? flat::StateKind::JointQ : flat::StateKind::JointU, owner->prim_index,
           static_cast<int>(k)})));
    return finish(v);
  }

  const ModValue* binding = nullptr;
  if (var->eq_binding) binding = &*var->eq_binding;
  if (var->mod.value) {
    if (binding) {
      auto& d = diags_.Error(DiagCode::ConflictingEquation, var->eq_binding->span,
                             "'" + var->path + "' already has a value from its declaration or a modifier");
      d.notes.push_back({var->mod.value->span, "value given here"});
    }
    binding = &*var->mod.value;
  }
  Value v;
  if (!binding) {
    bool any_elem = !var->eq_elem_binding.empty();
    if (any_elem && !(owner && owner->prim != Prim::None) && var->eq_elem_binding.size() != count) {
      for (size_t k = 0; k < count; ++k) {
        if (var->eq_elem_binding.count(static_cast<int>(k))) continue;
        auto& d = diags_.Error(DiagCode::MissingValue, var->decl ? var->decl->name_span : use_span,
                               "element " + std::to_string(k + 1) + " of '" + var->path + "' has no equation");
        d.hint = "give every element an equation, or bind the whole variable";
        break;
      }
      return finish(Value::Invalid());
    }
    if ((owner && owner->prim != Prim::None && !is_param) || any_elem) {
      v.type = var->vtype;
      v.shape = var->shape;
      v.e.assign(count, m_->exprs.Constant(0));
    } else {
      auto& d = diags_.Error(DiagCode::MissingValue, var->decl ? var->decl->name_span : use_span,
                             std::string(is_param ? "parameter" : "variable") + " '" + var->path + "' has no value");
      d.hint = is_param ? "give it a binding (parameter Real x = 1;), a modifier, or --set " + var->path + "=..."
                        : "bind it in its declaration (Real x = ...;) or with an equation 'x = ...;'";
      if (use_span.valid() && var->decl && use_span.begin != var->decl->name_span.begin)
        d.notes.push_back({use_span, "used here"});
      return finish(Value::Invalid());
    }
  } else {
    Span where;
    v = EvalModValue(*binding, &where);
    if (!v.valid) return finish(v);
    DiagCode tcode = binding->from_set ? DiagCode::BadSet : DiagCode::TypeMismatch;
    bool ok = true;
    if (var->vtype == VType::String || v.type == VType::String) ok = var->vtype == v.type;
    else if (var->vtype == VType::Boolean || v.type == VType::Boolean) ok = var->vtype == v.type;
    else if (var->vtype == VType::Integer && v.type == VType::Real) {
      // Accept Real values that are whole numbers only from literal folding.
      ok = false;
    }
    if (!ok) {
      auto& d = diags_.Error(tcode, where,
                             "'" + var->path + "' is " + VTypeName(var->vtype) + " but its value is " + VTypeName(v.type));
      if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
      if (var->vtype == VType::Integer) d.hint = "use a whole number, or integer(...)";
      return finish(Value::Invalid());
    }
    if (v.type == VType::Integer && var->vtype == VType::Real) v.type = VType::Real;
    // Shape: ':' dims adopt the value's size.
    bool shape_ok = v.shape.size() == var->shape.size();
    for (size_t i = 0; shape_ok && i < v.shape.size(); ++i) {
      if (var->shape[i] < 0) var->shape[i] = v.shape[i];
      shape_ok = var->shape[i] == v.shape[i];
    }
    if (!shape_ok && var->shape.size() > 0 && v.shape.empty() && binding->from_set == false && false) {
    }
    if (!shape_ok) {
      auto& d = diags_.Error(binding->from_set ? DiagCode::BadSet : DiagCode::SizeMismatch, where,
                             "'" + var->path + "' has size " + [&] {
                               std::string s = "[";
                               for (size_t i = 0; i < var->shape.size(); ++i)
                                 s += (i ? ", " : "") + std::to_string(var->shape[i]);
                               return var->shape.empty() ? std::string("scalar") : s + "]";
                             }() + " but its value has size " + [&] {
                               std::string s = "[";
                               for (size_t i = 0; i < v.shape.size(); ++i) s += (i ? ", " : "") + std::to_string(v.shape[i]);
                               return v.shape.empty() ? std::string("scalar") : s + "]";
                             }());
      if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
      return finish(Value::Invalid());
    }
    count = v.e.size();
  }
  // Element equations (x[2] = ...).
  for (const auto& [k, mv] : var->eq_elem_binding) {
    if (k < 0 || static_cast<size_t>(k) >= v.e.size()) continue;
    Value ev = EvalModValue(mv, nullptr);
    if (!ev.valid) continue;
    if (!ev.shape.empty()) {
      diags_.Error(DiagCode::SizeMismatch, mv.span, "an element equation needs a scalar value");
      continue;
    }
    v.e[static_cast<size_t>(k)] = ev.e[0];
  }
  if (!is_param) return finish(v);

  // Parameters and constants: no time, no state.
  for (ExprId x : v.e) {
    if (x >= 0 && m_->exprs.DependsOnTimeOrState(x)) {
      auto& d = diags_.Error(DiagCode::NotConstantExpr, binding ? binding->span : use_span,
                             "the value of parameter '" + var->path + "' depends on time or on the motion");
      d.hint = "parameters are fixed before the simulation; use a variable (Real x = ...) instead";
      return finish(Value::Invalid());
    }
  }
  // Attributes for flat parameters.
  std::string unit;
  double vmin = -1e300, vmax = 1e300;
  auto attr_num = [&](const char* key, double* out) {
    auto it = var->mod.sub.find(key);
    if (it == var->mod.sub.end() || !it->second.value) return;
    Value a = EvalModValue(*it->second.value, nullptr);
    if (a.valid && a.shape.empty() && a.type != VType::String)
      Structural(a, it->second.value->span, out, key);
  };
  attr_num("min", &vmin);
  attr_num("max", &vmax);
  if (auto it = var->mod.sub.find("unit"); it != var->mod.sub.end() && it->second.value) {
    Value a = EvalModValue(*it->second.value, nullptr);
    if (a.valid && a.type == VType::String && !a.s.empty()) unit = a.s[0];
  }
  Value out = v;
  const flat::SourceLoc loc = Loc(var->decl ? var->decl->name_span : use_span);
  for (size_t k = 0; k < v.e.size(); ++k) {
    std::string name = var->path;
    if (!var->shape.empty()) {
      // Row-major multi-index, 1-based.
      std::vector<int> idx(var->shape.size());
      size_t rem = k;
      for (size_t d = var->shape.size(); d-- > 0;) {
        idx[d] = static_cast<int>(rem % static_cast<size_t>(var->shape[d])) + 1;
        rem /= static_cast<size_t>(var->shape[d]);
      }
      name += "[";
      for (size_t d = 0; d < idx.size(); ++d) name += (d ? "," : "") + std::to_string(idx[d]);
      name += "]";
    }
    flat::Param p;
    p.name = std::move(name);
    p.type = var->vtype == VType::Real      ? flat::ParamType::Real
             : var->vtype == VType::Integer ? flat::ParamType::Integer
             : var->vtype == VType::Boolean ? flat::ParamType::Boolean
                                            : flat::ParamType::String;
    p.unit = unit;
    p.min = vmin;
    p.max = vmax;
    p.is_constant = var->variability == ast::Variability::Constant;
    p.user_set = binding && binding->from_set;
    p.loc = loc;
    if (var->vtype == VType::String) {
      p.string_value = v.s.empty() ? "" : v.s[k];
      m_->params.push_back(std::move(p));
      pvals_.push_back(0.0);
      continue;
    }
    ExprId x = v.e[k];
    double val = param_eval_.Eval(x);
    p.value = val;
    p.binding = m_->exprs.IsConstant(x) ? flat::kNoExpr : x;
    if (!std::isfinite(val)) {
      auto& d = diags_.Error(DiagCode::BadValue, binding ? binding->span : use_span,
                             "parameter '" + p.name + "' evaluates to " + std::to_string(val));
      if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
    } else if (val < vmin || val > vmax) {
      auto& d = diags_.Error(DiagCode::BadValue, binding ? binding->span : use_span,
                             "parameter '" + p.name + "' = " + std::to_string(val) + " is outside its range [" +
                                 (vmin <= -1e299 ? std::string("-inf") : std::to_string(vmin)) + ", " +
                                 (vmax >= 1e299 ? std::string("inf") : std::to_string(vmax)) + "]");
      if (var->decl) d.notes.push_back({var->decl->name_span, "declared here"});
    }
    if (p.is_constant) {
      out.e[k] = m_->exprs.Constant(val);
      continue;
    }
    m_->params.push_back(std::move(p));
    pvals_.push_back(val);
    out.e[k] = m_->exprs.Parameter(static_cast<int>(m_->params.size() - 1));
  }
  return finish(out);
}

// ---------------------------------------------------------------------------------------

Node* Elaborator::ResolveNode(const ast::Expr& ref, const Ctx& ctx, int* elem) {
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
                             "'" + n->path + "' is an array of components; index it before '." + part.name + "'");
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
                                     : "'" + n->path + "' has no member '" + part.name + "'");
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
                           " of '" + n->path + "'");
          return nullptr;
        }
        n = n->elems[static_cast<size_t>(k - 1)].get();
      } else if (n->kind == Node::kVar && pi + 1 == ref.parts.size()) {
        size_t flatk = 0, stride = 1;
        if (part.subscripts.size() != n->shape.size()) {
          diags_.Error(DiagCode::IndexOutOfRange, part.span, "'" + n->path + "' needs " +
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
        diags_.Error(DiagCode::TypeMismatch, part.span, "'" + n->path + "' is not an array");
        return nullptr;
      }
    }
  }
  return n;
}

void Elaborator::ProcessEquations(Node* node) {
  if (!node->enabled) return;
  if (node->kind == Node::kArray) {
    for (auto& e : node->elems) ProcessEquations(e.get());
    return;
  }
  if (node->kind != Node::kClass) return;
  std::function<void(const ast::Equation&, const std::shared_ptr<const Iters>&)> one;
  one = [&](const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
    if (diags_.Full()) return;
    Ctx ctx{node, iters.get()};
    switch (eq.kind) {
      case ast::EqKind::Connect: {
        Node* a = ResolveNode(*eq.lhs, ctx, nullptr);
        Node* b = ResolveNode(*eq.rhs, ctx, nullptr);
        if (!a || !b) return;
        if (!a->enabled || !b->enabled) return;  // a conditional component that is absent
        auto is_conn = [](Node* n) { return n->kind == Node::kClass && (n->prim == Prim::Frame || n->prim == Prim::Flange); };
        if (a->kind == Node::kArray && b->kind == Node::kArray && a->elems.size() == b->elems.size()) {
          for (size_t i = 0; i < a->elems.size(); ++i) {
            Node* x = a->elems[i].get();
            Node* y = b->elems[i].get();
            if (is_conn(x) && is_conn(y) && x->prim == y->prim)
              (x->prim == Prim::Frame ? frame_links_ : flange_links_).push_back({x->prim_index, y->prim_index});
          }
          return;
        }
        if (!is_conn(a) || !is_conn(b) || a->prim != b->prim) {
          Node* badn = !is_conn(a) ? a : b;
          auto& d = diags_.Error(DiagCode::BadConnect, (badn == a ? eq.lhs : eq.rhs)->span,
                                 !is_conn(a) || !is_conn(b)
                                     ? "'" + badn->path + "' is not a connector"
                                     : "cannot connect a Frame to a Flange");
          d.hint = "connect frames (frame_a, frame_b of bodies and joints) or flanges (drive, support)";
          return;
        }
        (a->prim == Prim::Frame ? frame_links_ : flange_links_).push_back({a->prim_index, b->prim_index});
        return;
      }
      case ast::EqKind::For: {
        Value r = Eval(*eq.range, ctx);
        if (!r.valid) return;
        if (r.Size() > static_cast<size_t>(kMaxArraySize)) {
          diags_.Error(DiagCode::ArrayTooLarge, eq.range->span, "for-loop range too large");
          return;
        }
        std::vector<double> xs = StructuralList(r, eq.range->span, "a for-loop range");
        for (double x : xs) {
          if (!ChargeSteps(1, eq.range->span)) return;
          auto local = std::make_shared<Iters>(iters ? *iters : Iters{});
          (*local)[eq.iter] = x;
          for (const auto& b : eq.body) one(b, local);
        }
        return;
      }
      case ast::EqKind::If: {
        for (size_t i = 0; i < eq.branches.size(); ++i) {
          if (i < eq.conditions.size()) {
            double cv = 0;
            Value c = Eval(*eq.conditions[i], ctx);
            if (!c.valid) return;
            if (c.type != VType::Boolean) {
              diags_.Error(DiagCode::TypeMismatch, eq.conditions[i]->span, "an if-equation condition must be Boolean");
              return;
            }
            if (!Structural(c, eq.conditions[i]->span, &cv, "an if-equation condition")) return;
            if (cv == 0) continue;
          }
          for (const auto& b : eq.branches[i]) one(b, iters);
          return;
        }
        return;
      }
      case ast::EqKind::Equality: {
        if (eq.lhs->kind != ast::ExprKind::Ref) {
          diags_.Error(DiagCode::BadEquation, eq.lhs->span,
                       "equations must have the form 'variable = expression'")
              .hint = "write the variable being defined on the left, e.g. 'j.tau = -k * j.q;'";
          return;
        }
        int elem = -1;
        Node* v = ResolveNode(*eq.lhs, ctx, &elem);
        if (!v || !v->enabled) return;
        if (v->kind != Node::kVar) {
          diags_.Error(DiagCode::BadEquation, eq.lhs->span, "'" + v->path + "' is a component, not a variable");
          return;
        }
        if (v->variability != ast::Variability::None) {
          auto& d = diags_.Error(DiagCode::BadEquation, eq.lhs->span,
                                 "'" + v->path + "' is a parameter; equations define variables");
          d.hint = "give parameters values in their declaration, with a modifier, or with --set";
          return;
        }
        ModValue mv;
        mv.expr = eq.rhs.get();
        mv.scope = node;
        mv.iters = iters;
        mv.span = eq.span;
        if (elem >= 0) {
          auto it = v->eq_elem_binding.find(elem);
          if (it != v->eq_elem_binding.end()) {
            auto& d = diags_.Error(DiagCode::ConflictingEquation, eq.span,
                                   "element " + std::to_string(elem + 1) + " of '" + v->path + "' has two equations");
            d.notes.push_back({it->second.span, "first equation here"});
            return;
          }
          v->eq_elem_binding[elem] = mv;
          return;
        }
        if (v->eq_binding) {
          auto& d = diags_.Error(DiagCode::ConflictingEquation, eq.span, "'" + v->path + "' has two equations");
          d.notes.push_back({v->eq_binding->span, "first equation here"});
          return;
        }
        v->eq_binding = mv;
        return;
      }
    }
  };
  for (const auto& src : node->equations) one(*src.eq, nullptr);
  for (auto& c : node->children) ProcessEquations(c.get());
}

}  // namespace kanesim::lang::elab
