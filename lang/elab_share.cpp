// Arrays of components of one class: one instance description shared by the elements.
//
// Element 1 is instantiated as any component is. When nothing in that instantiation
// depended on which element it was, elements 2..n are copies of element 1's instance tree
// bound to their own element: name and path, primitive ids (frames, flanges, joints, in
// the order instantiation would have given them), and the values of their slice of the
// array's modifier. Sharing is taken only when it is provably the same as instantiating:
//   - element 1's slice of the modifier holds no --set value (those are bound by name later);
//   - instantiating element 1 reported nothing;
//   - no variable inside element 1 was evaluated (so no size, condition or value inside the
//     element was computed from its parameters: they may differ per element);
//   - every value inside element 1 that carries a computed value is one of the element's
//     slice values, moved there unread, and each of those is found exactly once (so that
//     element k's slice can take its place);
//   - every modifier inside element 1 is evaluated in a scope outside the element or in an
//     ancestor of (or the very) node holding it (so that scopes map to element k's nodes).
// Otherwise every element is instantiated (tests/elab/array_share_test.cpp compares both).
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "lang/elab_instantiate.h"

#include "lang/elab_modifiers.h"

namespace kanesim::lang::elab {

namespace {

// A value of element 1's slice of the array's modifier: where it is, and its keys in the
// modifier (`axis`, or `body`, `m`).
struct SliceValue {
  const ModValue* at;
  std::vector<std::string> keys;
};

void FindSliceValues(const Mod& mod, std::vector<std::string>& keys, std::vector<SliceValue>* out, bool* from_set) {
  if (mod.set_only || (mod.value && mod.value->from_set)) *from_set = true;
  if (mod.value && mod.value->pre) out->push_back({&*mod.value, keys});
  for (const auto& [k, sm] : mod.sub) {
    keys.push_back(k);
    FindSliceValues(sm, keys, out, from_set);
    keys.pop_back();
  }
}

// Element `index` of the array's value at `keys` in the array's modifier (what SliceMod
// would give element `index` there); false when there is none.
bool SliceAt(const Mod& array_mod, const std::vector<std::string>& keys, int index, int count, Value* out) {
  const Mod* m = &array_mod;
  for (const auto& k : keys) {
    if (m->each) return false;
    auto it = m->sub.find(k);
    if (it == m->sub.end()) return false;
    m = &it->second;
  }
  if (m->each || !m->value || !m->value->pre) return false;
  const Value& v = *m->value->pre;
  if (!v.valid || v.shape.empty() || v.shape[0] != count) return false;
  *out = ElementOf(v, index, count);
  return true;
}

bool IsAncestorOrSelf(const Node* a, const Node* n) {
  for (; n; n = n->parent)
    if (n == a) return true;
  return false;
}

// The checks of the file's head on element 1's instance tree.
class ShareCheck {
 public:
  explicit ShareCheck(const std::vector<SliceValue>& slice) : slice_(slice), found_(slice.size(), 0) {}

  bool Run(const Node* root) {
    Gather(root);
    sorted_ = nodes_;
    std::sort(sorted_.begin(), sorted_.end());
    for (const Node* n : nodes_)
      if (!NodeOk(n) || !ModOk(n, n->mod)) return false;
    for (int f : found_)
      if (f != 1) return false;
    return true;
  }

 private:
  void Gather(const Node* n) {
    nodes_.push_back(n);
    for (const auto& c : n->children) Gather(c.get());
    for (const auto& e : n->elems) Gather(e.get());
  }
  bool Inside(const Node* n) const { return std::binary_search(sorted_.begin(), sorted_.end(), n); }
  bool NodeOk(const Node* n) const {
    return n->state == EvalState::Unevaluated && !n->eq_binding && n->eq_elem_binding.empty() && n->value.valid &&
           n->value.elements.empty();
  }
  bool ModOk(const Node* holder, const Mod& mod) {
    if (mod.value) {
      const ModValue& v = *mod.value;
      if (v.scope && Inside(v.scope) && !IsAncestorOrSelf(v.scope, holder)) return false;
      if (v.pre) {
        size_t i = 0;
        while (i < slice_.size() && slice_[i].at != &v) ++i;
        if (i == slice_.size()) return false;
        ++found_[i];
      }
    }
    for (const auto& [k, sm] : mod.sub)
      if (!ModOk(holder, sm)) return false;
    return true;
  }

  const std::vector<SliceValue>& slice_;
  std::vector<int> found_;
  std::vector<const Node*> nodes_;   // element 1's tree, in order
  std::vector<const Node*> sorted_;  // the same, sorted (for Inside)
};

// An expression that reads no name (literals and what is made of them): its value does
// not depend on the scope it is evaluated in. Iterative, as expressions can be deep.
bool ReadsNoName(const ast::Expr* e) {
  if (!e) return false;
  if (e->kind == ast::ExprKind::Number || e->kind == ast::ExprKind::String || e->kind == ast::ExprKind::Bool)
    return true;  // the common case, without a stack
  std::vector<const ast::Expr*> stack{e};
  while (!stack.empty()) {
    const ast::Expr* x = stack.back();
    stack.pop_back();
    if (x->kind == ast::ExprKind::Ref || x->kind == ast::ExprKind::Comprehension) return false;
    bool ok = true;
    ast::ForEachChild(*x, [&](const ast::ExprPtr& c) {
      if (c) stack.push_back(c.get());
      else ok = false;
    });
    if (!ok) return false;
  }
  return true;
}

}  // namespace

// Element 1's instance tree bound to element k: copies of the nodes with element k's names,
// scopes and slice values; `slice` and `values` are aligned (element k's value of each).
struct Instantiator::ShareBinding {
  const std::vector<SliceValue>* slice;
  std::vector<const Value*> values;
  std::vector<std::pair<const Node*, Node*>> ancestors;  // (element 1's node, element k's)
  // Per node of element 1's tree in the order CloneInstance visits them: whether its
  // modifiers are shared (SameInEveryElement: 1 yes, 0 no, -1 not yet known). The same
  // for every element, so found at the first copy and read at the others.
  std::vector<signed char>* same_mod;
  // Per node of element 1's tree, the same way: the id its class nodes' copies share
  // (Node::unit_slot), so that the unit check reads a binding once for all the copies.
  std::vector<int>* copy_ids;
  size_t visit = 0;
};

// Element k's copy of a modifier of element 1's tree: its value rebound to element k (the
// scope mapped to element k's node, a slice value replaced by element k's), its flags, and
// for a variable its sub-modifiers (attributes: start, unit, ...). Not copied, as read
// nowhere after instantiation: the order the keys were written in (for messages about
// them), and a class or array node's sub-modifiers (moved into its elements, or sliced
// for an array's elements).
Mod Instantiator::BoundCopy(const Mod& src, ShareBinding& b, bool with_sub) {
  Mod out;
  if (src.value) {
    out.value = *src.value;
    ModValue& v = *out.value;
    for (size_t i = b.ancestors.size(); i-- > 0;)
      if (b.ancestors[i].first == v.scope) {
        v.scope = b.ancestors[i].second;
        break;
      }
    for (size_t i = 0; i < b.slice->size(); ++i)
      if ((*b.slice)[i].at == &*src.value) v.pre = *b.values[i];
  }
  out.each = src.each;
  out.is_final = src.is_final;
  out.final_span = src.final_span;
  out.span = src.span;
  out.redeclare = src.redeclare;
  out.set_only = src.set_only;
  if (with_sub)
    for (const auto& [k, sm] : src.sub) out.sub.emplace_hint(out.sub.end(), k, BoundCopy(sm, b, true));
  return out;
}

// Whether a variable's modifiers in element 1 mean the same in element k: no slice value,
// and every value either reads no name or is evaluated outside element 1 (its scope is not
// one of the nodes being copied, which are the only ones BoundCopy would map).
bool Instantiator::SameInEveryElement(const Mod& m, const ShareBinding& b) const {
  if (m.value) {
    const ModValue& v = *m.value;
    if (v.pre) return false;
    if (!ReadsNoName(v.expr))
      for (const auto& a : b.ancestors)
        if (a.first == v.scope) return false;
  }
  for (const auto& [k, sm] : m.sub)
    if (!SameInEveryElement(sm, b)) return false;
  return true;
}

NodePtr Instantiator::CloneInstance(const Node& src, Node* parent, const std::string& name,
                                                  ShareBinding& b) {
  auto n = tree_.arena.New();
  n->kind = src.kind;
  n->name = name;
  n->parent = parent;
  n->decl = src.decl;
  n->enabled = src.enabled;
  n->depth = src.depth;
  n->cls = src.cls;
  n->equations = src.equations;
  n->prim = src.prim;
  n->prim_kind = src.prim_kind;
  n->vtype = src.vtype;
  n->variability = src.variability;
  n->causality = src.causality;
  n->shape = src.shape;
  n->is_final_decl = src.is_final_decl;
  b.ancestors.emplace_back(&src, n.get());
  if (src.kind != Node::kVar) {
    n->mod = BoundCopy(src.mod, b, false);
    if (src.kind == Node::kClass) {
      if (b.visit >= b.copy_ids->size()) b.copy_ids->resize(b.visit + 1, -1);
      int& id = (*b.copy_ids)[b.visit];
      if (id < 0) id = tree_.copies++;
      n->unit_slot = id;
    }
  } else if (src.mod_over_decl) {
    // Its declaration's attributes (literals) are every element's; its own value is element
    // 1's when that means the same in every element, else bound to element k. Shared, it
    // is checked on element 1 alone, as a shared whole modifier below.
    if (b.visit >= b.same_mod->size()) b.same_mod->resize(b.visit + 1, -1);
    signed char& same = (*b.same_mod)[b.visit];
    if (same < 0) same = !subscripted_sets_ && SameInEveryElement(src.mod, b);
    n->shared_mod = src.shared_mod;
    n->mod_over_decl = true;
    n->mod_from_decl = !same;
    n->mod = same ? src.mod : BoundCopy(src.mod, b, true);
  } else {
    // A variable's modifiers (its value and attributes) are shared with element 1 when they
    // mean the same there, copied and bound to element k otherwise. Not shared when a
    // subscripted --set may later change one element's (SetOverrides::Bind).
    const Mod& sm = src.shared_mod ? *src.shared_mod : src.mod;
    if (b.visit >= b.same_mod->size()) b.same_mod->resize(b.visit + 1, -1);
    signed char& same = (*b.same_mod)[b.visit];
    if (same < 0) same = !subscripted_sets_ && SameInEveryElement(sm, b);
    if (same) n->shared_mod = &sm;
    else n->mod = BoundCopy(sm, b, true);
  }
  ++b.visit;
  if (src.prim != Prim::None) RegisterPrimitive(n.get(), n->cls);
  n->children.reserve(src.children.size());
  for (const auto& c : src.children) n->children.push_back(CloneInstance(*c, n.get(), c->name, b));
  n->elems.reserve(src.elems.size());
  for (const auto& e : src.elems) n->elems.push_back(CloneInstance(*e, parent, e->name, b));
  b.ancestors.pop_back();
  return n;
}

// What element 1 of an array taught: whether elements 2..n may be copies of it.
struct Instantiator::ArrayShare {
  bool ok = false;
  const Node* first = nullptr;    // element 1
  long per_element = 0;           // tree_.instances counted by element 1
  std::vector<SliceValue> slice;  // its values from the array's modifier
  mutable std::vector<signed char> same_mod;  // ShareBinding::same_mod, filled by the first copy
  mutable std::vector<int> copy_ids;          // ShareBinding::copy_ids, the same way
};

// Element `index` as a copy of element 1 bound to its slice of the array's modifier; false
// (nothing done) when its slice lacks a value element 1 had, or the copy would pass the
// instance limit.
bool Instantiator::ShareElement(const ArrayShare& share, Node* node, Node* array, const std::string& name, int index,
                                int count) {
  if (!share.ok || tree_.instances + share.per_element > kMaxInstances) return false;
  std::vector<Value> values(share.slice.size());
  ShareBinding b{&share.slice, {}, {}, &share.same_mod, &share.copy_ids};
  for (size_t i = 0; i < share.slice.size(); ++i) {
    if (!SliceAt(array->mod, share.slice[i].keys, index, count, &values[i])) return false;
    b.values.push_back(&values[i]);
  }
  tree_.instances += share.per_element;
  array->elems.push_back(CloneInstance(*share.first, node, name, b));
  return true;
}

// Element 1: instantiated, and whether the others may share it (the checks at the top).
void Instantiator::InstantiateFirst(Node* el, const ast::ClassDef* tcls, ArrayShare* share) {
  std::vector<std::string> keys;
  bool from_set = false;
  FindSliceValues(el->mod, keys, &share->slice, &from_set);  // before Instantiate moves them
  const size_t diags_before = diags_.All().size();
  const long instances_before = tree_.instances;
  Instantiate(el, tcls);
  share->first = el;
  share->per_element = tree_.instances - instances_before;
  share->ok = !from_set && diags_.All().size() == diags_before && !diags_.HasErrors() &&
              ShareCheck(share->slice).Run(el);
}

void Instantiator::InstantiateArray(Node* node, Node* array, const ast::Component& comp, const ast::ClassDef* tcls,
                                    int n) {
  ArrayShare share;
  for (int i = 0; i < n && !diags_.Full() && !TooLarge(); ++i) {
    const std::string index = std::to_string(i + 1);
    std::string name;
    name.reserve(comp.name.size() + index.size() + 2);
    name.append(comp.name).append("[").append(index).append("]");
    if (i > 0 && ShareElement(share, node, array, name, i, n)) continue;
    auto el = tree_.arena.New();
    el->parent = node;  // elements resolve names in the same scope as the array
    el->decl = &comp;
    el->name = std::move(name);
    el->depth = array->depth;
    el->mod = SliceMod(array->mod, i, n, eval_, diags_);
    el->kind = Node::kClass;
    Node* raw = el.get();
    array->elems.push_back(std::move(el));
    if (i == 0 && n > 1) InstantiateFirst(raw, tcls, &share);
    else Instantiate(raw, tcls);
  }
}

}  // namespace kanesim::lang::elab
