// Components of one class: one instance description shared by several of them.
//
// Arrays. Element 1 is instantiated as any component is. When nothing in that instantiation
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
//
// Siblings. Scalar components of one class declared in one class instance (a robot's
// joints, links and fixed frames) are mostly the same tree with other values. The first
// of a modifier form (the same keys at every level, values in the same places, the same
// `each` and `final`) is instantiated; a later sibling of that form is a copy of its tree
// holding the sibling's own values (moved, with their scopes: they are evaluated where
// they were written, outside the copy), under the same conditions as an array's element 1,
// with "its own values" for "its slice", plus: no --set or redeclare anywhere in the
// modifier, no subscripted --set in the model, and no variable of the first read since it
// was instantiated (checked at each copy). Otherwise instantiated
// (tests/elab/sibling_share_test.cpp compares both).
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

// Nothing of a node was computed, bound by an equation or evaluated.
bool Untouched(const Node* n) {
  return n->state == EvalState::Unevaluated && !n->eq_binding && n->eq_elem_binding.empty() && n->value.valid &&
         n->value.elements.empty();
}

// Whether no node of the tree at `n` was evaluated (iterative: trees are deep).
bool Unread(const Node& root) {
  std::vector<const Node*> stack{&root};
  while (!stack.empty()) {
    const Node* n = stack.back();
    stack.pop_back();
    if (!Untouched(n)) return false;
    for (const auto& c : n->children) stack.push_back(c.get());
    for (const auto& e : n->elems) stack.push_back(e.get());
  }
  return true;
}

// The checks of the file's head on the first's instance tree: `places` are its own values
// (an array element's slice, a sibling's modifier values); a computed value (`pre`) must
// be one of them for an array's element (a sibling's copies keep the others: computed
// outside the first, as the scope check and Untouched make sure).
class ShareCheck {
 public:
  ShareCheck(const std::vector<const ModValue*>& places, bool pre_is_place)
      : places_(places), found_(places.size(), 0), pre_is_place_(pre_is_place) {}

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
  static bool NodeOk(const Node* n) { return Untouched(n); }
  bool ModOk(const Node* holder, const Mod& mod) {
    if (mod.value) {
      const ModValue& v = *mod.value;
      size_t i = 0;
      while (i < places_.size() && places_[i] != &v) ++i;
      if (i < places_.size()) ++found_[i];
      else if (v.pre && pre_is_place_) return false;
      if (v.scope && Inside(v.scope) && !IsAncestorOrSelf(v.scope, holder)) return false;
    }
    for (const auto& [k, sm] : mod.sub)
      if (!ModOk(holder, sm)) return false;
    return true;
  }

  const std::vector<const ModValue*>& places_;
  std::vector<int> found_;
  const bool pre_is_place_;
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

// The first's instance tree bound to a copy (an array's element k, or a sibling): copies
// of the nodes with the copy's names and scopes, and its own values in the first's places.
struct Instantiator::ShareBinding {
  // Arrays: element 1's slice values, and element k's value of each (aligned).
  const std::vector<SliceValue>* slice = nullptr;
  std::vector<const Value*> values;
  // Siblings: the first's own values, and the sibling's modifier's boxes holding its own
  // (aligned), moved into the copy.
  const std::vector<const ModValue*>* places = nullptr;
  std::vector<Boxed<ModValue>*> whole;
  std::vector<std::pair<const Node*, Node*>> ancestors;  // (the first's node, the copy's)
  // Per node of the first's tree in the order CloneInto visits them: whether its
  // modifiers are shared (SameInEveryElement: 1 yes, 0 no, -1 not yet known). The same
  // for every copy, so found at the first copy and read at the others.
  std::vector<signed char>* same_mod = nullptr;
  // Arrays, per node of element 1's tree, the same way: the id its class nodes' copies
  // share (Node::unit_slot), so that the unit check reads a binding once for all the
  // copies. Null for siblings: their values differ in more than numbers.
  std::vector<int>* copy_ids = nullptr;
  size_t visit = 0;

  // The index of `v` among the siblings' places, or -1.
  long Place(const ModValue* v) const {
    if (places)
      for (size_t i = 0; i < places->size(); ++i)
        if ((*places)[i] == v) return static_cast<long>(i);
    return -1;
  }
};

// The copy of a modifier of the first's tree: its value rebound to the copy (the scope
// mapped to the copy's node, a slice value replaced by element k's, a sibling's own value
// moved in), its flags, and for a variable its sub-modifiers (attributes: start, unit,
// ...). Not copied, as read nowhere after instantiation: the order the keys were written
// in (for messages about them), and a class or array node's sub-modifiers (moved into its
// elements, or sliced for an array's elements).
Mod Instantiator::BoundCopy(const Mod& src, ShareBinding& b, bool with_sub) {
  Mod out;
  if (const long own = src.value ? b.Place(&*src.value) : -1; own >= 0) {
    // The sibling's own (its scope, iterators and place in the source); the box moves,
    // so the value keeps its address (a copy of this copy finds it among its places).
    out.value = std::move(*b.whole[static_cast<size_t>(own)]);
  } else if (src.value) {
    out.value = *src.value;
    ModValue& v = *out.value;
    for (size_t i = b.ancestors.size(); i-- > 0;)
      if (b.ancestors[i].first == v.scope) {
        v.scope = b.ancestors[i].second;
        break;
      }
    if (b.slice)
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

// Whether a variable's modifiers in the first mean the same in every copy: no slice or
// sibling's own value, and every value either reads no name or is evaluated outside the
// first (its scope is not one of the nodes being copied, which are the only ones
// BoundCopy would map).
bool Instantiator::SameInEveryElement(const Mod& m, const ShareBinding& b) const {
  if (m.value) {
    const ModValue& v = *m.value;
    if (v.pre || b.Place(&v) >= 0) return false;
    if (!ReadsNoName(v.expr))
      for (const auto& a : b.ancestors)
        if (a.first == v.scope) return false;
  }
  for (const auto& [k, sm] : m.sub)
    if (!SameInEveryElement(sm, b)) return false;
  return true;
}

NodePtr Instantiator::CloneInstance(const Node& src, Node* parent, const std::string& name, ShareBinding& b) {
  auto n = tree_.arena.New();
  n->name = name;
  n->parent = parent;
  n->decl = src.decl;
  n->depth = src.depth;
  n->enabled = src.enabled;
  n->is_final_decl = src.is_final_decl;
  CloneInto(n.get(), src, b, false);
  return n;
}

// `n` made a copy of `src` (name, parent, declaration, depth set by the caller). The root
// of a sibling's copy keeps its own modifier: its values are moved from there by BoundCopy.
void Instantiator::CloneInto(Node* n, const Node& src, ShareBinding& b, bool root) {
  n->kind = src.kind;
  n->cls = src.cls;
  n->equations = src.equations;
  n->prim = src.prim;
  n->prim_kind = src.prim_kind;
  n->vtype = src.vtype;
  n->variability = src.variability;
  n->causality = src.causality;
  n->shape = src.shape;
  b.ancestors.emplace_back(&src, n);
  if (root) {
  } else if (src.kind != Node::kVar) {
    n->mod = BoundCopy(src.mod, b, false);
    if (src.kind == Node::kClass && b.copy_ids) {
      if (b.visit >= b.copy_ids->size()) b.copy_ids->resize(b.visit + 1, -1);
      int& id = (*b.copy_ids)[b.visit];
      if (id < 0) id = tree_.copies++;
      n->unit_slot = id;
    }
  } else if (src.mod_over_decl) {
    // Its declaration's attributes (literals) are every copy's; its own value is the
    // first's when that means the same in every copy, else bound to the copy. Shared, it
    // is checked on the first alone, as a shared whole modifier below.
    if (b.visit >= b.same_mod->size()) b.same_mod->resize(b.visit + 1, -1);
    signed char& same = (*b.same_mod)[b.visit];
    if (same < 0) same = !subscripted_sets_ && SameInEveryElement(src.mod, b);
    n->shared_mod = src.shared_mod;
    n->mod_over_decl = true;
    n->mod_from_decl = !same;
    // Not `same ? src.mod : BoundCopy(...)`: that expression is a copy of either, and a
    // sibling's own value would move into a box that is then copied and freed (its address,
    // which a copy of this copy looks for, reused by another value).
    if (same) n->mod = src.mod;
    else n->mod = BoundCopy(src.mod, b, true);
  } else {
    // A variable's modifiers (its value and attributes) are shared with the first when
    // they mean the same there, copied and bound to the copy otherwise. Not shared when a
    // subscripted --set may later change one element's (SetOverrides::Bind).
    const Mod& sm = src.shared_mod ? *src.shared_mod : src.mod;
    if (b.visit >= b.same_mod->size()) b.same_mod->resize(b.visit + 1, -1);
    signed char& same = (*b.same_mod)[b.visit];
    if (same < 0) same = !subscripted_sets_ && SameInEveryElement(sm, b);
    if (same) n->shared_mod = &sm;
    else n->mod = BoundCopy(sm, b, true);
  }
  ++b.visit;
  if (src.prim != Prim::None) RegisterPrimitive(n, n->cls);
  n->children.reserve(src.children.size());
  for (const auto& c : src.children) n->children.push_back(CloneInstance(*c, n, c->name, b));
  n->elems.reserve(src.elems.size());
  for (const auto& e : src.elems) n->elems.push_back(CloneInstance(*e, n->parent, e->name, b));
  b.ancestors.pop_back();
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
  ShareBinding b;
  b.slice = &share.slice;
  b.same_mod = &share.same_mod;
  b.copy_ids = &share.copy_ids;
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
  std::vector<const ModValue*> places;
  places.reserve(share->slice.size());
  for (const SliceValue& v : share->slice) places.push_back(v.at);
  share->ok = !from_set && diags_.All().size() == diags_before && !diags_.HasErrors() &&
              ShareCheck(places, true).Run(el);
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

// What the first sibling of a form taught: whether later ones may be copies of it.
struct Instantiator::SiblingShare {
  bool ok = false;
  const Node* first = nullptr;
  long per_copy = 0;                       // tree_.instances counted by the first
  std::vector<const ModValue*> places;     // its own values, where its modifier had them
  std::vector<signed char> same_mod;       // ShareBinding::same_mod, filled by the first copy
};

namespace {

// A scalar component's modifier as a form two siblings can share (keys, where the values
// are, each and final, into `form`) and its values' boxes, in the form's order (`own`);
// false when the modifier cannot be shared at all: a --set or a redeclare anywhere, or a
// value of the component itself.
bool SiblingForm(Mod& m, bool root, std::string* form, std::vector<Boxed<ModValue>*>* own) {
  if (m.set_only || m.redeclare) return false;
  if (m.value) {
    if (root || m.value->from_set) return false;
    own->push_back(&m.value);
    *form += m.value->is_final ? "=!" : "=";
  }
  if (m.each) *form += '*';
  if (m.is_final) *form += '!';
  for (auto& [k, sm] : m.sub) {
    form->append(k).push_back('(');
    if (!SiblingForm(sm, false, form, own)) return false;
    form->push_back(')');
  }
  return true;
}

}  // namespace

void Instantiator::InstantiateScalar(Node* node, Node* child, const ast::ClassDef* cls) {
  std::string form;
  std::vector<Boxed<ModValue>*> own;
  if (!share_siblings_ || subscripted_sets_ || !SiblingForm(child->mod, true, &form, &own)) {
    Instantiate(child, cls);
    return;
  }
  if (child->is_final_decl) form += "!";
  std::shared_ptr<SiblingShare>& share = siblings_[SiblingKey{node, cls, std::move(form)}];
  if (share && !share->ok) {  // the first could not be copied: neither can this one
    Instantiate(child, cls);
    return;
  }
  if (share && tree_.instances + share->per_copy <= kMaxInstances && Unread(*share->first)) {
    ShareBinding b;
    b.places = &share->places;
    b.whole = std::move(own);
    b.same_mod = &share->same_mod;
    tree_.instances += share->per_copy;
    CloneInto(child, *share->first, b, true);
    return;
  }
  // The first of its form, or a new first (the old one was read since, or the instance
  // limit is near: then instantiating reports it).
  share = std::make_shared<SiblingShare>();
  share->places.reserve(own.size());
  for (Boxed<ModValue>* v : own) share->places.push_back(&**v);  // before Instantiate moves them
  const size_t diags_before = diags_.All().size();
  const long instances_before = tree_.instances;
  Instantiate(child, cls);
  share->first = child;
  share->per_copy = tree_.instances - instances_before;
  share->ok = diags_.All().size() == diags_before && !diags_.HasErrors() && ShareCheck(share->places, false).Run(child);
}

}  // namespace kanesim::lang::elab
