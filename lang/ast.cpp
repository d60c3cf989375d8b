#include "lang/ast.h"

#include <cstdio>
#include <sstream>

#include "lang/lexer.h"

namespace kanesim::lang::ast {

std::string JoinName(const std::vector<std::string>& parts) {
  std::string s;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i) s += '.';
    s += parts[i];
  }
  return s;
}

Expr::~Expr() {
  // Children are moved onto a heap stack before their parent goes, so each node is
  // destroyed with no children left: no recursion, whatever the depth.
  std::vector<ExprPtr> pending;
  auto take = [&pending](ExprPtr& c) {
    if (c) pending.push_back(std::move(c));
  };
  ForEachChild(*this, take);
  while (!pending.empty()) {
    ExprPtr e = std::move(pending.back());
    pending.pop_back();
    ForEachChild(*e, take);
  }
}

// Copies everything of `from` but its children; each child slot of `to` gets a fresh
// empty node (or stays null), for the caller to fill.
static void CopyNode(const Expr& from, Expr* to) {
  to->kind = from.kind;
  to->span = from.span;
  to->number = from.number;
  to->is_integer = from.is_integer;
  to->text = from.text;
  to->op = from.op;
  to->depth = from.depth;
  for (const auto& p : from.parts) {
    RefPart q;
    q.name = p.name;
    q.span = p.span;
    q.subscripts.resize(p.subscripts.size());
    to->parts.push_back(std::move(q));
  }
  to->args.resize(from.args.size());
  for (const auto& n : from.named_args) to->named_args.push_back({n.name, nullptr, n.span});
  for (const auto& r : from.rows) to->rows.emplace_back(r.size());
}

ExprPtr Clone(const Expr& root) {
  auto out = std::make_unique<Expr>();
  std::vector<std::pair<const Expr*, Expr*>> todo{{&root, out.get()}};
  std::vector<const Expr*> from_children;
  while (!todo.empty()) {
    auto [from, to] = todo.back();
    todo.pop_back();
    CopyNode(*from, to);
    from_children.clear();
    ForEachChild(*from, [&](const ExprPtr& c) { from_children.push_back(c.get()); });
    size_t i = 0;
    ForEachChild(*to, [&](ExprPtr& c) {
      const Expr* src = from_children[i++];
      if (!src) return;
      c = std::make_unique<Expr>();
      todo.push_back({src, c.get()});
    });
  }
  return out;
}

namespace {

// The expression printer works from an explicit stack of pieces, each either text to
// write or a node to expand, so that chains of any length print without recursion.
struct Piece {
  const Expr* node = nullptr;  // expand this node, or, if null, write `text`
  std::string text;
};

std::string NumberText(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);  // as an ostream with precision(17)
  return buffer;
}

void AppendRef(const std::vector<RefPart>& parts, std::vector<Piece>* out) {
  for (size_t i = 0; i < parts.size(); ++i) {
    out->push_back({nullptr, (i ? "." : "") + parts[i].name});
    if (parts[i].subscripts.empty()) continue;
    out->push_back({nullptr, "["});
    for (size_t k = 0; k < parts[i].subscripts.size(); ++k) {
      if (k) out->push_back({nullptr, ", "});
      out->push_back({parts[i].subscripts[k].get(), ""});
    }
    out->push_back({nullptr, "]"});
  }
}

void AppendList(const std::vector<ExprPtr>& xs, const char* sep, std::vector<Piece>* out) {
  for (size_t i = 0; i < xs.size(); ++i) {
    if (i) out->push_back({nullptr, sep});
    out->push_back({xs[i].get(), ""});
  }
}

// The pieces of one node, in output order.
void Expand(const Expr& e, std::vector<Piece>* out) {
  auto text = [out](std::string s) { out->push_back({nullptr, std::move(s)}); };
  auto node = [out](const ExprPtr& x) { out->push_back({x.get(), ""}); };
  switch (e.kind) {
    case ExprKind::Number: text(NumberText(e.number)); break;
    case ExprKind::String: text('"' + e.text + '"'); break;
    case ExprKind::Bool: text(e.number != 0 ? "true" : "false"); break;
    case ExprKind::Ref: AppendRef(e.parts, out); break;
    case ExprKind::Call:
      AppendRef(e.parts, out);
      text("(");
      AppendList(e.args, ", ", out);
      for (size_t i = 0; i < e.named_args.size(); ++i) {
        text(std::string(i || !e.args.empty() ? ", " : "") + e.named_args[i].name + " = ");
        node(e.named_args[i].value);
      }
      text(")");
      break;
    case ExprKind::Array:
      text("{");
      AppendList(e.args, ", ", out);
      text("}");
      break;
    case ExprKind::Comprehension:
      text("{");
      node(e.args[0]);
      text(" for " + e.text + " in ");
      node(e.args[1]);
      text("}");
      break;
    case ExprKind::Matrix:
      text("[");
      for (size_t r = 0; r < e.rows.size(); ++r) {
        if (r) text("; ");
        AppendList(e.rows[r], ", ", out);
      }
      text("]");
      break;
    case ExprKind::Range:
      text("(");
      AppendList(e.args, ":", out);
      text(")");
      break;
    case ExprKind::Colon: text(":"); break;
    case ExprKind::End: text("end"); break;
    case ExprKind::Unary:
      text(std::string("(") + TokSpelling(static_cast<Tok>(e.op)) + (e.op == static_cast<int>(Tok::KwNot) ? " " : ""));
      node(e.args[0]);
      text(")");
      break;
    case ExprKind::Binary:
      text("(");
      node(e.args[0]);
      text(std::string(" ") + TokSpelling(static_cast<Tok>(e.op)) + " ");
      node(e.args[1]);
      text(")");
      break;
    case ExprKind::If:
      text("(if ");
      for (size_t i = 0; i + 1 < e.args.size(); i += 2) {
        if (i) text(" elseif ");
        node(e.args[i]);
        text(" then ");
        node(e.args[i + 1]);
      }
      text(" else ");
      node(e.args.back());
      text(")");
      break;
  }
}

}  // namespace

std::string DumpExpr(const Expr& root) {
  std::string s;
  std::vector<Piece> stack{{&root, ""}};
  std::vector<Piece> pieces;
  while (!stack.empty()) {
    Piece p = std::move(stack.back());
    stack.pop_back();
    if (!p.node) {
      s += p.text;
      continue;
    }
    pieces.clear();
    Expand(*p.node, &pieces);
    for (auto it = pieces.rbegin(); it != pieces.rend(); ++it) {
      if (it->node || !it->text.empty()) stack.push_back(std::move(*it));
    }
  }
  return s;
}

static void DumpMod(const Modification* m, std::ostringstream& os) {
  if (!m) return;
  if (m->has_args) {
    os << '(';
    for (size_t i = 0; i < m->args.size(); ++i) {
      const Argument& a = m->args[i];
      if (i) os << ", ";
      if (a.redeclare) os << "redeclare " << a.redeclare_type << ' ';
      if (a.each) os << "each ";
      if (a.is_final) os << "final ";
      os << JoinName(a.path);
      DumpMod(a.mod.get(), os);
    }
    os << ')';
  }
  if (m->value) os << " = " << DumpExpr(*m->value);
}

static const char* KindName(ClassKind k) {
  switch (k) {
    case ClassKind::Model: return "model";
    case ClassKind::Package: return "package";
    case ClassKind::Connector: return "connector";
    case ClassKind::Record: return "record";
    case ClassKind::Block: return "block";
    case ClassKind::Class: return "class";
    case ClassKind::Type: return "type";
    case ClassKind::Function: return "function";
  }
  return "?";
}

static void DumpEquations(const std::vector<Equation>& eqs, std::ostringstream& os, const std::string& ind) {
  for (const auto& eq : eqs) {
    switch (eq.kind) {
      case EqKind::Equality:
        os << ind << DumpExpr(*eq.lhs) << " = " << DumpExpr(*eq.rhs) << ";\n";
        break;
      case EqKind::Connect:
        os << ind << "connect(" << DumpExpr(*eq.lhs) << ", " << DumpExpr(*eq.rhs) << ");\n";
        break;
      case EqKind::For:
        os << ind << "for " << eq.iter << " in " << DumpExpr(*eq.range) << " loop\n";
        DumpEquations(eq.body, os, ind + "  ");
        os << ind << "end for;\n";
        break;
      case EqKind::If:
        for (size_t i = 0; i < eq.branches.size(); ++i) {
          if (i < eq.conditions.size())
            os << ind << (i ? "elseif " : "if ") << DumpExpr(*eq.conditions[i]) << " then\n";
          else
            os << ind << "else\n";
          DumpEquations(eq.branches[i], os, ind + "  ");
        }
        os << ind << "end if;\n";
        break;
      case EqKind::When:
        os << ind << "when " << DumpExpr(*eq.conditions[0]) << " then\n";
        DumpEquations(eq.body, os, ind + "  ");
        os << ind << "end when;\n";
        break;
      case EqKind::Call:
        os << ind << DumpExpr(*eq.lhs) << ";\n";
        break;
    }
  }
}

static void DumpClass(const ClassDef& c, std::ostringstream& os, const std::string& ind) {
  os << ind << (c.partial ? "partial " : "") << KindName(c.kind) << ' ' << c.name;
  if (c.is_short) {
    os << " = " << JoinName(c.short_base);
    DumpMod(c.short_mod.get(), os);
    os << ";\n";
    return;
  }
  if (!c.description.empty()) os << " \"" << c.description << '"';
  os << '\n';
  for (const auto& el : c.elements) {
    switch (el.kind) {
      case Element::kImport:
        os << ind << "  import " << (el.import->alias.empty() ? "" : el.import->alias + " = ")
           << JoinName(el.import->name) << (el.import->wildcard ? ".*" : "") << ";\n";
        break;
      case Element::kExtends:
        os << ind << "  extends " << JoinName(el.extends->base);
        DumpMod(el.extends->mod.get(), os);
        os << ";\n";
        break;
      case Element::kClass: DumpClass(*el.class_def, os, ind + "  "); break;
      case Element::kComponent: {
        const Component& k = *el.component;
        os << ind << "  ";
        if (k.is_protected) os << "protected ";
        if (k.redeclare) os << "redeclare ";
        if (k.is_final) os << "final ";
        if (k.replaceable) os << "replaceable ";
        if (k.variability == Variability::Parameter) os << "parameter ";
        if (k.variability == Variability::Constant) os << "constant ";
        if (k.causality == Causality::Output) os << "output ";
        if (k.causality == Causality::Input) os << "input ";
        os << JoinName(k.type_name);
        if (!k.type_dims.empty()) {
          os << '[';
          for (size_t i = 0; i < k.type_dims.size(); ++i) os << (i ? ", " : "") << DumpExpr(*k.type_dims[i]);
          os << ']';
        }
        os << ' ' << k.name;
        if (!k.dims.empty()) {
          os << '[';
          for (size_t i = 0; i < k.dims.size(); ++i) os << (i ? ", " : "") << DumpExpr(*k.dims[i]);
          os << ']';
        }
        DumpMod(k.mod.get(), os);
        if (k.condition) os << " if " << DumpExpr(*k.condition);
        os << ";\n";
        break;
      }
    }
  }
  if (!c.equations.empty()) {
    os << ind << "equation\n";
    DumpEquations(c.equations, os, ind + "  ");
  }
  if (c.annotation) {
    os << ind << "  annotation";
    DumpMod(c.annotation.get(), os);
    os << ";\n";
  }
  os << ind << "end " << c.name << ";\n";
}

std::string Dump(const StoredDefinition& def) {
  std::ostringstream os;
  if (!def.within.empty()) os << "within " << JoinName(def.within) << ";\n";
  for (const auto& i : def.imports)
    os << "import " << (i.alias.empty() ? "" : i.alias + " = ") << JoinName(i.name) << (i.wildcard ? ".*" : "")
       << ";\n";
  for (const auto& c : def.classes) DumpClass(*c, os, "");
  return os.str();
}

}  // namespace kanesim::lang::ast
