#include "lang/ast.h"

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

ExprPtr Clone(const Expr& e) {
  auto c = std::make_unique<Expr>();
  c->kind = e.kind;
  c->span = e.span;
  c->number = e.number;
  c->is_integer = e.is_integer;
  c->text = e.text;
  c->op = e.op;
  for (const auto& p : e.parts) {
    RefPart q;
    q.name = p.name;
    q.span = p.span;
    for (const auto& s : p.subscripts) q.subscripts.push_back(Clone(*s));
    c->parts.push_back(std::move(q));
  }
  for (const auto& a : e.args) c->args.push_back(Clone(*a));
  for (const auto& n : e.named_args) c->named_args.push_back({n.name, Clone(*n.value), n.span});
  for (const auto& r : e.rows) {
    c->rows.emplace_back();
    for (const auto& x : r) c->rows.back().push_back(Clone(*x));
  }
  return c;
}

static void DumpExprTo(const Expr& e, std::ostringstream& os, int depth);

static void DumpRef(const std::vector<RefPart>& parts, std::ostringstream& os, int depth) {
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i) os << '.';
    os << parts[i].name;
    if (!parts[i].subscripts.empty()) {
      os << '[';
      for (size_t k = 0; k < parts[i].subscripts.size(); ++k) {
        if (k) os << ", ";
        DumpExprTo(*parts[i].subscripts[k], os, depth + 1);
      }
      os << ']';
    }
  }
}

static void DumpExprTo(const Expr& e, std::ostringstream& os, int depth) {
  if (depth > 256) {
    os << "...";
    return;
  }
  switch (e.kind) {
    case ExprKind::Number: {
      std::ostringstream v;
      v.precision(17);
      v << e.number;
      os << v.str();
      break;
    }
    case ExprKind::String: os << '"' << e.text << '"'; break;
    case ExprKind::Bool: os << (e.number != 0 ? "true" : "false"); break;
    case ExprKind::Ref: DumpRef(e.parts, os, depth); break;
    case ExprKind::Call:
      DumpRef(e.parts, os, depth);
      os << '(';
      for (size_t i = 0; i < e.args.size(); ++i) {
        if (i) os << ", ";
        DumpExprTo(*e.args[i], os, depth + 1);
      }
      for (size_t i = 0; i < e.named_args.size(); ++i) {
        if (i || !e.args.empty()) os << ", ";
        os << e.named_args[i].name << " = ";
        DumpExprTo(*e.named_args[i].value, os, depth + 1);
      }
      os << ')';
      break;
    case ExprKind::Array:
      os << '{';
      for (size_t i = 0; i < e.args.size(); ++i) {
        if (i) os << ", ";
        DumpExprTo(*e.args[i], os, depth + 1);
      }
      os << '}';
      break;
    case ExprKind::Comprehension:
      os << '{';
      DumpExprTo(*e.args[0], os, depth + 1);
      os << " for " << e.text << " in ";
      DumpExprTo(*e.args[1], os, depth + 1);
      os << '}';
      break;
    case ExprKind::Matrix:
      os << '[';
      for (size_t r = 0; r < e.rows.size(); ++r) {
        if (r) os << "; ";
        for (size_t i = 0; i < e.rows[r].size(); ++i) {
          if (i) os << ", ";
          DumpExprTo(*e.rows[r][i], os, depth + 1);
        }
      }
      os << ']';
      break;
    case ExprKind::Range:
      os << '(';
      for (size_t i = 0; i < e.args.size(); ++i) {
        if (i) os << ':';
        DumpExprTo(*e.args[i], os, depth + 1);
      }
      os << ')';
      break;
    case ExprKind::Colon: os << ':'; break;
    case ExprKind::End: os << "end"; break;
    case ExprKind::Unary:
      os << '(' << TokSpelling(static_cast<Tok>(e.op)) << (e.op == static_cast<int>(Tok::KwNot) ? " " : "");
      DumpExprTo(*e.args[0], os, depth + 1);
      os << ')';
      break;
    case ExprKind::Binary:
      os << '(';
      DumpExprTo(*e.args[0], os, depth + 1);
      os << ' ' << TokSpelling(static_cast<Tok>(e.op)) << ' ';
      DumpExprTo(*e.args[1], os, depth + 1);
      os << ')';
      break;
    case ExprKind::If:
      os << "(if ";
      for (size_t i = 0; i + 1 < e.args.size(); i += 2) {
        if (i) os << " elseif ";
        DumpExprTo(*e.args[i], os, depth + 1);
        os << " then ";
        DumpExprTo(*e.args[i + 1], os, depth + 1);
      }
      os << " else ";
      DumpExprTo(*e.args.back(), os, depth + 1);
      os << ')';
      break;
  }
}

std::string DumpExpr(const Expr& e) {
  std::ostringstream os;
  DumpExprTo(e, os, 0);
  return os.str();
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
