// Equations of the instance tree: connect() pairs frames and flanges, `x = expr` binds a
// variable (or one element), for- and if-equations are unrolled at elaboration time.
#include <memory>

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

void Elaborator::ProcessEquations(Node* node) {
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
void Elaborator::ProcessEquation(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  if (diags_.Full()) return;
  switch (eq.kind) {
    case ast::EqKind::Connect: return ProcessConnect(node, eq, iters.get());
    case ast::EqKind::For: return ProcessFor(node, eq, iters);
    case ast::EqKind::If: return ProcessIf(node, eq, iters);
    case ast::EqKind::Equality: return ProcessEquality(node, eq, iters);
  }
}

static bool IsConnector(const Node* n) {
  return n->kind == Node::kClass && (n->prim == Prim::Frame || n->prim == Prim::Flange);
}

// connect(a, b): a frame or flange link; arrays of connectors element by element.
void Elaborator::ProcessConnect(Node* node, const ast::Equation& eq, const Iters* iters) {
  Ctx ctx{node, iters};
  Node* a = ResolveNode(*eq.lhs, ctx, nullptr);
  Node* b = ResolveNode(*eq.rhs, ctx, nullptr);
  if (!a || !b) return;
  if (!a->enabled || !b->enabled) return;  // a conditional component that is absent
  if (a->kind == Node::kArray && b->kind == Node::kArray && a->elems.size() == b->elems.size()) {
    for (size_t i = 0; i < a->elems.size(); ++i) {
      Node* x = a->elems[i].get();
      Node* y = b->elems[i].get();
      if (IsConnector(x) && IsConnector(y) && x->prim == y->prim)
        (x->prim == Prim::Frame ? frame_links_ : flange_links_).push_back({x->prim_index, y->prim_index});
    }
    return;
  }
  if (!IsConnector(a) || !IsConnector(b) || a->prim != b->prim) {
    Node* badn = !IsConnector(a) ? a : b;
    auto& d = diags_.Error(DiagCode::BadConnect, (badn == a ? eq.lhs : eq.rhs)->span,
                           !IsConnector(a) || !IsConnector(b) ? "'" + badn->path + "' is not a connector"
                                                              : "cannot connect a Frame to a Flange");
    d.hint = "connect frames (frame_a, frame_b of bodies and joints) or flanges (drive, support)";
    return;
  }
  (a->prim == Prim::Frame ? frame_links_ : flange_links_).push_back({a->prim_index, b->prim_index});
}

// for i in range loop ... end for: the body once per value of the iterator.
void Elaborator::ProcessFor(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  Value r = Eval(*eq.range, Ctx{node, iters.get()});
  if (!r.valid) return;
  if (r.Size() > static_cast<size_t>(kMaxArraySize)) {
    diags_.Error(DiagCode::ArrayTooLarge, eq.range->span, "for-loop range too large");
    return;
  }
  std::vector<double> xs = StructuralList(r, eq.range->span, "a for-loop range");
  std::shared_ptr<Iters> local;
  for (double x : xs) {
    if (!ChargeSteps(1, eq.range->span)) return;
    // The iterators of the last pass are reused unless an equation of it kept them (a
    // binding evaluated later reads its own pass's values).
    if (!local || local.use_count() != 1) local = std::make_shared<Iters>(iters ? *iters : Iters{});
    (*local)[eq.iter] = x;
    for (const auto& b : eq.body) ProcessEquation(node, b, local);
  }
}

// if c1 then ... elseif c2 then ... else ... end if: the first branch whose condition holds.
void Elaborator::ProcessIf(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  Ctx ctx{node, iters.get()};
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
    for (const auto& b : eq.branches[i]) ProcessEquation(node, b, iters);
    return;
  }
}

// variable = expression: the variable's binding (or one element's).
void Elaborator::ProcessEquality(Node* node, const ast::Equation& eq, const std::shared_ptr<const Iters>& iters) {
  if (eq.lhs->kind != ast::ExprKind::Ref) {
    diags_.Error(DiagCode::BadEquation, eq.lhs->span, "equations must have the form 'variable = expression'")
        .hint = "write the variable being defined on the left, e.g. 'j.tau = -k * j.q;'";
    return;
  }
  int elem = -1;
  Node* v = ResolveNode(*eq.lhs, Ctx{node, iters.get()}, &elem);
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
  BindEquation(v, elem, eq, std::move(mv));
}

void Elaborator::BindEquation(Node* v, int elem, const ast::Equation& eq, ModValue mv) {
  if (elem >= 0) {
    auto it = v->eq_elem_binding.find(elem);
    if (it != v->eq_elem_binding.end()) {
      auto& d = diags_.Error(DiagCode::ConflictingEquation, eq.span,
                             "element " + std::to_string(elem + 1) + " of '" + v->path + "' has two equations");
      d.notes.push_back({it->second.span, "first equation here"});
      return;
    }
    v->eq_elem_binding[elem] = std::move(mv);
    return;
  }
  if (v->eq_binding) {
    auto& d = diags_.Error(DiagCode::ConflictingEquation, eq.span, "'" + v->path + "' has two equations");
    d.notes.push_back({v->eq_binding->span, "first equation here"});
    return;
  }
  v->eq_binding = std::move(mv);
}

}  // namespace kanesim::lang::elab
