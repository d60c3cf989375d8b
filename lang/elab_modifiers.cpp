// Modifiers: built, merged (outer wins), sliced per array element (lang/elab_modifiers.h).
#include <algorithm>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "lang/elab_modifiers.h"

#include "lang/elab_eval.h"

namespace kanesim::lang::elab {

bool IsVarAttribute(const std::string& name) {
  // By length first: each variable's attributes are checked in every instance.
  const std::string_view n = name;
  switch (n.size()) {
    case 3: return n == "min" || n == "max";
    case 4: return n == "unit";
    case 5: return n == "start" || n == "fixed";
    case 7: return n == "nominal";
    case 8: return n == "quantity";
    case 11: return n == "displayUnit" || n == "stateSelect";
    default: return false;
  }
}
namespace {

// BuildMod into `out`, a Mod as default-constructed: a sub-modifier seen for the first time
// is built in its map node, not built apart and moved there.
void BuildModInto(Mod& out, const ast::Modification* m, Node* scope, const std::shared_ptr<const Iters>& iters,
                  Diagnostics& diags) {
  if (!m) return;
  out.span = m->span;
  out.order.reserve(m->args.size());
  if (m->value) {
    ModValue v;
    v.expr = m->value.get();
    v.scope = scope;
    v.iters = iters;
    v.span = m->value->span;
    out.value = v;
  }
  for (const auto& a : m->args) {
    // a.b.c = x  ==  a(b(c = x))
    Mod* target = &out;
    for (size_t i = 0; i < a.path.size(); ++i) {
      const std::string& key = a.path[i];
      auto [slot, added] = target->sub.try_emplace(key);
      if (added) target->order.push_back(key);
      Mod& next = slot->second;
      if (i + 1 < a.path.size()) {
        if (!next.span.valid()) next.span = a.name_span;
        target = &next;
        continue;
      }
      auto build = [&](Mod& into) {
        BuildModInto(into, a.mod.get(), scope, iters, diags);
        into.span = a.name_span;
        into.each = a.each;
        if (a.is_final) {
          into.is_final = true;
          into.final_span = a.span;
          if (into.value) into.value->is_final = true;
        }
        if (a.redeclare) {
          into.redeclare = Mod::Redeclare{a.redeclare_type, scope && scope->cls ? scope->cls : nullptr, a.span};
        }
      };
      if (added) {  // a new key: built in place
        build(next);
        continue;
      }
      Mod built;  // a key met before: built apart, checked, then moved in
      build(built);
      if (next.value || !next.sub.empty()) {
        auto& d = diags.Error(DiagCode::Duplicate, a.name_span, "'" + ast::JoinName(a.path) + "' is modified twice");
        d.notes.push_back({next.span, "first modified here"});
      }
      next = std::move(built);
    }
  }
}

}  // namespace

Mod BuildMod(const ast::Modification* m, Node* scope, const std::shared_ptr<const Iters>& iters,
             Diagnostics& diags) {
  Mod out;
  BuildModInto(out, m, scope, iters, diags);
  return out;
}

namespace {

// The recursion of MergeInto (as deep as the modifier is written), for an inner modifier
// that is kept (const Mod&: its values are copied) or given up (Mod&&: they are moved).
// The name for messages is `what` followed by `keys`, built only when a message needs it.
// The keys from `what` down to the modifier being merged; as deep as a modifier is written,
// so no heap allocation.
using MergeKeys = SmallVec<const std::string*, 8>;

template <class InnerRef>
void MergeModsImpl(Diagnostics& diags, Mod& outer, InnerRef&& inner, const MergeWhat& what, MergeKeys& keys) {
  constexpr bool kMove = !std::is_lvalue_reference_v<InnerRef>;
  auto take = [](auto& x) -> decltype(auto) {
    if constexpr (kMove) return std::move(x);
    else return static_cast<const std::remove_reference_t<decltype(x)>&>(x);
  };
  auto name = [&] {
    std::string s = what.Str();
    for (const std::string* k : keys) s += "." + *k;
    return s;
  };
  const bool inner_empty = inner.empty();  // before anything moves out of inner
  // --set on a final parameter is reported once by SetOverrides::Bind.
  if (outer.value && outer.value->from_set && inner.is_final) {
    outer.value.reset();
  }
  if (inner.is_final && (outer.value || !outer.sub.empty() || outer.Redeclared())) {
    Span at = outer.value ? outer.value->span : outer.span;
    auto& d = diags.Error(DiagCode::FinalOverride, at, "'" + name() + "' is final and cannot be modified");
    d.notes.push_back({inner.final_span.valid() ? inner.final_span : inner.span, "declared final here"});
    outer.value.reset();
    outer.sub.clear();
  }
  if (!outer.value && inner.value) outer.value = take(inner.value);
  else if (outer.value && inner.value && inner.value->is_final) {
    auto& d = diags.Error(DiagCode::FinalOverride, outer.value->span, "'" + name() + "' is final and cannot be modified");
    d.notes.push_back({inner.value->span, "final value given here"});
    outer.value = take(inner.value);
  }
  if (inner.is_final) {
    outer.is_final = true;
    outer.final_span = inner.final_span;
  }
  if (!outer.Redeclared() && inner.Redeclared()) outer.redeclare = take(inner.redeclare);
  if (!outer.span.valid()) outer.span = inner.span;
  outer.each = outer.each || inner.each;
  if (!inner_empty && !inner.set_only) outer.set_only = false;
  if (outer.order.empty()) outer.order.reserve(inner.order.size());  // later merges grow it geometrically
  for (const auto& key : inner.order) {
    auto it = inner.sub.find(key);
    if (it == inner.sub.end()) continue;
    auto [slot, added] = outer.sub.try_emplace(key);
    if (added) outer.order.push_back(key);
    keys.push_back(&key);
    MergeModsImpl(diags, slot->second, take(it->second), what, keys);
    keys.pop_back();
  }
}

// A modifier as default-constructed: merging it changes nothing, and merging into it
// gives the inner one.
bool Pristine(const Mod& m) {
  return !m.value && m.sub.empty() && m.order.empty() && !m.each && !m.is_final && !m.final_span.valid() &&
         !m.span.valid() && !m.redeclare && !m.set_only;
}

// Whether every level of m lists each of its sub-modifiers once in `order` (as BuildMod
// and MergeMods make them), so that moving m whole equals merging it key by key.
bool OrderMatchesSubs(const Mod& m) {
  if (m.order.size() != m.sub.size()) return false;
  SmallVec<const Mod*, 16> listed;  // each key of `order` found in `sub`, and none twice
  for (const std::string& k : m.order) {
    auto it = m.sub.find(k);
    if (it == m.sub.end()) return false;
    listed.push_back(&it->second);
  }
  std::sort(listed.begin(), listed.end());
  if (std::adjacent_find(listed.begin(), listed.end()) != listed.end()) return false;
  for (const auto& [k, sm] : m.sub)
    if (!OrderMatchesSubs(sm)) return false;
  return true;
}

// What MergeModsImpl leaves in a pristine outer modifier besides the inner one's fields:
// set_only cleared, final_span and the redeclare fields only where they apply.
void NormalizeMerged(Mod& m) {
  m.set_only = false;
  if (!m.is_final) m.final_span = Span{};
  if (!m.Redeclared()) m.redeclare.reset();
  for (auto& [k, sm] : m.sub) NormalizeMerged(sm);
}

}  // namespace

std::string MergeWhat::Str() const {
  if (node_) return node_->Path();
  if (parts_) return ast::JoinName(*parts_);
  return text_ ? *text_ : std::string();
}

void MergeMods(Mod& outer, const Mod& inner, MergeWhat what, Diagnostics& diags) {
  if (Pristine(inner)) return;
  MergeKeys keys;
  MergeModsImpl(diags, outer, inner, what, keys);
}

// Merging into a pristine modifier (an element without outer modifiers, the common case)
// moves the inner tree instead of rebuilding it node by node: no diagnostic can arise.
void MergeMods(Mod& outer, Mod&& inner, MergeWhat what, Diagnostics& diags) {
  if (Pristine(inner)) return;
  if (Pristine(outer) && OrderMatchesSubs(inner)) {
    outer = std::move(inner);
    NormalizeMerged(outer);
    return;
  }
  MergeKeys keys;
  MergeModsImpl(diags, outer, std::move(inner), what, keys);
}

void MergeBuiltMod(Mod& outer, Mod&& built, MergeWhat what, Diagnostics& diags) {
  if (Pristine(built)) return;
  if (Pristine(outer)) {  // OrderMatchesSubs(built) holds: BuildMod adds a key to both at once
    outer = std::move(built);
    NormalizeMerged(outer);
    return;
  }
  MergeKeys keys;
  MergeModsImpl(diags, outer, std::move(built), what, keys);
}

Value ElementOf(const Value& v, int index, int count) {
  Value s;
  s.type = v.type;
  s.shape.assign(v.shape.begin() + 1, v.shape.end());
  size_t stride = v.Size() / static_cast<size_t>(count);
  for (size_t k = 0; k < stride; ++k) {
    s.elements.push_back(v.elements[static_cast<size_t>(index) * stride + k]);
    if (v.type == VType::String) s.strings.push_back(v.strings[static_cast<size_t>(index) * stride + k]);
  }
  return s;
}

// Element `index` of an array component's modifier. Copies everything but the values,
// and of a value only the slice: copying the whole array value for every element would
// cost O(count^2) time and memory.
Mod SliceMod(const Mod& mod, int index, int count, Evaluator& eval, Diagnostics& diags) {
  if (mod.each) return mod;  // `each` applies the whole modifier to every element
  Mod out;
  out.order = mod.order;
  out.each = mod.each;
  out.is_final = mod.is_final;
  out.final_span = mod.final_span;
  out.span = mod.span;
  out.redeclare = mod.redeclare;
  out.set_only = mod.set_only;
  if (mod.value) {
    std::optional<Value> evaluated;
    if (!mod.value->pre) evaluated = eval.EvalModValue(*mod.value, nullptr);
    const Value& v = mod.value->pre ? *mod.value->pre : *evaluated;
    if (v.valid && (v.shape.empty() || v.shape[0] != count)) {
      auto& d = diags.Error(DiagCode::SizeMismatch, mod.value->span,
                            "modifier of an array of " + std::to_string(count) + " components needs " +
                                std::to_string(count) + " values");
      d.hint = "write 'each' before the name to give every element the same value";
    } else if (v.valid) {
      ModValue mv;
      mv.expr = mod.value->expr;
      mv.scope = mod.value->scope;
      mv.iters = mod.value->iters;
      mv.span = mod.value->span;
      mv.is_final = mod.value->is_final;
      mv.from_set = mod.value->from_set;
      mv.pre = ElementOf(v, index, count);
      out.value = std::move(mv);
    }
  }
  for (const auto& [k, sm] : mod.sub) out.sub[k] = SliceMod(sm, index, count, eval, diags);
  return out;
}
void PreEvaluateMod(Mod& mod, int count, Evaluator& eval, Diagnostics& diags) {
  if (mod.each) return;
  if (mod.value && !mod.value->pre) {
    Value v = eval.EvalModValue(*mod.value, nullptr);
    if (!v.valid) {
      mod.value.reset();
    } else if (v.shape.empty() || v.shape[0] != count) {
      auto& d = diags.Error(DiagCode::SizeMismatch, mod.value->span,
                            "modifier of an array of " + std::to_string(count) + " components needs " +
                                std::to_string(count) + " values");
      d.hint = mod.value->from_set ? "set one element (--set name[k].x=...), or give " + std::to_string(count) + " values"
                                   : "write 'each' before the name to give every element the same value";
      mod.value.reset();
    } else {
      mod.value->pre = std::move(v);
    }
  }
  for (auto& [k, sm] : mod.sub) PreEvaluateMod(sm, count, eval, diags);
}

}  // namespace kanesim::lang::elab
