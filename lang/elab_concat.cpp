// Array concatenation, as Modelica 3.5 section 10.4 defines it: cat(k, A, B, ...) joins
// arrays along dimension k, and the concatenation constructor [A, B; C, D] is
// cat(1, cat(2, A, B), cat(2, C, D)) after every block is promoted to at least two
// dimensions (a scalar is 1 x 1, a vector of n is a column, n x 1). The array constructor
// {a, b}, which adds a dimension, is EvalArray (elab_eval.cpp).
//
// Sizes are checked before anything is copied: the result is at most kMaxArraySize
// elements (E209), and EvalNested charges it to the work budget (E228) like every value.
#include <string>
#include <vector>

#include "lang/elab_eval.h"

namespace kanesim::lang::elab {

namespace {

// 1-based ordinal for messages: "argument 3".
std::string Nth(size_t i) { return std::to_string(i + 1); }

// Numbers (Real and Integer) join with each other; Booleans and Strings only with their own.
bool Compatible(VType a, VType b) {
  auto kind = [](VType t) { return t == VType::String ? 2 : t == VType::Boolean ? 1 : 0; };
  return kind(a) == kind(b);
}

// [a, b; c, d] of scalars of one kind, every row as long (a 3 x 3 inertia, a rotation):
// the matrix directly, which is what the general joins below give it, without their
// messages made ready for errors that cannot occur. False for anything else.
bool ScalarGrid(const std::vector<std::vector<Value>>& rows, Value* out) {
  if (rows.empty() || rows[0].empty()) return false;
  const size_t cols = rows[0].size();
  if (rows.size() * cols > static_cast<size_t>(kMaxArraySize)) return false;
  const VType first = rows[0][0].type;
  VType type = first;
  for (const auto& row : rows) {
    if (row.size() != cols) return false;
    for (const Value& v : row) {
      if (!v.shape.empty() || v.elements.size() != 1 || !Compatible(first, v.type)) return false;
      if (v.type == VType::String && v.strings.empty()) return false;
      if (type != VType::String && type != VType::Boolean) type = Promote(type, v.type);
    }
  }
  out->type = type;
  out->shape = {static_cast<int>(rows.size()), static_cast<int>(cols)};
  out->elements.reserve(rows.size() * cols);
  for (const auto& row : rows)
    for (const Value& v : row) {
      out->elements.push_back(v.elements[0]);
      if (type == VType::String) out->strings.push_back(v.strings[0]);
    }
  return true;
}

}  // namespace

// Joins `parts` along dimension `k` (0-based). Every part has the same number of
// dimensions (> k) and the same size in every dimension but k; `what` names the
// construct in messages ("cat(2, ...)"), `spans` locate the parts and `names` name them
// ("argument 2", "row 1").
Value Evaluator::Concatenate(size_t k, const std::vector<Value>& parts, const std::vector<Span>& spans,
                             const std::vector<std::string>& names, Span whole, const std::string& what,
                             const std::string& hint) {
  const Value& first = parts[0];
  size_t total = 0;
  int joined = 0;
  VType type = first.type;
  for (size_t p = 0; p < parts.size(); ++p) {
    const Value& v = parts[p];
    if (!Compatible(first.type, v.type)) {
      auto& d = diags_.Error(DiagCode::TypeMismatch, spans[p],
                             what + ": " + names[p] + " is " + VTypeName(v.type) + " but " + names[0] + " is " +
                                 VTypeName(first.type) + "; they cannot be joined");
      d.notes.push_back({spans[0], names[0] + ", " + VTypeName(first.type)});
      return Value::Invalid();
    }
    if (type != VType::String && type != VType::Boolean) type = Promote(type, v.type);
    bool same = v.shape.size() == first.shape.size();
    for (size_t d = 0; same && d < v.shape.size(); ++d) same = d == k || v.shape[d] == first.shape[d];
    if (!same) {
      auto& d = diags_.Error(DiagCode::SizeMismatch, spans[p],
                             what + ": " + names[p] + " is " + ShapeStr(v.shape) + " but " + names[0] + " is " +
                                 ShapeStr(first.shape) + "; they must agree in every dimension but " +
                                 std::to_string(k + 1));
      d.notes.push_back({spans[0], names[0] + ", " + ShapeStr(first.shape)});
      d.hint = hint;
      return Value::Invalid();
    }
    total += v.Size();
    joined += v.shape[k];
    if (total > static_cast<size_t>(kMaxArraySize)) {
      diags_.Error(DiagCode::ArrayTooLarge, whole,
                   what + " has more than " + std::to_string(kMaxArraySize) + " elements");
      return Value::Invalid();
    }
  }
  Value r;
  r.type = type;
  r.shape = first.shape;
  r.shape[k] = joined;
  // Row-major: for each index of the dimensions before k, each part contributes one
  // contiguous block (its slice along k and every dimension after it).
  size_t outer = 1, inner = 1;
  for (size_t d = 0; d < k; ++d) outer *= static_cast<size_t>(first.shape[d]);
  for (size_t d = k + 1; d < first.shape.size(); ++d) inner *= static_cast<size_t>(first.shape[d]);
  r.elements.reserve(total);
  const bool strings = type == VType::String;
  for (size_t o = 0; o < outer; ++o) {
    for (const Value& v : parts) {
      const size_t block = static_cast<size_t>(v.shape[k]) * inner;
      r.elements.insert(r.elements.end(), v.elements.begin() + static_cast<std::ptrdiff_t>(o * block),
                 v.elements.begin() + static_cast<std::ptrdiff_t>((o + 1) * block));
      if (strings)
        r.strings.insert(r.strings.end(), v.strings.begin() + static_cast<std::ptrdiff_t>(o * block),
                   v.strings.begin() + static_cast<std::ptrdiff_t>((o + 1) * block));
    }
  }
  return r;
}

// cat(k, A, B, ...): `args` are evaluated already (args[0] is k).
Value Evaluator::EvalCat(const ast::Expr& e, const std::vector<Value>& args) {
  if (args.size() < 2) {
    diags_.Error(DiagCode::BadCall, e.span, "'cat' needs a dimension and at least one array, got " +
                                                std::to_string(args.size()) + " argument(s)")
        .hint = "cat(k, A, B, ...) joins A, B, ... along dimension k";
    return Value::Invalid();
  }
  long k = 0;
  if (!StructuralInt(args[0], e.args[0]->span, &k, "the dimension of 'cat'")) return Value::Invalid();
  std::vector<Value> parts(args.begin() + 1, args.end());
  std::vector<Span> spans;
  std::vector<std::string> names;
  for (size_t i = 1; i < e.args.size(); ++i) {
    spans.push_back(e.args[i]->span);
    names.push_back("argument " + Nth(i));
  }
  const size_t dims = parts[0].shape.size();
  if (dims == 0) {
    diags_.Error(DiagCode::SizeMismatch, spans[0], "'cat' joins arrays, but argument 2 is a scalar")
        .hint = "write {x} for a vector of one element";
    return Value::Invalid();
  }
  if (k < 1 || k > static_cast<long>(dims)) {
    diags_.Error(DiagCode::IndexOutOfRange, e.args[0]->span,
                 "dimension " + std::to_string(k) + " of 'cat' is out of range 1.." + std::to_string(dims) +
                     " (the arrays have " + std::to_string(dims) + " dimension(s))")
        .hint = "cat(1, ...) stacks along the first dimension (rows), cat(2, ...) along the second (columns)";
    return Value::Invalid();
  }
  for (size_t p = 1; p < parts.size(); ++p) {
    if (parts[p].shape.size() != dims) {
      auto& d = diags_.Error(DiagCode::SizeMismatch, spans[p],
                             "'cat': argument " + Nth(p + 1) + " has " + std::to_string(parts[p].shape.size()) +
                                 " dimension(s), " + ShapeStr(parts[p].shape) + ", but argument 2 has " +
                                 std::to_string(dims) + ", " + ShapeStr(parts[0].shape));
      d.notes.push_back({spans[0], "argument 2, " + ShapeStr(parts[0].shape)});
      d.hint = "every array given to cat has the same number of dimensions; write {x} for a vector of one element";
      return Value::Invalid();
    }
  }
  return Concatenate(static_cast<size_t>(k - 1), parts, spans, names, e.span, "cat(" + std::to_string(k) + ", ...)",
                     "cat(k, A, B) joins along dimension k; every other dimension of A and B must be equal");
}

// [a, b; c, d]: ',' joins side by side (cat(2, ...)), ';' stacks the rows (cat(1, ...)).
Value Evaluator::EvalMatrix(const ast::Expr& e, const Ctx& ctx) {
  std::vector<std::vector<Value>> rows;
  rows.reserve(e.rows.size());  // at their final sizes: a 3 x 3 inertia is 4 allocations, not 12
  size_t ndims = 2;
  for (const auto& row : e.rows) {
    rows.emplace_back().reserve(row.size());
    for (const auto& x : row) {
      Value v = Eval(*x, ctx);
      if (!v.valid) return Value::Invalid();
      if (v.shape.size() > ndims) ndims = v.shape.size();
      rows.back().push_back(std::move(v));
    }
  }
  if (Value grid; ScalarGrid(rows, &grid)) return grid;
  // Promote to ndims dimensions: trailing dimensions of size 1.
  for (auto& row : rows)
    for (auto& v : row) v.shape.resize(ndims, 1);
  const std::string hint =
      "in [A, B; C, D], ',' puts blocks side by side (equal numbers of rows) and ';' stacks rows of blocks (equal "
      "numbers of columns); a scalar is 1 x 1 and a vector a column";
  std::vector<Value> joined;
  std::vector<Span> row_spans;
  std::vector<std::string> row_names;
  for (size_t ri = 0; ri < rows.size(); ++ri) {
    const auto& src = e.rows[ri];
    Span row_span = src.empty() ? e.span : src.front()->span;
    if (!src.empty()) row_span.end = src.back()->span.end;
    row_spans.push_back(row_span);
    row_names.push_back("row " + Nth(ri));
    if (rows[ri].empty()) {  // [] or an empty row: a 1 x 0 matrix
      Value v;
      v.type = VType::Real;
      v.shape.assign(ndims, 1);
      v.shape[1] = 0;
      joined.push_back(v);
      continue;
    }
    std::vector<Span> spans;
    std::vector<std::string> names;
    for (const auto& x : src) {
      spans.push_back(x->span);
      names.push_back("block " + Nth(names.size()));
    }
    Value r = rows[ri].size() == 1 ? rows[ri][0]
                                   : Concatenate(1, rows[ri], spans, names, e.span, "row " + Nth(ri) + " of [...]", hint);
    if (!r.valid) return Value::Invalid();
    joined.push_back(std::move(r));
  }
  if (joined.size() == 1) return joined[0];
  return Concatenate(0, joined, row_spans, row_names, e.span, "[...]", hint);
}

}  // namespace kanesim::lang::elab
