// Internal data of the elaborator: the instance tree, merged modifiers and values.
// Only lang/elab_*.cpp and lang/elaborate.cpp include this.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "lang/ast.h"
#include "lang/diagnostics.h"
#include "lang/elab_budget.h"
#include "lang/library_cache.h"
#include "lang/elab_small_vec.h"
#include "lang/elaborate.h"
#include "flat/mechanism.h"
#include "flat/param_eval.h"
#include "geometry/mesh_check.h"
#include "geometry/tri_mesh.h"

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
  Dims shape;                     // empty = scalar
  Elements elements;               // the elements' expressions in the pool, row-major (up to 3x3 inline)
  std::vector<std::string> strings;  // a String value's elements, row-major (elements too holds one id each)
  bool valid = true;               // false after an error (suppresses cascades)
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

struct Node;

// One binding written somewhere in the source: an expression, where to evaluate it, and
// the loop iterators in force there; or a value already computed (array slicing).
struct ModValue {
  const ast::Expr* expr = nullptr;
  Node* scope = nullptr;
  std::shared_ptr<const Iters> iters;
  Boxed<Value> pre;
  Span span;
  bool is_final = false;
  bool from_set = false;  // came from --set on the command line
};

// A merged modification tree (Modelica "modification environment").
struct Mod {
  Boxed<ModValue> value;
  std::map<std::string, Mod, std::less<>> sub;  // transparent: find("unit") makes no string
  std::vector<std::string> order;   // sub keys in the order written
  bool each = false;
  bool is_final = false;
  Span final_span;                   // where `final` was written
  Span span;                         // where this modifier was written (name span)
  // redeclare: the new type, looked up from `redeclare_from`.
  std::string redeclare_type;
  const ast::ClassDef* redeclare_from = nullptr;
  Span redeclare_span;
  bool set_only = false;  // made by --set alone: its names are checked by BindSetOverrides
  bool empty() const { return !value && sub.empty() && redeclare_type.empty(); }
};

// Shape: a stdlib part drawn as what it is (kind "rod", "box", "cylinder", "sphere", "mesh";
// lang/elab_shapes.cpp); it only describes, its Body does the physics.
enum class Prim { None, Frame, Flange, World, Body, Fixed, Joint, LineForce, Wrench, Contact, RotSpring, Shape };

// Where GetVar (lang/elab_lookup.cpp) is with a variable: not yet asked for, being
// evaluated (asked again now means a cycle), or `value` final.
enum class EvalState { Unevaluated, Evaluating, Done };

struct Node {
  enum Kind { kClass, kVar, kArray } kind = kClass;
  std::string name;  // "links[2]" for array elements
  std::string path;  // "robot.links[2]"
  Node* parent = nullptr;
  const ast::Component* decl = nullptr;  // null for the root and array elements' owner copy
  Mod mod;
  // A variable of an array element copied from element 1 (lang/elab_share.cpp) whose
  // modifiers mean the same in every element (literals, or evaluated outside the element)
  // reads element 1's instead of a copy: `mod` then stays empty. Read modifiers after
  // instantiation through Modifiers().
  const Mod* shared_mod = nullptr;
  const Mod& Modifiers() const { return shared_mod ? *shared_mod : mod; }
  bool enabled = true;
  int depth = 0;

  // kClass
  const ast::ClassDef* cls = nullptr;
  std::vector<std::unique_ptr<Node>> children;
  mutable std::unique_ptr<std::unordered_map<std::string, Node*>> by_name;  // index of `children`, built by
                                                                           // Child() for large classes
  struct EqSource {
    const ast::Equation* eq;
    const ast::ClassDef* cls;  // for lookups
  };
  std::vector<EqSource> equations;
  Prim prim = Prim::None;
  std::string prim_kind;  // annotation's second key value ("revolute", "rolling_disk"...)
  int prim_index = -1;    // frame id / joint id / flange id

  // kVar
  VType vtype = VType::Real;
  ast::Variability variability = ast::Variability::None;
  ast::Causality causality = ast::Causality::None;
  Dims shape;
  EvalState state = EvalState::Unevaluated;  // GetVar's progress on `value`
  Value value;
  Boxed<ModValue> eq_binding;                    // from an equation `x = expr`
  std::map<int, ModValue> eq_elem_binding;       // from `x[k] = expr`
  bool is_final_decl = false;

  // kArray
  std::vector<std::unique_ptr<Node>> elems;

  static constexpr size_t kScanChildren = 16;
  Node* Child(const std::string& n) const {
    // Most classes have a handful of elements: a scan beats hashing. Large ones (a model
    // with many declared components) get an index, so that lookups stay O(1).
    if (children.size() <= kScanChildren) {
      for (size_t i = children.size(); i-- > 0;)
        if (children[i]->name == n) return children[i].get();
      return nullptr;
    }
    if (!by_name || by_name->size() != children.size()) {
      by_name = std::make_unique<std::unordered_map<std::string, Node*>>();
      for (const auto& c : children) (*by_name)[c->name] = c.get();
    }
    auto it = by_name->find(n);
    return it == by_name->end() ? nullptr : it->second;
  }
};

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
};

struct ClassInfo {
  const ast::ClassDef* cls;
  const ast::StoredDefinition* file;
  std::string qualified;
};

class Elaborator {
 public:
  Elaborator(const Program& program, const ElaborateOptions& options, flat::Mechanism* out, Diagnostics& diags);
  bool Run();
  // Run's stages (elaborate.cpp).
  const ast::ClassDef* PickModel();
  bool CheckImports(const ast::StoredDefinition& f);
  void CheckImport(const std::string& q, bool wildcard, Span span);
  void ReadExperiment(const ast::Modification& ex, const ast::ClassDef* top);

  // --- classes (elaborate.cpp) ---
  const ast::ClassDef* FindClass(const std::vector<std::string>& parts, const ast::ClassDef* from) const;
  const ast::StoredDefinition* FileOf(const ast::ClassDef* c) const;
  // The registry of classes by qualified name. The embedded library's classes join it
  // when a lookup first names them (LookupClass), or all at once (LoadWholeLibrary) before
  // anything lists the registry (the hints of an error): either way every answer is the
  // one a registry of the whole library would give.
  const ClassInfo* LookupClass(const std::string& q) const;
  void LoadWholeLibrary() const;
  void Register(const ast::ClassDef* c, const std::string& prefix, const ast::StoredDefinition* file) const;
  bool LoadLibraryClass(const std::string& q) const;
  void LoadUnit(int u) const;

  // --- values (elab_eval.cpp) ---
  struct Ctx {
    Node* scope = nullptr;
    const Iters* iters = nullptr;
  };
  Value Eval(const ast::Expr& e, const Ctx& ctx);
  // One kind each (elab_eval.cpp); EvalNested bounds their recursion (elab_budget.cpp).
  Value EvalNested(const ast::Expr& e, const Ctx& ctx);
  Value EvalNode(const ast::Expr& e, const Ctx& ctx);
  Value EvalRef(const ast::Expr& e, const Ctx& ctx);
  // EvalRef's steps (elab_eval.cpp): a reference walked part by part through the tree.
  void ReportUnknownName(const ast::RefPart& head, const Ctx& ctx);
  static bool IsFrameMotion(const Node* n, const std::string& name);
  Value FrameMotion(const ast::Expr& e, size_t pi, const Node* frame, const Ctx& ctx);  // frame.r/R/v/w
  Value SubscriptFrameMotion(const Value& v, const ast::RefPart& part, const Ctx& ctx);
  Node* Member(Node* n, const ast::RefPart& part);  // null after a diagnostic
  Node* ArrayElement(Node* array, const ast::RefPart& part, const Ctx& ctx);
  Value VarReference(const ast::Expr& e, size_t pi, Node* var, const Ctx& ctx);
  Value SubscriptValue(const Value& v, const ast::RefPart& part, const Node* var, const Ctx& ctx);
  // One subscript of dimension `size`: its 0-based indices; *keep when it keeps the dimension.
  bool SubscriptIndices(const ast::Expr& s, int size, const Node* var, const Ctx& ctx, std::vector<int>* list,
                        bool* keep);
  Value EvalArray(const ast::Expr& e, const Ctx& ctx);
  Value EvalComprehension(const ast::Expr& e, const Ctx& ctx);
  Value EvalMatrix(const ast::Expr& e, const Ctx& ctx);
  Value EvalRange(const ast::Expr& e, const Ctx& ctx);
  Value EvalIf(const ast::Expr& e, const Ctx& ctx);
  // Built-in functions (elab_builtins.cpp): one table {name, arity, lowering}.
  Value EvalCall(const ast::Expr& e, const Ctx& ctx);
  // Concatenation (elab_concat.cpp): cat(k, ...), and EvalMatrix above.
  Value EvalCat(const ast::Expr& e, const std::vector<Value>& args);
  Value Concatenate(size_t k, const std::vector<Value>& parts, const std::vector<Span>& spans,
                    const std::vector<std::string>& names, Span whole, const std::string& what,
                    const std::string& hint);
  // Operators (elab_operators.cpp): chains of them with an explicit stack.
  Value EvalOperators(const ast::Expr& root, const Ctx& ctx);
  Value UnaryOp(const ast::Expr& e, Value v);
  Value BinaryOp(const ast::Expr& e, const Value& a, const Value& b);
  Value MatrixProduct(const ast::Expr& e, const Value& a, const Value& b);
  Value Comparison(const ast::Expr& e, const Value& a, const Value& b);
  Value Elementwise2(const Value& a, const Value& b, flat::Op op, VType rt, Span sp);
  // Work budget (elab_budget.cpp): false once the elaboration has used it up.
  // Node n's declaration, or the nearest enclosing one in a user file (not the library).
  Span UserSpan(const Node* n) const;
  bool ChargeSteps(std::int64_t steps, Span where);
  bool ChargeNodes(std::int64_t more, Span where);  // false once the pool would pass kMaxExprNodes
  bool Charge(const Value& v, Span where);
  Value EvalModValue(const ModValue& mv, Span* where);
  // The variable's value, evaluated on first use; valid as long as the instance tree.
  const Value& GetVar(Node* var, Span use_span);
  // GetVar's stages (elab_lookup.cpp): the value from the binding, checked, then for a
  // parameter its flat parameters.
  Value EvaluateVar(Node* var, Span use_span);
  Value JointStateValue(Node* var);                       // a joint's q or u: state references
  const ModValue* VarBinding(Node* var);                  // declaration/modifier or equation
  Value UnboundValue(Node* var, Span use_span);           // zeros, or a missing-value error
  Value BoundValue(Node* var, const ModValue& binding);   // evaluated, type and size checked
  bool CheckValueType(Node* var, const ModValue& binding, const Value& v, Span where);
  void ApplyElementEquations(Node* var, Value& v);        // x[k] = ... over the value
  Value ParameterValue(Node* var, const ModValue* binding, Span use_span, Value v);
  struct ParamAttributes {  // a parameter's min, max and unit modifiers
    std::string unit;
    double min = -1e300, max = 1e300;
  };
  ParamAttributes ReadParamAttributes(Node* var);
  // One element as a flat parameter: `p`, the last of m_->params (for a constant, folded
  // instead, a Param of its own); its value checked and set; its pool node.
  ExprId AddParamElement(Node* var, flat::Param& p, ExprId x, Span value_span);
  // Evaluates to a number at elaboration time (array sizes, conditions, for ranges,
  // subscripts); marks the parameters it reads as structural.
  bool Structural(const Value& v, Span span, double* out, const char* what);
  bool StructuralInt(const Value& v, Span span, long* out, const char* what);
  void MarkStructural(ExprId id);
  std::vector<double> StructuralList(const Value& v, Span span, const char* what);
  Value Const(double x, VType t = VType::Real);
  Value Scalar(ExprId e, VType t = VType::Real);

  // --- meshes (elab_mesh.cpp) ---
  // One mesh file read at one scale: its mass properties at unit density, or its problems.
  struct MeshEntry {
    bool ok = false;
    std::uint64_t triangles = 0;
    double volume = 0;                                      // V  (m³)
    geometry::Vec3 centre = geometry::Vec3::Zero();          // p_MBcm  (m)
    geometry::Mat3 unit_inertia = geometry::Mat3::Zero();    // I_Bcm_M at density 1  (m⁵)
    std::vector<geometry::MeshProblem> problems;
    std::set<std::pair<int, int>> reported;                 // (file, offset) of places told of the problems
  };
  // meshVolume / meshCentre / meshInertia(file, scale).
  Value EvalMeshCall(const std::string& fn, const ast::Expr& e, const std::vector<Value>& args, const Ctx& ctx);
  // Reads (once) and reports its problems at `where` (once per place); null when unusable.
  const MeshEntry* LoadMeshFor(const std::string& path, double scale, Span where);
  // `file` resolved against the directory of the source file `origin` is in.
  std::string MeshPath(const std::string& file, Span origin) const;
  // Where an argument's value was written: follows references to the binding they take
  // their value from (a MeshBody's `file` to the user's `file = "..."`).
  Span ValueOrigin(const ast::Expr& arg, const Ctx& ctx);
  // Records a shape for drawing (elab_shapes.cpp), and links them to their bodies.
  void EmitShape(Node* n);
  void LinkShapes();

  // --- instances (elab_instantiate.cpp) ---
  Mod BuildMod(const ast::Modification* m, Node* scope, const std::shared_ptr<const Iters>& iters);
  void MergeInto(Mod& outer, const Mod& inner, const std::string& what);  // outer wins
  void MergeInto(Mod& outer, Mod&& inner, const std::string& what);       // the same, moving inner's values
  void Instantiate(Node* node, const ast::ClassDef* cls, const ast::ClassDef* lookup_from);
  void CollectEquations(Node* node);
  void ProcessEquations(Node* node);
  void ProcessEquation(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  // One kind each (elab_equations.cpp).
  void ProcessConnect(Node* node, const ast::Equation& eq, const Iters* iters);
  void ProcessFor(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  void ProcessIf(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  void ProcessEquality(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  void BindEquation(Node* v, int elem, const ast::Equation& eq, ModValue mv);  // x = ... or x[k] = ...
  // Resolves a reference to an instance node; for variables with subscripts, *elem gets
  // the flat element index (or -1 for the whole variable).
  Node* ResolveNode(const ast::Expr& ref, const Ctx& ctx, int* elem);
  struct Collected {
    const ast::Component* comp;
    const ast::ClassDef* owner;
    Mod ext_mod;
    bool is_final = false, replaceable = false;
  };
  // `names` indexes `out` by element name (the AST owns the names), so that a class of n
  // elements is collected in O(n), not O(n^2) (issue 38: 123 000 parameters).
  using CollectedNames = std::unordered_map<std::string_view, size_t>;
  void Collect(const ast::ClassDef* cls, Node* node, const Mod* ext_mod, std::vector<Collected>& out,
               CollectedNames& names, std::vector<Node::EqSource>& eqs, int depth);
  void CheckOuterModifiers(Node* node, const ast::ClassDef* cls, const std::vector<Collected>& elems,
                           const CollectedNames& names);
  // Instantiate's steps (elab_instantiate.cpp).
  struct ClassPrim;
  const ClassPrim& PrimitiveAnnotation(const ast::ClassDef* cls);
  std::unique_ptr<Node> MakeChild(Node* node, Collected& c);
  void Expand(Node* node, Node* child, const Collected& c);
  // Expand's steps (elab_instantiate.cpp).
  struct ComponentType {  // what a component's declared (or redeclared) type turned out to be
    const ast::ClassDef* cls = nullptr;  // a class type; null for a builtin
    VType builtin = VType::Real;
    bool is_builtin = false;
    std::string redeclared_name;  // a builtin named by a redeclare
    // The type's name, for messages.
    std::string Name(const ast::Component& comp) const {
      return redeclared_name.empty() ? ast::JoinName(comp.type_name) : redeclared_name;
    }
  };
  bool ComponentEnabled(Node* node, Node* child, const ast::Component& comp);  // its condition
  void AppendDims(const std::vector<ast::ExprPtr>& ds, Node* node, std::vector<int>* dims);
  bool ResolveComponentType(Node* node, Node* child, const Collected& c, ComponentType* t);
  bool ApplyRedeclare(Node* child, const Collected& c, ComponentType* t);
  const ast::ClassDef* DeclaredClass(const ast::Component& comp, const ast::ClassDef* owner);
  void ReportUnknownType(const ast::Component& comp, const ComponentType& t);
  bool ShortTypeToBuiltin(Node* node, Node* child, const ast::Component& comp, ComponentType* t);
  void ExpandVariable(Node* child, const ast::Component& comp, VType builtin, const std::vector<int>& dims);
  void CheckVarAttributes(Node* var, VType builtin);
  void ExpandComponent(Node* node, Node* child, const Collected& c, const ComponentType& t,
                       const std::vector<int>& dims);
  Mod SliceMod(const Mod& mod, int index, int count, Span where);
  void RegisterPrimitive(Node* node, const ast::ClassDef* cls);
  // Arrays of components (elab_share.cpp): element 1 instantiated, the others bound
  // copies of it when that is provably the same, else instantiated each.
  void InstantiateArray(Node* node, Node* array, const ast::Component& comp, const ast::ClassDef* tcls,
                        const ast::ClassDef* owner, int n);
  struct ShareBinding;
  struct ArrayShare;
  void InstantiateFirst(Node* el, const ast::ClassDef* tcls, const ast::ClassDef* owner, ArrayShare* share);
  bool ShareElement(const ArrayShare& share, Node* node, Node* array, const std::string& name, int index, int count);
  std::unique_ptr<Node> CloneInstance(const Node& src, Node* parent, const std::string& name, ShareBinding& b);
  Mod BoundCopy(const Mod& src, ShareBinding& b, bool with_sub);
  bool SameInEveryElement(const Mod& m, const ShareBinding& b) const;
  const ast::ClassDef* ResolveShort(const ast::ClassDef* cls, Node* node, Mod* mod);
  const ast::Modification* FindAnnotation(const ast::ClassDef* cls, const std::string& key) const;
  flat::SourceLoc Loc(Span s) const;

  // --- --set overrides (elab_set.cpp) ---
  bool ParseSetOverrides();
  void BindSetOverrides();
  Node* ResolveSetTarget(const SetOverride& so, int* elem);
  Node* SetMember(const SetOverride& so, size_t i, Node* n);
  Node* SetArrayElement(const SetOverride& so, size_t i, Node* array);
  bool SetVarElement(const SetOverride& so, size_t i, const Node* n, int* elem);
  ModValue SetValue(const SetOverride& so);
  Span SetSpan(const SetOverride& so, int begin, int end) const;

  // --- emission (elab_emit.cpp) ---
  void Emit(Node* root);

  const Program& program_;
  const ElaborateOptions& options_;
  flat::Mechanism* m_;
  Diagnostics& diags_;
  const Library* library_;  // null when the library is in program_.files
  // mutable: a lookup (const) registers the library's classes it is the first to name.
  mutable std::vector<char> unit_loaded_;  // per library unit
  mutable std::map<std::string, ClassInfo> classes_;  // qualified name -> class
  mutable std::unordered_map<const ast::ClassDef*, const ast::StoredDefinition*> file_of_;
  mutable std::unordered_map<const ast::ClassDef*, std::string> qualified_of_;
  std::vector<double> pvals_;  // values of m_->params, index-aligned
  flat::ParamEvaluator param_eval_{m_->exprs, pvals_};  // memoized values of pool nodes
  std::vector<std::uint8_t> structural_seen_;  // per pool node: walked by MarkStructural
  std::vector<ExprId> structural_stack_;        // MarkStructural's scratch
  std::vector<Node*> frame_nodes_;   // provisional frame id -> node
  std::vector<Node*> flange_nodes_;  // flange id -> node
  std::vector<Node*> joint_nodes_;   // joint id -> node
  std::vector<std::pair<int, int>> frame_links_;   // connect() pairs (provisional ids)
  std::vector<std::pair<int, int>> flange_links_;
  long instances_ = 0;
  WorkBudget budget_{kMaxElabWork};
  bool budget_reported_ = false;
  int eval_depth_ = 0;  // EvalNested frames on the native stack
  StackGuard stack_;    // made with the Elaborator: the base of its evaluation
  bool depth_reported_ = false;
  bool too_large_ = false;
  std::vector<const ast::ClassDef*> extends_stack_;
  // Lookups that depend on the class alone, made once per class rather than per instance:
  // the __kanesim annotation (null: none), and a component's declared type (with the
  // class it was looked up from).
  struct ClassPrim {  // a class's __kanesim annotation: primitive and kind, if given
    bool has_prim = false;
    Prim prim = Prim::None;
    const std::string* kind = nullptr;
  };
  std::unordered_map<const ast::ClassDef*, ClassPrim> primitive_annotation_;
  std::unordered_map<const ast::Component*, std::pair<const ast::ClassDef*, const ast::ClassDef*>> component_type_;
  std::vector<int> end_stack_;  // size of the dimension being subscripted (for `end`)
  // EvalOperators' explicit stacks (lang/elab_operators.cpp), kept between calls.
  struct OpItem {
    const ast::Expr* e;
    bool combine;  // operands already evaluated: their values are on top of op_values_
  };
  std::vector<OpItem> op_work_;
  std::vector<Value> op_values_;
  std::unique_ptr<Node> root_;
  std::vector<std::unique_ptr<ast::StoredDefinition>> override_defs_;  // parsed --set values
  std::vector<std::unique_ptr<ast::Expr>> synthetic_;  // expressions made by the elaborator
  std::vector<SetOverride> sets_;                      // parsed --set overrides
  bool has_subscripted_set_ = false;                   // one of sets_ names an element (j[2].mu)
  std::map<std::string, MeshEntry> meshes_;            // "path\nscale" -> the mesh read (elab_mesh.cpp)
  mutable std::unordered_map<std::uint64_t, flat::SourceLoc> loc_cache_;  // Loc(): (file, offset) -> place
};

// Element `index` (0-based) of `v`, an array value of `count` elements along its first
// dimension (lang/elab_modifiers.cpp).
Value ElementOf(const Value& v, int index, int count);

// "prefix.name", or "name" at the root (lang/elab_instantiate.cpp).
std::string JoinPath(const std::string& prefix, const std::string& name);

// Modelica-style attribute names accepted on variables.
bool IsVarAttribute(const std::string& name);

}  // namespace kanesim::lang::elab
