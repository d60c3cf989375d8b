// The elaborator's intermediate forms, shared by its phases: values, merged modifiers and
// the instance tree. The phases' own headers (lang/elab_lookup.h, elab_modifiers.h,
// elab_eval.h, elab_instantiate.h, elab_set.h, elab_connect.h, elab_emit.h) declare what
// each takes and gives; lang/elaborate.cpp runs them in order. Only lang/elab_*.cpp and
// lang/elaborate.cpp include these headers.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <new>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "lang/ast.h"
#include "lang/diagnostics.h"
#include "lang/elab_small_vec.h"
#include "lang/elaborate.h"
#include "lang/node_pool.h"
#include "flat/mechanism.h"

namespace kanesim::lang::elab {

using flat::ExprId;

enum class VType { Real, Integer, Boolean, String };
const char* VTypeName(VType t);

// The type of an arithmetic result: Integer only when both operands are.
inline VType Promote(VType a, VType b) {
  return a == VType::Integer && b == VType::Integer ? VType::Integer : VType::Real;
}

// An array's sizes: empty for a scalar; vectors and matrices without a heap allocation.
using Dims = SmallVec<int, 2>;

// "scalar" or "[2, 3]", for messages.
inline std::string ShapeStr(const Dims& shape) {
  if (shape.empty()) return "scalar";
  std::string s = "[";
  for (size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

// A value's element expressions: a scalar, 3-vector or 3x3 matrix without a heap allocation.
using Elements = SmallVec<ExprId, 9>;

// A value: a (possibly empty-shaped = scalar) array of scalar expressions.
struct Value {
  VType type = VType::Real;
  bool valid = true;               // false after an error (suppresses cascades)
  Dims shape;                     // empty = scalar
  Elements elements;               // the elements' expressions in the pool, row-major (up to 3x3 inline)
  std::vector<std::string> strings;  // a String value's elements, row-major (elements too holds one id each)
  size_t Size() const;
  static Value Invalid() {
    Value v;
    v.valid = false;
    return v;
  }
};

using Iters = std::map<std::string, double>;

// An optional value kept on the heap: like std::optional (bool test, *, ->, reset,
// assignment of a T), copied deeply, but one pointer wide while empty. Instance nodes and
// modifiers have several of these fields and most are empty, so this keeps the instance
// tree small (memory is linear in the model, and this is its constant).
template <class T>
class Boxed {
 public:
  Boxed() = default;
  Boxed(const Boxed& o) : p_(o.p_ ? std::make_unique<T>(*o.p_) : nullptr) {}
  Boxed(Boxed&&) noexcept = default;
  Boxed& operator=(const Boxed& o) {
    if (this != &o) p_ = o.p_ ? std::make_unique<T>(*o.p_) : nullptr;
    return *this;
  }
  Boxed& operator=(Boxed&&) noexcept = default;
  Boxed& operator=(const T& v) {
    p_ = std::make_unique<T>(v);
    return *this;
  }
  Boxed& operator=(T&& v) {
    p_ = std::make_unique<T>(std::move(v));
    return *this;
  }
  explicit operator bool() const { return p_ != nullptr; }
  T& operator*() const { return *p_; }
  T* operator->() const { return p_.get(); }
  void reset() { p_.reset(); }

 private:
  std::unique_ptr<T> p_;
};

// A std::map that is one pointer wide while empty (what Boxed is to std::optional):
// nearly every variable has no per-element equation, and the instance tree's size is
// the front end's memory, so its fresh pages, in a short process.
template <class K, class V>
class LazyMap {
  using Map = std::map<K, V>;

 public:
  using iterator = typename Map::iterator;
  using const_iterator = typename Map::const_iterator;
  iterator begin() { return m_ ? m_->begin() : Empty().begin(); }
  iterator end() { return m_ ? m_->end() : Empty().end(); }
  const_iterator begin() const { return m_ ? m_->cbegin() : Empty().cbegin(); }
  const_iterator end() const { return m_ ? m_->cend() : Empty().cend(); }
  iterator find(const K& k) { return m_ ? m_->find(k) : Empty().end(); }
  const_iterator find(const K& k) const { return m_ ? m_->find(k) : Empty().cend(); }
  size_t size() const { return m_ ? m_->size() : 0; }
  bool empty() const { return !m_ || m_->empty(); }
  size_t count(const K& k) const { return m_ ? m_->count(k) : 0; }
  V& operator[](const K& k) {
    if (!m_) m_ = std::make_unique<Map>();
    return (*m_)[k];
  }

 private:
  static Map& Empty() {  // never written: its begin() == end() stand for an empty map's
    static Map empty;
    return empty;
  }
  std::unique_ptr<Map> m_;
};

struct Node;

// Ends a node made by a NodeArena: runs its destructor; its memory goes with the arena's.
struct NodeRelease {
  void operator()(Node* n) const;
};
using NodePtr = std::unique_ptr<Node, NodeRelease>;

// Where an instance tree's nodes live: blocks of nodes handed out in order and given back
// all at once when the tree ends (one allocation per kBlockNodes nodes instead of one
// each). Blocks stay small enough for malloc to reuse them (no fresh pages for compile).
class NodeArena {
 public:
  NodeArena() = default;
  NodeArena(const NodeArena&) = delete;
  NodeArena& operator=(const NodeArena&) = delete;
  ~NodeArena();
  NodePtr New();

 private:
  static constexpr size_t kBlockNodes = 64;
  std::vector<void*> blocks_;
  size_t used_ = kBlockNodes;  // nodes handed out from the last block
};

// One binding written somewhere in the source: an expression, where to evaluate it, and
// the loop iterators in force there; or a value already computed (array slicing).
struct ModValue {
  KANESIM_POOLED_NODE(ModValue)  // one per modifier value of every instance (lang/node_pool.h)
  const ast::Expr* expr = nullptr;
  Node* scope = nullptr;
  std::shared_ptr<const Iters> iters;
  Boxed<Value> pre;
  Span span;
  bool is_final = false;
  bool from_set = false;  // came from --set on the command line
};

// A merged modification tree (Modelica "modification environment").
struct Mod;
// A modifier's sub-modifiers by name; transparent: find("unit") makes no string. Its nodes
// come from a pool (thousands per model, made one at a time: lang/node_pool.h).
using ModMap = std::map<std::string, Mod, std::less<>, PoolAllocator<std::pair<const std::string, Mod>>>;

struct Mod {
  // User-provided, so that value-initialization (a map's try_emplace, Mod{}) runs the
  // member initializers only and does not zero the whole struct first.
  Mod() {}  // NOLINT(modernize-use-equals-default)
  Boxed<ModValue> value;
  ModMap sub;
  std::vector<std::string> order;   // sub keys in the order written
  bool each = false;
  bool is_final = false;
  Span final_span;                   // where `final` was written
  Span span;                         // where this modifier was written (name span)
  // redeclare: the new type, looked up from `from` (boxed: rarely written).
  struct Redeclare {
    std::string type;
    const ast::ClassDef* from = nullptr;
    Span span;
  };
  Boxed<Redeclare> redeclare;
  bool Redeclared() const { return redeclare && !redeclare->type.empty(); }
  bool set_only = false;  // made by --set alone: its names are checked by SetOverrides::Bind
  bool empty() const { return !value && sub.empty() && !Redeclared(); }
};

// A variable's modifiers as Node::Modifiers() reads them: its value and its attributes
// (start, unit, min, ...), which may be held in two places (Node::mod_over_decl).
struct ModView {
  const ModValue* value;  // null: none
  const ModMap& sub;
  const std::vector<std::string>& order;
  bool is_final;
};

// Shape: a stdlib part drawn as what it is (kind "rod", "box", "cylinder", "sphere", "mesh";
// lang/elab_shapes.cpp); it only describes, its Body does the physics.
enum class Prim { None, Frame, Flange, World, Body, Fixed, Joint, LineForce, Wrench, Contact, RotSpring, Coupling, Shape };

// Where Evaluator::GetVar (lang/elab_vars.cpp) is with a variable: not yet asked for, being
// evaluated (asked again now means a cycle), or `value` final.
enum class EvalState { Unevaluated, Evaluating, Done };

struct Node {
  // The small fields first, together: a model has thousands of nodes (no padding between them).
  enum Kind : std::uint8_t { kClass, kVar, kArray } kind = kClass;
  bool enabled = true;
  bool is_final_decl = false;  // kVar
  // kVar: shared_mod is its declaration's modifier, shared by every instance not modified
  // from outside or only given a value (Instantiator::DeclarationMod), read as its own (not
  // an array element's copy).
  bool mod_from_decl = false;
  // kVar: two-level modifiers. `mod` holds only the value given from outside (`m = 2.5`),
  // shared_mod (its declaration's) the attributes: no merged copy of them per instance.
  bool mod_over_decl = false;
  mutable std::uint16_t scans = 0;  // Child()'s scans of a class above kScanChildren elements
  int depth = 0;
  // For the unit check (lang/elab_units.cpp), in the padding before `name` (the node does
  // not grow). kVar: its declared unit, looked up once per variable instead of once per
  // use: -1 not yet, >= 0 the checker's slot, below -1 none (and how far its inference got).
  // kClass: in an array element copied from element 1 (lang/elab_share.cpp), the id every
  // copy of the same node of element 1 has, else -1: a binding read there has one unit in
  // all the copies.
  mutable std::int32_t unit_slot = -1;
  std::string name;  // "links[2]" for array elements
  Node* parent = nullptr;
  const ast::Component* decl = nullptr;  // null for the root and array elements' owner copy
  Mod mod;
  // A variable of an array element copied from element 1 (lang/elab_share.cpp) whose
  // modifiers mean the same in every element (literals, or evaluated outside the element)
  // reads element 1's instead of a copy: `mod` then stays empty. Read modifiers after
  // instantiation through Modifiers().
  const Mod* shared_mod = nullptr;
  ModView Modifiers() const {
    const Mod& attrs = shared_mod ? *shared_mod : mod;
    const Boxed<ModValue>& v = mod_over_decl ? mod.value : attrs.value;
    return {v ? &*v : nullptr, attrs.sub, attrs.order, attrs.is_final};
  }
  // The modifiers as the node's own, to change (a --set of one instance): shared ones
  // copied first, as the merge of the outer value over the declaration would have made them.
  Mod& OwnMod() {
    if (!shared_mod) return mod;
    Mod whole = *shared_mod;
    if (mod_over_decl) {
      whole.value = std::move(mod.value);
      if (mod.span.valid()) whole.span = mod.span;
    }
    mod = std::move(whole);
    shared_mod = nullptr;
    mod_over_decl = false;
    return mod;
  }
  // "robot.links[2]" (the root's is empty), made when asked for: most nodes' paths are
  // only read by a diagnostic, and a string kept in each cost an allocation and its free.
  std::string Path() const {
    std::string p;
    p.reserve(PathSize());  // one allocation: appended part by part, a long path regrew twice
    AppendPath(p);
    return p;
  }
  // The length of Path(), read up the tree without writing it.
  size_t PathSize() const {
    size_t n = 0;
    for (const Node* a = this; a->parent; a = a->parent) n += a->name.size() + 1;
    return n > 0 ? n - 1 : 0;
  }
  void AppendPath(std::string& out) const { AppendPathFrom(out, out.size()); }

  // kClass
  const ast::ClassDef* cls = nullptr;
  std::vector<NodePtr> children;
  // The index of `children` Child() builds for a large class, keyed by the children's names
  // (views of Node::name, which outlives it).
  using ChildIndex = std::unordered_map<std::string_view, Node*, std::hash<std::string_view>,
                                        std::equal_to<>, PoolAllocator<std::pair<const std::string_view, Node*>>>;
  mutable std::unique_ptr<ChildIndex> by_name;  // its entries from a pool (lang/node_pool.h)
  struct EqSource {
    const ast::Equation* eq;
    const ast::ClassDef* cls;  // for lookups
  };
  std::vector<EqSource> equations;
  Prim prim = Prim::None;
  int prim_index = -1;    // frame id / joint id / flange id
  std::string prim_kind;  // annotation's second key value ("revolute", "rolling_disk"...)

  // kVar
  VType vtype = VType::Real;
  ast::Variability variability = ast::Variability::None;
  ast::Causality causality = ast::Causality::None;
  EvalState state = EvalState::Unevaluated;  // GetVar's progress on `value`
  Dims shape;
  Value value;
  Boxed<ModValue> eq_binding;                    // from an equation `x = expr`
  LazyMap<int, ModValue> eq_elem_binding;        // from `x[k] = expr`

  // kArray
  std::vector<NodePtr> elems;

  static constexpr size_t kScanChildren = 16;
  void AppendPathFrom(std::string& out, size_t start) const {
    if (!parent) return;
    parent->AppendPathFrom(out, start);
    if (out.size() > start) out += '.';
    out += name;
  }
  static constexpr size_t kScanBudget = 256;  // names a larger class's scans compare before it gets an index
  // By view: the emitter's and the evaluator's names are literals (no string made per call).
  Node* Child(std::string_view n) const {
    // Most classes have a handful of elements: a scan beats hashing. A larger one gets an
    // index once its scans would have compared kScanBudget names: at once for a model of
    // many declarations (lookups stay O(1)), never for an instance looked up a few times
    // (each element of an array of links, whose index cost more than its lookups).
    const size_t count = children.size();
    if (count <= kScanChildren || (!by_name && count * (scans + 1u) <= kScanBudget)) {
      if (count > kScanChildren) ++scans;
      for (size_t i = count; i-- > 0;) {  // lengths first: most names differ in length
        const std::string& c = children[i]->name;
        if (c.size() == n.size() && std::char_traits<char>::compare(c.data(), n.data(), n.size()) == 0)
          return children[i].get();
      }
      return nullptr;
    }
    if (!by_name || by_name->size() != children.size()) {
      by_name = std::make_unique<ChildIndex>();
      by_name->reserve(children.size());
      for (const auto& c : children) (*by_name)[c->name] = c.get();
    }
    auto it = by_name->find(n);
    return it == by_name->end() ? nullptr : it->second;
  }
};

inline void NodeRelease::operator()(Node* n) const { n->~Node(); }

inline NodeArena::~NodeArena() {
  // Unsized: clang 14 (the fuzz build) declares the sized form only with -fsized-deallocation.
  for (void* b : blocks_) ::operator delete(b);
}

inline NodePtr NodeArena::New() {
  static_assert(alignof(Node) <= __STDCPP_DEFAULT_NEW_ALIGNMENT__);
  if (used_ == kBlockNodes) {
    blocks_.push_back(::operator new(kBlockNodes * sizeof(Node)));
    used_ = 0;
  }
  void* at = static_cast<char*>(blocks_.back()) + used_++ * sizeof(Node);
  // Default-initialized: every field has its initializer. `Node()` would zero the whole
  // ~500 bytes first (value-initialization of a class without a user-provided constructor).
  return NodePtr(new (at) Node);
}

// Where an expression is evaluated: the instance it names things in, and the loop
// iterators in force there.
struct Ctx {
  Node* scope = nullptr;
  const Iters* iters = nullptr;
};

// Places in the source for the flat mechanism (file, line, column), found once per place:
// every element of an array asks for the same declarations' places (lang/elaborate.cpp).
class SourcePlaces {
 public:
  explicit SourcePlaces(const SourceManager& sources) : sources_(sources) {}
  flat::SourceLoc Loc(Span s) const;
  // Node n's declaration, or the nearest enclosing one in a user file (not the library).
  Span UserSpan(const Node* n) const;
  const SourceManager& Sources() const { return sources_; }

 private:
  const SourceManager& sources_;
  mutable std::unordered_map<std::uint64_t, flat::SourceLoc> cache_;  // (file, offset) -> place
};

// Element `index` (0-based) of `v`, an array value of `count` elements along its first
// dimension (lang/elab_modifiers.cpp).
Value ElementOf(const Value& v, int index, int count);

// Modelica-style attribute names accepted on variables.
bool IsVarAttribute(const std::string& name);

}  // namespace kanesim::lang::elab
