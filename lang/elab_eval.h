// Evaluate, the elaborator's phase that gives expressions their values: AST expressions
// become Values, arrays of scalar expressions in the mechanism's pool (parameters stay
// symbolic Param nodes so that a sweep can change them without elaborating again;
// constants fold). It is asked on demand by the other phases (array sizes and conditions
// while instantiating, for-ranges and subscripts while connecting, primitives' fields
// while emitting), and evaluates a variable once, on first use, from its binding (GetVar),
// making a parameter's flat parameters then. Its files: lang/elab_eval.cpp (expressions
// and references), elab_vars.cpp (variables and instance references), elab_operators.cpp,
// elab_builtins.cpp, elab_concat.cpp, elab_mesh.cpp and elab_budget.cpp (the bounds).
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "lang/elab_budget.h"
#include "lang/elab_internal.h"
#include "flat/param_eval.h"
#include "geometry/mesh_check.h"
#include "geometry/tri_mesh.h"

namespace kanesim::lang::elab {

class Evaluator {
 public:
  // Writes the pool, the parameters, state references and data files of `m`.
  Evaluator(flat::Mechanism* m, const SourcePlaces& places, Diagnostics& diags);

  // --- what the other phases ask ---
  Value Eval(const ast::Expr& e, const Ctx& ctx);
  // A modifier's or equation's value; *where (if given) gets the span it was written at.
  Value EvalModValue(const ModValue& mv, Span* where);
  // The variable's value, evaluated on first use; valid as long as the instance tree.
  const Value& GetVar(Node* var, Span use_span);
  // Resolves a reference to an instance node; for variables with subscripts, *elem gets
  // the flat element index (or -1 for the whole variable). Null after a diagnostic.
  Node* ResolveNode(const ast::Expr& ref, const Ctx& ctx, int* elem);
  // Evaluates to a number at elaboration time (array sizes, conditions, for ranges,
  // subscripts); marks the parameters it reads as structural.
  bool Structural(const Value& v, Span span, double* out, const char* what);
  bool StructuralInt(const Value& v, Span span, long* out, const char* what);
  // StructuralInt(Eval(e, ...)) for an integer literal `e` (array sizes: Real r[3], nearly
  // all of them), read from the syntax: the same pool node and the same charge to the work
  // budget, no Value. False, with nothing done, for any other expression, and where the
  // evaluation would refuse (budget or depth used up): then evaluate it.
  bool LiteralStructuralInt(const ast::Expr& e, long* out);
  // The values of an array of structural numbers (subscripts, ranges): a few inline.
  using Numbers = SmallVec<double, 4>;
  Numbers StructuralList(const Value& v, Span span, const char* what);
  // Work budget: false once the elaboration has used it up. Inline: charged for every value
  // made; the report when it runs out is StepsRanOut's (elab_budget.cpp).
  bool ChargeSteps(std::int64_t steps, Span where) {
    if (budget_.Spend(steps)) return ChargeNodes(0, where);
    return StepsRanOut(where);
  }
  // Whether the work budget ran out (reported once): the other phases stop then.
  bool OverBudget() const { return budget_reported_; }
  // Room for `n` parameters, made once instead of by doubling (each step moving every Param).
  void ReserveParams(size_t n);
  // `file` resolved against the directory of the source file `origin` is in.
  std::string MeshPath(const std::string& file, Span origin) const;
  // Where data files are read from instead (ElaborateOptions::data_files); null: as named.
  void ReadDataFrom(const std::map<std::string, std::string>* files) { data_from_ = files; }
  // Where an argument's value was written: follows references to the binding they take
  // their value from (a MeshBody's `file` to the user's `file = "..."`).
  Span ValueOrigin(const ast::Expr& arg, const Ctx& ctx);

  // Inside a when clause (lang/elab_when.cpp): pre(x) is read there only.
  void SetInWhen(bool on) { in_when_ = on; }
  bool InWhen() const { return in_when_; }

  // --- for the lowerings of built-in functions (elab_builtins.cpp, elab_concat.cpp) ---
  Value Const(double x, VType t = VType::Real);
  Value Scalar(ExprId e, VType t = VType::Real);
  Value Elementwise2(const Value& a, const Value& b, flat::Op op, VType rt, Span sp);
  Value EvalCat(const ast::Expr& e, const std::vector<Value>& args);
  // meshVolume / meshCentre / meshInertia(file, scale).
  Value EvalMeshCall(const std::string& fn, const ast::Expr& e, const std::vector<Value>& args, const Ctx& ctx);

 private:
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
  // One subscript of dimension `size`: its 0-based indices appended to *list; *keep when it
  // keeps the dimension.
  using SubscriptList = SmallVec<int, 16>;
  bool SubscriptIndices(const ast::Expr& s, int size, const Node* var, const Ctx& ctx, SubscriptList* list,
                        bool* keep);
  Value EvalArray(const ast::Expr& e, const Ctx& ctx);
  Value EvalComprehension(const ast::Expr& e, const Ctx& ctx);
  Value EvalMatrix(const ast::Expr& e, const Ctx& ctx);
  Value EvalRange(const ast::Expr& e, const Ctx& ctx);
  Value EvalIf(const ast::Expr& e, const Ctx& ctx);
  // Built-in functions (elab_builtins.cpp): one table {name, arity, lowering}.
  Value EvalCall(const ast::Expr& e, const Ctx& ctx);
  // Concatenation (elab_concat.cpp): cat(k, ...), and EvalMatrix above.
  Value Concatenate(size_t k, const std::vector<Value>& parts, const std::vector<Span>& spans,
                    const std::vector<std::string>& names, Span whole, const std::string& what,
                    const std::string& hint);
  // Operators (elab_operators.cpp): chains of them with an explicit stack.
  Value EvalOperators(const ast::Expr& root, const Ctx& ctx);
  Value UnaryOp(const ast::Expr& e, Value v);
  Value BinaryOp(const ast::Expr& e, const Value& a, const Value& b);
  Value MatrixProduct(const ast::Expr& e, const Value& a, const Value& b);
  Value Comparison(const ast::Expr& e, const Value& a, const Value& b);
  // Work budget (the reports in elab_budget.cpp). False once the pool would pass kMaxExprNodes.
  bool ChargeNodes(std::int64_t more, Span where) {
    if (static_cast<std::int64_t>(m_->exprs.size()) + more <= kMaxExprNodes) return true;
    return NodesRanOut(where);
  }
  bool Charge(const Value& v, Span where) {
    return ChargeSteps(static_cast<std::int64_t>(v.elements.size()) + 1, where);
  }
  bool StepsRanOut(Span where);  // ChargeSteps's report, once; false
  bool NodesRanOut(Span where);  // ChargeNodes's report, once; false
  // GetVar's stages (elab_vars.cpp): the value from the binding, checked, then for a
  // parameter its flat parameters.
  Value EvaluateVar(Node* var, Span use_span);
  Value JointStateValue(Node* var);
  // A top-level `input` without a value: one flat::Input per element (Op::Input nodes).
  Value InputValue(Node* var, Span use_span);                       // a joint's q or u: state references
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
  ExprId AddParamElement(Node* var, flat::Param& p, std::string_view name, ExprId x, Span value_span);
  void MarkStructural(ExprId id);

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
  // Reads (once) and reports its problems at `where` (once per place); null when unusable.
  const MeshEntry* LoadMeshFor(const std::string& path, double scale, Span where);

  flat::Mechanism* m_;
  const SourcePlaces& places_;
  Diagnostics& diags_;
  std::vector<double> pvals_;  // values of m_->params, index-aligned
  flat::ParamEvaluator param_eval_{m_->exprs, pvals_};  // memoized values of pool nodes
  std::vector<std::uint8_t> structural_seen_;  // per pool node: walked by MarkStructural
  std::vector<ExprId> structural_stack_;        // MarkStructural's scratch
  WorkBudget budget_{kMaxElabWork};
  bool budget_reported_ = false;
  bool in_when_ = false;  // SetInWhen
  int eval_depth_ = 0;  // EvalNested frames on the native stack
  StackGuard stack_;    // made with the Evaluator: the base of its evaluation
  bool depth_reported_ = false;
  std::vector<int> end_stack_;  // size of the dimension being subscripted (for `end`)
  std::string path_scratch_;    // ParameterValue's variable path, kept between calls
  // EvalOperators' explicit stacks (lang/elab_operators.cpp), kept between calls.
  struct OpItem {
    const ast::Expr* e;
    bool combine;  // operands already evaluated: their values are on top of op_values_
  };
  std::vector<OpItem> op_work_;
  std::vector<Value> op_values_;
  std::map<std::string, MeshEntry> meshes_;
  const std::map<std::string, std::string>* data_from_ = nullptr;  // "path\nscale" -> the mesh read (elab_mesh.cpp)
};

}  // namespace kanesim::lang::elab
