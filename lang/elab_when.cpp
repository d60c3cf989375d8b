// When clauses (docs/events.md): the condition of each clause becomes indicators over time
// and state whose upward zero crossings fire it, and its statements become reinit targets
// and values or terminate's message (flat::WhenClause).
#include <string>
#include <utility>
#include <vector>

#include "lang/elab_connect.h"
#include "lang/elab_emit.h"
#include "lang/elab_eval.h"

namespace kanesim::lang::elab {

using flat::ExprId;
using flat::Op;

namespace {

// Boolean operators nested deeper than this in one condition are refused (the conversion
// recurses over them).
constexpr int kMaxConditionDepth = 64;

class WhenEmitter {
 public:
  WhenEmitter(Evaluator& eval, const SourcePlaces& places, Diagnostics& diags, flat::Mechanism* m)
      : eval_(eval), places_(places), diags_(diags), m_(m), pool_(m->exprs) {}

  void Clause(const PendingWhen& w) {
    const ast::Equation& eq = *w.eq;
    const Ctx ctx{w.scope, w.iters.get()};
    flat::WhenClause out;
    out.loc = places_.Loc(eq.span);
    eval_.SetInWhen(true);
    // when {c1, c2, ...}: fires where any of them becomes true (Modelica's vector form).
    const ast::Expr& cond = *eq.conditions[0];
    bool ok = true;
    if (cond.kind == ast::ExprKind::Array) {
      for (const auto& c : cond.args) ok = Condition(*c, ctx, &out.indicators) && ok;
    } else {
      ok = Condition(cond, ctx, &out.indicators);
    }
    for (const ast::Equation& st : eq.body) ok = Statement(st, ctx, &out) && ok;
    eval_.SetInWhen(false);
    if (ok) m_->whens.push_back(std::move(out));
  }

 private:
  // One condition: b, edge(b) (the same: a clause fires where b becomes true) or change(b)
  // (b's indicator and its negation: fires where b becomes true or false).
  bool Condition(const ast::Expr& c, const Ctx& ctx, std::vector<ExprId>* indicators) {
    const ast::Expr* b = &c;
    bool change = false;
    if (c.kind == ast::ExprKind::Call && c.parts.size() == 1 &&
        (c.parts[0].name == "edge" || c.parts[0].name == "change")) {
      if (c.args.size() != 1 || !c.named_args.empty()) {
        diags_.Error(DiagCode::BadCall, c.span, "'" + c.parts[0].name + "' takes 1 argument");
        return false;
      }
      change = c.parts[0].name == "change";
      b = c.args[0].get();
    }
    Value v = eval_.Eval(*b, ctx);
    if (!v.valid) return false;
    if (v.type != VType::Boolean || v.elements.size() != 1) {
      diags_.Error(DiagCode::TypeMismatch, b->span, "a when condition must be one Boolean")
          .hint = "compare a signal with a value, e.g. 'when j.q < 0 then'";
      return false;
    }
    const ExprId h = Indicator(v.elements[0], b->span, 0);
    if (h == flat::kNoExpr) return false;
    indicators->push_back(h);
    if (change) indicators->push_back(pool_.Unary(Op::Neg, h));
    return true;
  }

  // The indicator of Boolean expression e: positive exactly where e holds (a relation's
  // equality edge aside, which is where the event is). kNoExpr after a diagnostic.
  ExprId Indicator(ExprId e, Span where, int depth) {
    if (depth > kMaxConditionDepth) {
      diags_.Error(DiagCode::BadEquation, where, "a when condition nests 'and', 'or' and 'not' too deeply");
      return flat::kNoExpr;
    }
    const flat::ExprNode n = pool_[e];
    switch (n.op) {
      case Op::Gt:
      case Op::Ge: return pool_.Binary(Op::Sub, n.a, n.b);
      case Op::Lt:
      case Op::Le: return pool_.Binary(Op::Sub, n.b, n.a);
      case Op::Const: return pool_.Constant(n.value != 0.0 ? 1.0 : -1.0);
      case Op::Param: return pool_.IfElse(e, pool_.Constant(1.0), pool_.Constant(-1.0));
      case Op::Not: {
        const ExprId a = Indicator(n.a, where, depth + 1);
        return a == flat::kNoExpr ? a : pool_.Unary(Op::Neg, a);
      }
      case Op::And:
      case Op::Or: {
        const ExprId a = Indicator(n.a, where, depth + 1);
        const ExprId b = a == flat::kNoExpr ? a : Indicator(n.b, where, depth + 1);
        return b == flat::kNoExpr ? b : pool_.Binary(n.op == Op::And ? Op::Min : Op::Max, a, b);
      }
      default: break;
    }
    diags_.Error(DiagCode::BadEquation, where,
                 std::string("a when condition cannot use '") + flat::OpSpelling(n.op) +
                     "': an event is located where a relation's two sides cross")
        .hint = "build the condition of <, <=, >, >= joined by and, or, not";
    return flat::kNoExpr;
  }

  bool Statement(const ast::Equation& st, const Ctx& ctx, flat::WhenClause* out) {
    if (st.kind != ast::EqKind::Call) {
      diags_.Error(DiagCode::BadEquation, st.span, "a when clause holds reinit(...) and terminate(...) only")
          .hint = "kanesim has no discrete variables; set a joint's coordinate or speed with reinit(j.u, expr)";
      return false;
    }
    const ast::Expr& call = *st.lhs;
    const std::string fn = call.kind == ast::ExprKind::Call && call.parts.size() == 1 ? call.parts[0].name : "";
    if (fn == "reinit") return Reinit(call, ctx, out);
    if (fn == "terminate") return Terminate(call, out);
    diags_.Error(DiagCode::BadEquation, call.span, "a when clause holds reinit(...) and terminate(...) only");
    return false;
  }

  // reinit(j.u, expr) or reinit(j.q[k], expr): a joint's speed or coordinate.
  bool Reinit(const ast::Expr& call, const Ctx& ctx, flat::WhenClause* out) {
    if (call.args.size() != 2 || !call.named_args.empty()) {
      diags_.Error(DiagCode::BadCall, call.span, "'reinit' takes 2 arguments: reinit(j.u, expr)");
      return false;
    }
    Value x = eval_.Eval(*call.args[0], ctx);
    Value v = eval_.Eval(*call.args[1], ctx);
    if (!x.valid || !v.valid) return false;
    const bool state = x.elements.size() == 1 && pool_[x.elements[0]].op == Op::State;
    const flat::StateRef* ref = state ? &m_->state_refs[static_cast<size_t>(pool_[x.elements[0]].index)] : nullptr;
    if (!ref || (ref->kind != flat::StateKind::JointQ && ref->kind != flat::StateKind::JointU)) {
      diags_.Error(DiagCode::BadCall, call.args[0]->span,
                   "reinit sets a joint's coordinate or speed (j.q, j.u, j.q[k], j.u[k]), one element")
          .hint = "a frame's position or velocity follows from the joints' q and u";
      return false;
    }
    if (v.type == VType::String || v.elements.size() != 1) {
      diags_.Error(DiagCode::TypeMismatch, call.args[1]->span, "reinit's value must be one number");
      return false;
    }
    const std::int32_t target = pool_[x.elements[0]].index;
    for (const flat::Reinit& r : out->reinits)
      if (r.state_ref == target) {
        diags_.Error(DiagCode::ConflictingEquation, call.span,
                     "'" + m_->StateRefName(*ref) + "' is reinit'ed twice in one when clause");
        return false;
      }
    out->reinits.push_back({target, v.elements[0], places_.Loc(call.span)});
    return true;
  }

  // terminate("why"): the message is a string literal.
  bool Terminate(const ast::Expr& call, flat::WhenClause* out) {
    if (call.args.size() != 1 || call.args[0]->kind != ast::ExprKind::String) {
      diags_.Error(DiagCode::BadCall, call.span, "'terminate' takes one string: terminate(\"why\")");
      return false;
    }
    out->terminate = true;
    out->message = call.args[0]->text;
    return true;
  }

  Evaluator& eval_;
  const SourcePlaces& places_;
  Diagnostics& diags_;
  flat::Mechanism* m_;
  flat::ExprPool& pool_;
};

}  // namespace

void EmitWhens(const std::vector<PendingWhen>& whens, Evaluator& eval, const SourcePlaces& places,
               Diagnostics& diags, flat::Mechanism* m) {
  WhenEmitter emitter(eval, places, diags, m);
  for (const PendingWhen& w : whens) {
    if (diags.Full()) return;
    emitter.Clause(w);
  }
}

}  // namespace kanesim::lang::elab
