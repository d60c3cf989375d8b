// Lookup: the class registry, class names resolved from a scope, annotations through
// extends, the model picked and the user's imports checked (lang/elab_lookup.h).
#include "lang/elab_lookup.h"

#include <algorithm>
#include <functional>
#include <sstream>
#include <string_view>

#include "lang/library_cache.h"

namespace kanesim::lang::elab {

ClassLookup::ClassLookup(const Program& program, Diagnostics& diags)
    : program_(program), diags_(diags), library_(program.library.get()) {
  for (const auto& f : program.files)
    for (const auto& c : f->classes) Register(c.get(), ast::JoinName(f->within), f.get());
  if (library_) unit_loaded_.assign(static_cast<size_t>(library_->NumUnits()), 0);
}

void ClassLookup::Register(const ast::ClassDef* c, const std::string& prefix, const ast::StoredDefinition* file) const {
  std::string q = prefix.empty() ? c->name : prefix + "." + c->name;
  if (!classes_.count(q)) classes_[q] = {c, file, q};
  file_of_[c] = file;
  qualified_of_[c] = q;
  for (const auto& el : c->elements)
    if (el.kind == ast::Element::kClass) Register(el.class_def.get(), q, file);
}

void ClassLookup::LoadUnit(int u) const {
  if (unit_loaded_[static_cast<size_t>(u)]) return;
  unit_loaded_[static_cast<size_t>(u)] = 1;
  const ast::StoredDefinition* f = library_->Unit(u).get();
  for (const Diagnostic& d : library_->UnitDiagnostics(u))  // none for the embedded library
    (d.severity == Severity::Error ? diags_.Error(d.code, d.span, d.message) : diags_.Warning(d.code, d.span, d.message)) = d;
  for (const auto& c : f->classes) Register(c.get(), ast::JoinName(f->within), f);
}

// The library's unit that declares `q` or a class that encloses it, registered; true if
// one was newly registered. The registry then answers `q` exactly as if the whole library
// had been registered at the start: the main file's classes come first either way, and
// the library declares each top-level name once.
bool ClassLookup::LoadLibraryClass(const std::string& q) const {
  if (!library_) return false;
  for (std::string_view name(q);;) {
    int u = library_->FindUnit(name);
    if (u >= 0 && !unit_loaded_[static_cast<size_t>(u)]) {
      LoadUnit(u);
      return true;
    }
    size_t dot = name.rfind('.');
    if (dot == std::string_view::npos) return false;
    name = name.substr(0, dot);
  }
}

void ClassLookup::LoadWholeLibrary() const {
  if (library_)
    for (int u = 0; u < library_->NumUnits(); ++u) LoadUnit(u);
}

const ClassInfo* ClassLookup::LookupClass(const std::string& q) const {
  auto it = classes_.find(q);
  if (it == classes_.end() && LoadLibraryClass(q)) it = classes_.find(q);
  return it == classes_.end() ? nullptr : &it->second;
}

const ast::StoredDefinition* ClassLookup::FileOf(const ast::ClassDef* c) const {
  auto it = file_of_.find(c);
  return it == file_of_.end() ? nullptr : it->second;
}

size_t ClassLookup::FoundHash::Of(const ast::ClassDef* from, const std::vector<std::string>& parts) {
  size_t h = std::hash<const void*>()(from);
  for (const std::string& p : parts) h = h * 31 + std::hash<std::string_view>()(p);
  return h;
}

const ast::ClassDef* ClassLookup::FindClass(const std::vector<std::string>& parts, const ast::ClassDef* from) const {
  if (auto it = found_.find(FoundRef{from, parts}); it != found_.end()) return it->second;
  const ast::ClassDef* c = Resolve(parts, from);
  found_.emplace(FoundKey{from, parts}, c);
  return c;
}

const ast::ClassDef* ClassLookup::Resolve(const std::vector<std::string>& parts, const ast::ClassDef* from) const {
  if (parts.empty()) return nullptr;
  auto nested = [&](const ast::ClassDef* c, const std::string& n) -> const ast::ClassDef* {
    for (const auto& el : c->elements)
      if (el.kind == ast::Element::kClass && el.class_def->name == n) return el.class_def.get();
    return nullptr;
  };
  auto by_qualified = [&](const std::string& q) -> const ast::ClassDef* {
    const ClassInfo* info = LookupClass(q);
    return info ? info->cls : nullptr;
  };
  auto via_imports = [&](const std::vector<ast::Import>& imports) -> const ast::ClassDef* {
    for (const auto& imp : imports) {
      std::string q = ast::JoinName(imp.name);
      if (imp.wildcard) {
        if (auto* c = by_qualified(q + "." + parts[0])) return c;
      } else if (!imp.alias.empty()) {
        if (imp.alias == parts[0]) return by_qualified(q);
      } else if (!imp.name.empty() && imp.name.back() == parts[0]) {
        return by_qualified(q);
      }
    }
    return nullptr;
  };
  const ast::ClassDef* first = nullptr;
  for (const ast::ClassDef* s = from; s && !first; s = s->parent) {
    if (s->name == parts[0] && s->parent == nullptr) first = s;
    if (!first) first = nested(s, parts[0]);
    if (!first) {
      std::vector<ast::Import> imports;
      for (const auto& el : s->elements)
        if (el.kind == ast::Element::kImport) {
          ast::Import copy;
          copy.name = el.import->name;
          copy.alias = el.import->alias;
          copy.wildcard = el.import->wildcard;
          imports.push_back(std::move(copy));
        }
      first = via_imports(imports);
    }
  }
  const ast::StoredDefinition* file = from ? FileOf(from) : nullptr;
  if (!first && file) first = via_imports(file->imports);
  if (!first && file && !file->within.empty()) first = by_qualified(ast::JoinName(file->within) + "." + parts[0]);
  if (!first) first = by_qualified(parts[0]);
  if (!first) first = by_qualified("Kanesim." + parts[0]);  // the standard library is always visible
  for (size_t i = 1; first && i < parts.size(); ++i) first = nested(first, parts[i]);
  if (!first && parts.size() > 1) first = by_qualified(ast::JoinName(parts));
  return first;
}

// Breadth-first over the class and its bases (each visited once, so cyclic extends
// cannot loop; the cycle itself is reported by Collect).
const ast::Modification* ClassLookup::FindAnnotation(const ast::ClassDef* cls, const std::string& key) const {
  std::vector<const ast::ClassDef*> queue{cls};
  for (size_t i = 0; i < queue.size() && i < 256; ++i) {
    const ast::ClassDef* c = queue[i];
    if (c->annotation)
      for (const auto& a : c->annotation->args)
        if (a.path.size() == 1 && a.path[0] == key) return a.mod.get();
    auto push = [&](const ast::ClassDef* b) {
      if (b && std::find(queue.begin(), queue.end(), b) == queue.end()) queue.push_back(b);
    };
    for (const auto& el : c->elements)
      if (el.kind == ast::Element::kExtends) push(FindClass(el.extends->base, c));
    if (c->is_short) push(FindClass(c->short_base, c));
  }
  return nullptr;
}

const ast::ClassDef* ClassLookup::PickModel(const std::string& model) {
  const ast::ClassDef* top = nullptr;
  if (model.empty()) {
    if (program_.files.empty()) return nullptr;
    for (const auto& c : program_.files[0]->classes)
      if (c->kind == ast::ClassKind::Model && !c->partial) top = c.get();
    if (!top)
      diags_.Error(DiagCode::NotAModel, Span{0, 0, 0}, "the file declares no (non-partial) model")
          .hint = "write 'model Name ... end Name;' or choose one with --model";
    return top;
  }
  std::vector<std::string> parts;
  std::stringstream ss(model);
  std::string p;
  while (std::getline(ss, p, '.')) parts.push_back(p);
  top = FindClass(parts, nullptr);
  if (!top && !program_.files.empty())
    for (const auto& c : program_.files[0]->classes)
      if (c->name == parts[0]) top = FindClass(parts, c.get());
  if (top) return top;
  auto& d = diags_.Error(DiagCode::NotAModel, Span{}, "no class named '" + model + "'");
  LoadWholeLibrary();  // the hint considers every class
  std::vector<std::string> names;
  for (auto& [k, v] : classes_) names.push_back(k);
  std::string best = ClosestName(model, names);
  if (!best.empty()) d.hint = "did you mean '" + best + "'?";
  return nullptr;
}

bool ClassLookup::CheckImports(const ast::StoredDefinition& f) {
  for (const auto& imp : f.imports) CheckImport(ast::JoinName(imp.name), imp.wildcard, imp.span);
  std::function<void(const ast::ClassDef&)> walk = [&](const ast::ClassDef& c) {
    for (const auto& el : c.elements) {
      if (el.kind == ast::Element::kImport)
        CheckImport(ast::JoinName(el.import->name), el.import->wildcard, el.import->span);
      if (el.kind == ast::Element::kClass) walk(*el.class_def);
    }
  };
  for (const auto& c : f.classes) walk(*c);
  return !diags_.HasErrors();
}

void ClassLookup::CheckImport(const std::string& q, bool wildcard, Span span) {
  bool ok = LookupClass(q) != nullptr;
  if (!ok && wildcard && q == "Kanesim") ok = true;
  if (!ok && wildcard) {
    LoadWholeLibrary();  // a package's classes may be in any unit
    for (const auto& [k, v] : classes_) ok = ok || k.rfind(q + ".", 0) == 0;
  }
  if (ok) return;
  LoadWholeLibrary();  // the hint considers every class
  auto& d = diags_.Error(DiagCode::BadImport, span, "import names nothing: no class or package '" + q + "'");
  std::vector<std::string> names;
  for (const auto& [k, v] : classes_) names.push_back(k);
  std::string best = ClosestName(q, names);
  if (!best.empty()) d.hint = "did you mean '" + best + "'?";
}


std::vector<std::string> ClassLookup::AllNames() const {
  LoadWholeLibrary();
  std::vector<std::string> names;
  names.reserve(classes_.size());
  for (const auto& [k, v] : classes_) names.push_back(k);
  return names;
}

std::string ClassLookup::QualifiedName(const ast::ClassDef* c) const {
  auto it = qualified_of_.find(c);
  return it == qualified_of_.end() ? c->name : it->second;
}

}  // namespace kanesim::lang::elab
