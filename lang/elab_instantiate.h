// Instantiate, the elaborator's phase that builds the instance tree: the model's class
// becomes a tree of instance nodes. Extends copies the base's elements and equations; each
// element gets a node with its merged modifier (lang/elab_modifiers.h); arrays of
// components get one node per element (element 1's tree shared when provably the same,
// lang/elab_share.cpp), and so do scalar components of one class side by side, modified
// alike (the first one's tree); conditional components are dropped when false. Array sizes and
// conditions are asked of the evaluator. Frames, flanges and joints get their ids here,
// in the order of instantiation. Files: lang/elab_instantiate.cpp, elab_share.cpp.
#pragma once

#include <deque>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

class ClassLookup;
class Evaluator;

// The instance tree and its primitives' ids.
struct InstanceTree {
  NodeArena arena;  // before root: the nodes end before their memory
  NodePtr root;
  std::vector<Node*> frames;        // provisional frame id (Node::prim_index) -> its Frame node
  std::vector<Node*> flanges;       // flange id -> its Flange node
  std::vector<flat::Joint> joints;  // joint id -> the joint as far as instantiation knows it (name, type, place)
  long instances = 0;               // scalar variables' elements + components
  int copies = 0;                   // ids given to class nodes of array elements copied from element 1
  std::deque<Mod> decl_mods;        // modifiers shared by every instance of a declaration (Node::mod_from_decl)
};

class Instantiator {
 public:
  // `subscripted_sets`: a --set names an array element (bound after instantiation), so no
  // element may share its variables' modifiers with element 1, and no component is a copy
  // of a sibling. `share_siblings` (ElaborateOptions): siblings may be copies.
  Instantiator(const ClassLookup& lookup, Evaluator& eval, const SourcePlaces& places, Diagnostics& diags,
               bool subscripted_sets, bool share_siblings, InstanceTree* tree);
  // Instantiates `top` into tree->root (made by the caller, holding the --set modifiers).
  void Run(const ast::ClassDef* top);

 private:
  struct Collected {
    const ast::Component* comp;
    const ast::ClassDef* owner;
    Mod ext_mod;
    bool is_final = false, replaceable = false;
  };
  // `names` indexes `out` by element name (the AST owns the names), so that a class of n
  // elements is collected in O(n), not O(n^2) (issue 38: 123 000 parameters). A class of a
  // few elements (nearly every instance) is scanned instead: no hash node per element.
  class CollectedNames {
   public:
    // The index of the element named `name` in `out`, or -1.
    long Find(std::string_view name, const std::vector<Collected>& out) const;
    // After out.push_back: the new last element is indexed (once out is past kScan).
    void Added(const std::vector<Collected>& out);
    // Set by Instantiate when the class's elements are known to have distinct names and no
    // redeclare (its first instance found so): Collect then asks Find nothing per element.
    bool known_distinct = false;
    // Set by Collect when an element repeats a name or is a redeclare.
    bool repeated = false;

   private:
    static constexpr size_t kScan = 32;
    std::unordered_map<std::string_view, size_t> index_;
  };
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
  // Lookups that depend on the class alone, made once per class rather than per instance.
  struct ClassPrim {  // a class's __kanesim annotation: primitive and kind, if given
    bool has_prim = false;
    Prim prim = Prim::None;
    const std::string* kind = nullptr;
  };

  void Instantiate(Node* node, const ast::ClassDef* cls);
  void Collect(const ast::ClassDef* cls, Node* node, const Mod* ext_mod, std::vector<Collected>& out,
               CollectedNames& names, std::vector<Node::EqSource>& eqs, int depth);
  void CheckOuterModifiers(Node* node, const ast::ClassDef* cls, const std::vector<Collected>& elems,
                           const CollectedNames& names);
  const ClassPrim& PrimitiveAnnotation(const ast::ClassDef* cls);
  NodePtr MakeChild(Node* node, Collected& c);
  const Mod* DeclarationMod(Node* node, const ast::Component& comp);
  void Expand(Node* node, Node* child, const Collected& c);
  // Expand's steps.
  bool ComponentEnabled(Node* node, Node* child, const ast::Component& comp);  // its condition
  void AppendDims(const std::vector<ast::ExprPtr>& ds, Node* node, Dims* dims);
  bool ResolveComponentType(Node* node, Node* child, const Collected& c, ComponentType* t);
  bool ApplyRedeclare(Node* child, const Collected& c, ComponentType* t);
  const ast::ClassDef* DeclaredClass(const ast::Component& comp, const ast::ClassDef* owner);
  void ReportUnknownType(const ast::Component& comp, const ComponentType& t);
  bool ShortTypeToBuiltin(Node* node, Node* child, const ast::Component& comp, ComponentType* t);
  void ExpandVariable(Node* child, const ast::Component& comp, VType builtin, const Dims& dims);
  void CheckVarAttributes(Node* var, VType builtin);
  void ExpandComponent(Node* node, Node* child, const Collected& c, const ComponentType& t,
                       const Dims& dims);
  void RegisterPrimitive(Node* node, const ast::ClassDef* cls);
  const ast::ClassDef* ResolveShort(const ast::ClassDef* cls, Node* node, Mod* mod);
  bool TooLarge() const;  // past kMaxInstances, or the evaluator over its work budget

  // Arrays of components (elab_share.cpp): element 1 instantiated, the others bound
  // copies of it when that is provably the same, else instantiated each.
  void InstantiateArray(Node* node, Node* array, const ast::Component& comp, const ast::ClassDef* tcls, int n);
  struct ShareBinding;
  struct ArrayShare;
  void InstantiateFirst(Node* el, const ast::ClassDef* tcls, ArrayShare* share);
  bool ShareElement(const ArrayShare& share, Node* node, Node* array, const std::string& name, int index, int count);
  NodePtr CloneInstance(const Node& src, Node* parent, const std::string& name, ShareBinding& b);
  void CloneInto(Node* n, const Node& src, ShareBinding& b, bool root);
  Mod BoundCopy(const Mod& src, ShareBinding& b, bool with_sub);
  bool SameInEveryElement(const Mod& m, const ShareBinding& b) const;

  // Scalar components (elab_share.cpp): a component of class `cls` whose modifier has the
  // form of an earlier sibling's (same keys, values in the same places) is a copy of that
  // sibling's tree holding its own values, when that is provably the same; else instantiated.
  void InstantiateScalar(Node* node, Node* child, const ast::ClassDef* cls);
  struct SiblingShare;
  // (parent node, class, the modifier's form) -> the first sibling of that form.
  using SiblingKey = std::tuple<const Node*, const ast::ClassDef*, std::string>;
  std::map<SiblingKey, std::shared_ptr<SiblingShare>> siblings_;  // shared: SiblingShare is incomplete here

  const ClassLookup& lookup_;
  Evaluator& eval_;
  const SourcePlaces& places_;
  Diagnostics& diags_;
  const bool subscripted_sets_;
  const bool share_siblings_;
  InstanceTree& tree_;
  bool too_large_ = false;  // past kMaxInstances (reported once)
  std::vector<const ast::ClassDef*> extends_stack_;
  std::unordered_map<const ast::ClassDef*, ClassPrim> primitive_annotation_;
  // Per class: its collected elements have distinct names and none is a redeclare (what the
  // elements are depends on the class alone, so its first instance tells for all).
  std::unordered_map<const ast::ClassDef*, bool> distinct_elements_;
  // A component's declared type, with the class it was looked up from.
  std::unordered_map<const ast::Component*, std::pair<const ast::ClassDef*, const ast::ClassDef*>> component_type_;
  // DeclarationMod's: per declaration, its shared modifier (null: not shareable).
  std::unordered_map<const ast::Component*, const Mod*> decl_mods_;
  // CheckVarAttributes': the shared modifiers (Node::shared_mod) already found to name
  // attributes only, checked once instead of in every instance that shares them.
  std::unordered_set<const Mod*> attributes_ok_;
};

}  // namespace kanesim::lang::elab
