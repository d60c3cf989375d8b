#include "lang/ast_image.h"

#include <cstdint>
#include <cstring>

namespace kanesim::lang::ast {

namespace {

// Each node is written field by field in the order of its struct (lang/ast.h); counts and
// enums as 32-bit integers, strings as a count and their bytes, numbers as their 8 bytes.
class Writer {
 public:
  explicit Writer(std::string* out) : out_(out) {}
  bool ok() const { return ok_; }

  void Int(std::int64_t v) {
    const auto x = static_cast<std::int32_t>(v);
    out_->append(reinterpret_cast<const char*>(&x), sizeof x);
  }
  void Str(const std::string& s) {
    Int(static_cast<std::int64_t>(s.size()));
    out_->append(s);
  }
  void Strs(const std::vector<std::string>& v) {
    Int(static_cast<std::int64_t>(v.size()));
    for (const auto& s : v) Str(s);
  }
  void At(const Span& s) {
    Int(s.file);
    Int(s.begin);
    Int(s.end);
  }
  void Num(double d) { out_->append(reinterpret_cast<const char*>(&d), sizeof d); }

  void ExprOpt(const ExprPtr& e) {
    Int(e ? 1 : 0);
    if (e) Node(*e);
  }
  void Exprs(const std::vector<ExprPtr>& v) {
    Int(static_cast<std::int64_t>(v.size()));
    for (const auto& e : v) ExprOpt(e);
  }
  void Node(const Expr& e) {
    if (e.depth > kMaxImageExprDepth) {
      ok_ = false;
      return;
    }
    Int(static_cast<int>(e.kind));
    At(e.span);
    Num(e.number);
    Int(e.is_integer);
    Str(e.text);
    Int(e.op);
    Int(static_cast<std::int64_t>(e.parts.size()));
    for (const auto& p : e.parts) {
      Str(p.name);
      Exprs(p.subscripts);
      At(p.span);
    }
    Exprs(e.args);
    Int(static_cast<std::int64_t>(e.named_args.size()));
    for (const auto& n : e.named_args) {
      Str(n.name);
      ExprOpt(n.value);
      At(n.span);
    }
    Int(static_cast<std::int64_t>(e.rows.size()));
    for (const auto& r : e.rows) Exprs(r);
    Int(e.depth);
  }

  void ModOpt(const std::unique_ptr<Modification>& m) {
    Int(m ? 1 : 0);
    if (!m) return;
    Int(static_cast<std::int64_t>(m->args.size()));
    for (const Argument& a : m->args) {
      Int(a.each);
      Int(a.is_final);
      Int(a.redeclare);
      Strs(a.path);
      Str(a.redeclare_type);
      ModOpt(a.mod);
      Str(a.description);
      At(a.span);
      At(a.name_span);
    }
    Int(m->has_args);
    ExprOpt(m->value);
    At(m->span);
  }

  void ImportNode(const Import& i) {
    Strs(i.name);
    Str(i.alias);
    Int(i.wildcard);
    At(i.span);
  }

  void Equations(const std::vector<Equation>& v) {
    Int(static_cast<std::int64_t>(v.size()));
    for (const Equation& q : v) {
      Int(static_cast<int>(q.kind));
      ExprOpt(q.lhs);
      ExprOpt(q.rhs);
      Str(q.iter);
      ExprOpt(q.range);
      Equations(q.body);
      Exprs(q.conditions);
      Int(static_cast<std::int64_t>(q.branches.size()));
      for (const auto& b : q.branches) Equations(b);
      At(q.span);
    }
  }

  void Class(const ClassDef& c) {
    Int(static_cast<int>(c.kind));
    Str(c.name);
    Str(c.description);
    Int(c.partial);
    Int(static_cast<std::int64_t>(c.elements.size()));
    for (const Element& el : c.elements) {
      Int(el.kind);
      Int(el.is_final);
      Int(el.replaceable);
      Int(el.redeclare);
      switch (el.kind) {
        case Element::kComponent: ComponentNode(*el.component); break;
        case Element::kExtends:
          Strs(el.extends->base);
          ModOpt(el.extends->mod);
          At(el.extends->span);
          break;
        case Element::kImport: ImportNode(*el.import); break;
        case Element::kClass: Class(*el.class_def); break;
      }
    }
    Equations(c.equations);
    ModOpt(c.annotation);
    Int(c.is_short);
    Strs(c.short_base);
    ModOpt(c.short_mod);
    At(c.span);
    At(c.name_span);
  }

  void ComponentNode(const Component& c) {
    Int(static_cast<int>(c.variability));
    Int(static_cast<int>(c.causality));
    Int(c.is_final);
    Int(c.replaceable);
    Int(c.redeclare);
    Int(c.is_protected);
    Strs(c.type_name);
    Exprs(c.type_dims);
    Str(c.name);
    Exprs(c.dims);
    ModOpt(c.mod);
    ExprOpt(c.condition);
    Str(c.description);
    ModOpt(c.annotation);
    At(c.span);
    At(c.name_span);
    At(c.type_span);
  }

 private:
  std::string* out_;
  bool ok_ = true;
};

// Reads what Writer wrote; any count or enum out of range, or bytes running out, sets
// !ok() and every later read returns zeros, so the caller only checks at the end.
class Reader {
 public:
  Reader(std::string_view bytes, std::size_t pos) : b_(bytes), p_(pos) {}
  bool ok() const { return ok_; }
  std::size_t pos() const { return p_; }

  std::int32_t Int() {
    std::int32_t x = 0;
    if (!Take(&x, sizeof x)) return 0;
    return x;
  }
  bool Flag() { return Int() != 0; }
  // A count of items each at least one byte long, checked against what is left.
  std::size_t Count() {
    const std::int32_t n = Int();
    if (n < 0 || static_cast<std::size_t>(n) > b_.size() - p_) return Fail(), 0;
    return static_cast<std::size_t>(n);
  }
  template <class E>
  E Enum(int last) {
    const std::int32_t v = Int();
    if (v < 0 || v > last) return Fail(), E{};
    return static_cast<E>(v);
  }
  std::string Str() {
    const std::size_t n = Count();
    std::string s(b_.data() + p_, ok_ ? n : 0);
    p_ += ok_ ? n : 0;
    return s;
  }
  std::vector<std::string> Strs() {
    std::vector<std::string> v(Count());
    for (auto& s : v) s = Str();
    return v;
  }
  Span At() {
    Span s;
    s.file = Int();
    s.begin = Int();
    s.end = Int();
    return s;
  }
  double Num() {
    double d = 0;
    Take(&d, sizeof d);
    return d;
  }

  ExprPtr ExprOpt(int depth) {
    if (!Flag() || !ok_) return nullptr;
    if (depth > kMaxImageExprDepth) return Fail(), nullptr;
    auto e = std::make_unique<Expr>();
    e->kind = Enum<ExprKind>(static_cast<int>(ExprKind::If));
    e->span = At();
    e->number = Num();
    e->is_integer = Flag();
    e->text = Str();
    e->op = Int();
    e->parts.resize(Count());
    for (RefPart& p : e->parts) {
      p.name = Str();
      p.subscripts = Exprs(depth + 1);
      p.span = At();
    }
    e->args = Exprs(depth + 1);
    e->named_args.resize(Count());
    for (NamedArg& n : e->named_args) {
      n.name = Str();
      n.value = ExprOpt(depth + 1);
      n.span = At();
    }
    e->rows.resize(Count());
    for (auto& r : e->rows) r = Exprs(depth + 1);
    e->depth = Int();
    return e;
  }
  std::vector<ExprPtr> Exprs(int depth) {
    std::vector<ExprPtr> v(Count());
    for (auto& e : v) e = ExprOpt(depth);
    return v;
  }

  std::unique_ptr<Modification> ModOpt() {
    if (!Flag() || !ok_) return nullptr;
    auto m = std::make_unique<Modification>();
    m->args.resize(Count());
    for (Argument& a : m->args) {
      a.each = Flag();
      a.is_final = Flag();
      a.redeclare = Flag();
      a.path = Strs();
      a.redeclare_type = Str();
      a.mod = ModOpt();
      a.description = Str();
      a.span = At();
      a.name_span = At();
    }
    m->has_args = Flag();
    m->value = ExprOpt(1);
    m->span = At();
    return m;
  }

  void ImportNode(Import* i) {
    i->name = Strs();
    i->alias = Str();
    i->wildcard = Flag();
    i->span = At();
  }

  std::vector<Equation> Equations() {
    std::vector<Equation> v(Count());
    for (Equation& q : v) {
      q.kind = Enum<EqKind>(static_cast<int>(EqKind::If));
      q.lhs = ExprOpt(1);
      q.rhs = ExprOpt(1);
      q.iter = Str();
      q.range = ExprOpt(1);
      q.body = Equations();
      q.conditions = Exprs(1);
      q.branches.resize(Count());
      for (auto& b : q.branches) b = Equations();
      q.span = At();
    }
    return v;
  }

  std::unique_ptr<ClassDef> Class(ClassDef* parent) {
    auto c = std::make_unique<ClassDef>();
    c->parent = parent;
    c->kind = Enum<ClassKind>(static_cast<int>(ClassKind::Function));
    c->name = Str();
    c->description = Str();
    c->partial = Flag();
    c->elements.resize(Count());
    for (Element& el : c->elements) {
      el.kind = Enum<Element::Kind>(Element::kClass);
      el.is_final = Flag();
      el.replaceable = Flag();
      el.redeclare = Flag();
      if (!ok_) break;
      switch (el.kind) {
        case Element::kComponent: el.component = ComponentNode(); break;
        case Element::kExtends:
          el.extends = std::make_unique<Extends>();
          el.extends->base = Strs();
          el.extends->mod = ModOpt();
          el.extends->span = At();
          break;
        case Element::kImport:
          el.import = std::make_unique<Import>();
          ImportNode(el.import.get());
          break;
        case Element::kClass: el.class_def = Class(c.get()); break;
      }
    }
    c->equations = Equations();
    c->annotation = ModOpt();
    c->is_short = Flag();
    c->short_base = Strs();
    c->short_mod = ModOpt();
    c->span = At();
    c->name_span = At();
    return c;
  }

  std::unique_ptr<Component> ComponentNode() {
    auto c = std::make_unique<Component>();
    c->variability = Enum<Variability>(static_cast<int>(Variability::Constant));
    c->causality = Enum<Causality>(static_cast<int>(Causality::Output));
    c->is_final = Flag();
    c->replaceable = Flag();
    c->redeclare = Flag();
    c->is_protected = Flag();
    c->type_name = Strs();
    c->type_dims = Exprs(1);
    c->name = Str();
    c->dims = Exprs(1);
    c->mod = ModOpt();
    c->condition = ExprOpt(1);
    c->description = Str();
    c->annotation = ModOpt();
    c->span = At();
    c->name_span = At();
    c->type_span = At();
    return c;
  }

 private:
  void Fail() { ok_ = false; }
  bool Take(void* to, std::size_t n) {
    if (!ok_ || b_.size() - p_ < n) return Fail(), false;
    std::memcpy(to, b_.data() + p_, n);
    p_ += n;
    return true;
  }
  std::string_view b_;
  std::size_t p_;
  bool ok_ = true;
};

constexpr std::int32_t kMagic = 0x4B415354;  // "KAST"

}  // namespace

bool WriteDefinition(const StoredDefinition& def, std::string* out) {
  Writer w(out);
  w.Int(kMagic);
  w.Int(def.file);
  w.Strs(def.within);
  w.Int(static_cast<std::int64_t>(def.imports.size()));
  for (const Import& i : def.imports) w.ImportNode(i);
  w.Int(static_cast<std::int64_t>(def.classes.size()));
  for (const auto& c : def.classes) w.Class(*c);
  return w.ok();
}

std::shared_ptr<StoredDefinition> ReadDefinition(std::string_view bytes, std::size_t* pos) {
  Reader r(bytes, *pos);
  if (r.Int() != kMagic) return nullptr;
  auto def = std::make_shared<StoredDefinition>();
  def->file = r.Int();
  def->within = r.Strs();
  def->imports.resize(r.Count());
  for (Import& i : def->imports) r.ImportNode(&i);
  def->classes.resize(r.Count());
  for (auto& c : def->classes) {
    if (!r.ok()) break;
    c = r.Class(nullptr);
  }
  if (!r.ok()) return nullptr;
  *pos = r.pos();
  return def;
}

}  // namespace kanesim::lang::ast
