// Connect: the equations bound and unrolled, connect() pairs found, and their sets made
// identities (lang/elab_connect.h).
#include "lang/elab_connect.h"

#include <memory>

#include "flat/union_find.h"
#include "lang/elab_eval.h"
#include "lang/elab_instantiate.h"

namespace kanesim::lang::elab {

namespace {

// The equations' walk over the instance tree.
class EquationWalker {
 public:
  EquationWalker(Evaluator& eval, Diagnostics& diags) : eval_(eval), diags_(diags) {}
  void ProcessEquations(Node* node);
  Links& Result() { return links_; }

 private:
  void ProcessEquation(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  // One kind each.
  void ProcessConnect(Node* node, const ast::Equation& eq, const Iters* iters);
  void ProcessFor(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  void ProcessIf(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  void ProcessEquality(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters);
  void BindEquation(Node* v, int elem, const ast::Equation& eq, ModValue mv);  // x = ... or x[k] = ...

  Evaluator& eval_;
  Diagnostics& diags_;
  Links links_;
};

void EquationWalker::ProcessEquations(Node* node) {
  if (!node->enabled) return;
  if (node->kind == Node::kArray) {
    for (auto& e : node->elems) ProcessEquations(e.get());
    return;
  }
  if (node->kind != Node::kClass) return;
  for (const auto& src : node->equations) ProcessEquation(node, *src.eq, nullptr);
  for (auto& c : node->children) ProcessEquations(c.get());
}

// One equation of `node` (for- and if-equations: their bodies, recursively).
void EquationWalker::ProcessEquation(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  if (diags_.Full()) return;
  switch (eq.kind) {
    case ast::EqKind::Connect: return ProcessConnect(node, eq, iters.get());
    case ast::EqKind::For: return ProcessFor(node, eq, iters);
    case ast::EqKind::If: return ProcessIf(node, eq, iters);
    case ast::EqKind::Equality: return ProcessEquality(node, eq, iters);
    case ast::EqKind::When: links_.whens.push_back({node, &eq, iters}); return;
    case ast::EqKind::Call:  // the parser makes these only inside a when clause
      diags_.Error(DiagCode::BadEquation, eq.span, "a call statement outside a when clause");
      return;
  }
}

bool IsConnector(const Node* n) {
  return n->kind == Node::kClass && (n->prim == Prim::Frame || n->prim == Prim::Flange);
}

// connect(a, b): a frame or flange link; arrays of connectors element by element.
void EquationWalker::ProcessConnect(Node* node, const ast::Equation& eq, const Iters* iters) {
  Ctx ctx{node, iters};
  Node* a = eval_.ResolveNode(*eq.lhs, ctx, nullptr);
  Node* b = eval_.ResolveNode(*eq.rhs, ctx, nullptr);
  if (!a || !b) return;
  if (!a->enabled || !b->enabled) return;  // a conditional component that is absent
  if (a->kind == Node::kArray && b->kind == Node::kArray && a->elems.size() == b->elems.size()) {
    for (size_t i = 0; i < a->elems.size(); ++i) {
      Node* x = a->elems[i].get();
      Node* y = b->elems[i].get();
      if (IsConnector(x) && IsConnector(y) && x->prim == y->prim)
        (x->prim == Prim::Frame ? links_.frames : links_.flanges).push_back({x->prim_index, y->prim_index});
    }
    return;
  }
  if (!IsConnector(a) || !IsConnector(b) || a->prim != b->prim) {
    Node* badn = !IsConnector(a) ? a : b;
    auto& d = diags_.Error(DiagCode::BadConnect, (badn == a ? eq.lhs : eq.rhs)->span,
                           !IsConnector(a) || !IsConnector(b) ? "'" + badn->Path() + "' is not a connector"
                                                              : "cannot connect a Frame to a Flange");
    d.hint = "connect frames (frame_a, frame_b of bodies and joints) or flanges (drive, support)";
    return;
  }
  (a->prim == Prim::Frame ? links_.frames : links_.flanges).push_back({a->prim_index, b->prim_index});
}

// for i in range loop ... end for: the body once per value of the iterator.
void EquationWalker::ProcessFor(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  Value r = eval_.Eval(*eq.range, Ctx{node, iters.get()});
  if (!r.valid) return;
  if (r.Size() > static_cast<size_t>(kMaxArraySize)) {
    diags_.Error(DiagCode::ArrayTooLarge, eq.range->span, "for-loop range too large");
    return;
  }
  const Evaluator::Numbers xs = eval_.StructuralList(r, eq.range->span, "a for-loop range");
  std::shared_ptr<Iters> local;
  for (double x : xs) {
    if (!eval_.ChargeSteps(1, eq.range->span)) return;
    // The iterators of the last pass are reused unless an equation of it kept them (a
    // binding evaluated later reads its own pass's values).
    if (!local || local.use_count() != 1) local = std::make_shared<Iters>(iters ? *iters : Iters{});
    (*local)[eq.iter] = x;
    for (const auto& b : eq.body) ProcessEquation(node, b, local);
  }
}

// if c1 then ... elseif c2 then ... else ... end if: the first branch whose condition holds.
void EquationWalker::ProcessIf(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  Ctx ctx{node, iters.get()};
  for (size_t i = 0; i < eq.branches.size(); ++i) {
    if (i < eq.conditions.size()) {
      double cv = 0;
      Value c = eval_.Eval(*eq.conditions[i], ctx);
      if (!c.valid) return;
      if (c.type != VType::Boolean) {
        diags_.Error(DiagCode::TypeMismatch, eq.conditions[i]->span, "an if-equation condition must be Boolean");
        return;
      }
      if (!eval_.Structural(c, eq.conditions[i]->span, &cv, "an if-equation condition")) return;
      if (cv == 0) continue;
    }
    for (const auto& b : eq.branches[i]) ProcessEquation(node, b, iters);
    return;
  }
}

// variable = expression: the variable's binding (or one element's).
void EquationWalker::ProcessEquality(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  if (eq.lhs->kind != ast::ExprKind::Ref) {
    diags_.Error(DiagCode::BadEquation, eq.lhs->span, "equations must have the form 'variable = expression'")
        .hint = "write the variable being defined on the left, e.g. 'j.tau = -k * j.q;'";
    return;
  }
  int elem = -1;
  Node* v = eval_.ResolveNode(*eq.lhs, Ctx{node, iters.get()}, &elem);
  if (!v || !v->enabled) return;
  if (v->kind != Node::kVar) {
    diags_.Error(DiagCode::BadEquation, eq.lhs->span, "'" + v->Path() + "' is a component, not a variable");
    return;
  }
  if (v->variability != ast::Variability::None) {
    auto& d = diags_.Error(DiagCode::BadEquation, eq.lhs->span,
                           "'" + v->Path() + "' is a parameter; equations define variables");
    d.hint = "give parameters values in their declaration, with a modifier, or with --set";
    return;
  }
  ModValue mv;
  mv.expr = eq.rhs.get();
  mv.scope = node;
  mv.iters = iters;
  mv.span = eq.span;
  BindEquation(v, elem, eq, std::move(mv));
}

void EquationWalker::BindEquation(Node* v, int elem, const ast::Equation& eq, ModValue mv) {
  if (elem >= 0) {
    auto it = v->eq_elem_binding.find(elem);
    if (it != v->eq_elem_binding.end()) {
      auto& d = diags_.Error(DiagCode::ConflictingEquation, eq.span,
                             "element " + std::to_string(elem + 1) + " of '" + v->Path() + "' has two equations");
      d.notes.push_back({it->second.span, "first equation here"});
      return;
    }
    v->eq_elem_binding[elem] = std::move(mv);
    return;
  }
  if (v->eq_binding) {
    auto& d = diags_.Error(DiagCode::ConflictingEquation, eq.span, "'" + v->Path() + "' has two equations");
    d.notes.push_back({v->eq_binding->span, "first equation here"});
    return;
  }
  v->eq_binding = std::move(mv);
}

}  // namespace

Links BindEquations(Node* root, Evaluator& eval, Diagnostics& diags) {
  EquationWalker walker(eval, diags);
  walker.ProcessEquations(root);
  return std::move(walker.Result());
}

// Each connect() set of frames becomes one flat frame, in the order of the frames' ids.
Connections Connect(const InstanceTree& tree, const Links& links, const SourcePlaces& places, flat::Mechanism* m) {
  const size_t n = tree.frames.size();
  flat::UnionFind uf(n);
  for (auto [a, b] : links.frames) uf.Unite(a, b);
  Connections out;
  out.frame.assign(n, -1);
  std::vector<int> set_size(n, 0);  // per set root
  for (size_t i = 0; i < n; ++i) set_size[static_cast<size_t>(uf.Find(static_cast<int>(i)))]++;
  for (size_t i = 0; i < n; ++i) {
    const size_t r = static_cast<size_t>(uf.Find(static_cast<int>(i)));
    if (out.frame[r] < 0) {
      out.frame[r] = static_cast<int>(m->frames.size());
      flat::Frame f;
      const Node* first = tree.frames[r];
      f.name = first->Path();
      f.loc = places.Loc(first->decl ? first->decl->name_span : Span{});
      m->frames.push_back(std::move(f));
    }
    out.frame[i] = out.frame[r];
    flat::Frame& f = m->frames[static_cast<size_t>(out.frame[i])];
    f.aliases.push_back(i == r ? f.name : tree.frames[i]->Path());  // the first's path is the name
  }
  out.frame_set_size.resize(n);
  for (size_t i = 0; i < n; ++i) out.frame_set_size[i] = set_size[static_cast<size_t>(uf.Find(static_cast<int>(i)))];
  flat::UnionFind fu(tree.flanges.size());
  for (auto [a, b] : links.flanges) fu.Unite(a, b);
  out.flange_set.resize(tree.flanges.size());
  for (size_t i = 0; i < tree.flanges.size(); ++i) out.flange_set[i] = fu.Find(static_cast<int>(i));
  return out;
}

}  // namespace kanesim::lang::elab
