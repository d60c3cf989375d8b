// Elaboration driver: loading files, the class registry and lookup, --set overrides,
// and the order of the phases (instantiate, equations, emit).
#include "lang/elaborate.h"

#include <algorithm>
#include <functional>
#include <fstream>
#include <sstream>

#include "lang/elab_internal.h"
#include "lang/library_cache.h"
#include "lang/parser.h"

namespace kanesim::lang {

static bool ParseInto(Program* program, int file, Diagnostics& diags) {
  auto def = Parse(file, program->sources, diags);
  program->files.push_back(std::move(def));
  return true;
}

// The library's text goes into this Program's sources (for diagnostics), shared, not
// copied. Its classes are parsed on demand, once per process (lang/library_cache.h); that
// needs the main file to be file 0 so that their file ids match (otherwise the library is
// parsed here, whole).
static void AddStdlib(const std::vector<std::pair<std::string, std::string>>& stdlib_files, Program* program,
                      Diagnostics& diags) {
  program->library = program->sources.NumFiles() == 1 ? SharedLibrary(stdlib_files) : nullptr;
  if (program->library) {
    for (const auto& src : program->library->Sources()) program->sources.AddShared(src);
    return;
  }
  for (const auto& [name, text] : stdlib_files) ParseInto(program, program->sources.Add(name, text), diags);
}

bool LoadProgramFromText(const std::string& name, const std::string& text,
                         const std::vector<std::pair<std::string, std::string>>& stdlib_files, Program* program,
                         Diagnostics& diags) {
  int f = program->sources.Add(name, text);
  ParseInto(program, f, diags);
  AddStdlib(stdlib_files, program, diags);
  return !diags.HasErrors();
}

bool LoadProgram(const std::string& path, const std::vector<std::pair<std::string, std::string>>& stdlib_files,
                 Program* program, Diagnostics& diags) {
  std::string text, message;
  switch (ReadSourceFile(path, &text, &message)) {
    case ReadStatus::Ok: return LoadProgramFromText(path, text, stdlib_files, program, diags);
    case ReadStatus::TooLarge:
      diags.Error(DiagCode::FileTooLarge, Span{}, message).hint = "split the model into several files";
      return false;
    case ReadStatus::NotAFile:
      diags.Error(DiagCode::NotAModel, Span{}, message).hint = "give the path of a .mech file";
      return false;
    case ReadStatus::CannotOpen: break;
  }
  diags.Error(DiagCode::NotAModel, Span{}, message).hint = "check the path";
  return false;
}

namespace elab {

Elaborator::Elaborator(const Program& program, const ElaborateOptions& options, flat::Mechanism* out,
                       Diagnostics& diags)
    : program_(program), options_(options), m_(out), diags_(diags), library_(program.library.get()) {
  for (const auto& f : program.files)
    for (const auto& c : f->classes) Register(c.get(), ast::JoinName(f->within), f.get());
  if (library_) unit_loaded_.assign(static_cast<size_t>(library_->NumUnits()), 0);
}

void Elaborator::Register(const ast::ClassDef* c, const std::string& prefix, const ast::StoredDefinition* file) const {
  std::string q = prefix.empty() ? c->name : prefix + "." + c->name;
  if (!classes_.count(q)) classes_[q] = {c, file, q};
  file_of_[c] = file;
  qualified_of_[c] = q;
  for (const auto& el : c->elements)
    if (el.kind == ast::Element::kClass) Register(el.class_def.get(), q, file);
}

void Elaborator::LoadUnit(int u) const {
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
bool Elaborator::LoadLibraryClass(const std::string& q) const {
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

void Elaborator::LoadWholeLibrary() const {
  if (library_)
    for (int u = 0; u < library_->NumUnits(); ++u) LoadUnit(u);
}

const ClassInfo* Elaborator::LookupClass(const std::string& q) const {
  auto it = classes_.find(q);
  if (it == classes_.end() && LoadLibraryClass(q)) it = classes_.find(q);
  return it == classes_.end() ? nullptr : &it->second;
}

const ast::StoredDefinition* Elaborator::FileOf(const ast::ClassDef* c) const {
  auto it = file_of_.find(c);
  return it == file_of_.end() ? nullptr : it->second;
}

const ast::ClassDef* Elaborator::FindClass(const std::vector<std::string>& parts, const ast::ClassDef* from) const {
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

// The stages, in order: the model picked, its imports checked, instantiated with the --set
// overrides bound, equations bound, flat mechanism emitted, experiment read.
bool Elaborator::Run() {
  const ast::ClassDef* top = PickModel();
  if (!top) return false;
  if (!program_.files.empty() && !CheckImports(*program_.files[0])) return false;
  m_->model_name = qualified_of_.count(top) ? qualified_of_.at(top) : top->name;
  m_->description = top->description;
  for (int f = 0; f < program_.sources.NumFiles(); ++f) m_->source_files.push_back(program_.sources.Name(f));

  root_ = std::make_unique<Node>();
  root_->kind = Node::kClass;
  root_->path = "";

  if (!ParseSetOverrides()) return false;

  // The unknown-modifier check at the root would report --set names; do our own check
  // with a better message first.
  Instantiate(root_.get(), top, top);
  BindSetOverrides();
  if (diags_.HasErrors()) return false;
  ProcessEquations(root_.get());
  if (diags_.HasErrors()) return false;
  // Every parameter is one element of a scalar variable, all counted by instances_: the
  // parameter table grows to its size once instead of by doubling (each step moving
  // every Param).
  m_->params.reserve(static_cast<size_t>(instances_));
  pvals_.reserve(static_cast<size_t>(instances_));
  Emit(root_.get());

  if (const ast::Modification* ex = FindAnnotation(top, "experiment")) ReadExperiment(*ex, top);
  if (m_->worlds.size() != 1 && !diags_.HasErrors()) {
    auto& d = diags_.Error(DiagCode::WorldCount, top->name_span,
                           "'" + top->name + "' has " + std::to_string(m_->worlds.size()) +
                               " World components; a mechanism needs exactly one");
    if (m_->worlds.empty()) d.hint = "add 'World world;' and connect the first joint to world.frame_b";
  }
  return !diags_.HasErrors();
}

// The model named by --model, else the last non-partial model of the user's file; null
// after a diagnostic (or with no file).
const ast::ClassDef* Elaborator::PickModel() {
  const ast::ClassDef* top = nullptr;
  if (options_.model.empty()) {
    if (program_.files.empty()) return nullptr;
    for (const auto& c : program_.files[0]->classes)
      if (c->kind == ast::ClassKind::Model && !c->partial) top = c.get();
    if (!top)
      diags_.Error(DiagCode::NotAModel, Span{0, 0, 0}, "the file declares no (non-partial) model")
          .hint = "write 'model Name ... end Name;' or choose one with --model";
    return top;
  }
  std::vector<std::string> parts;
  std::stringstream ss(options_.model);
  std::string p;
  while (std::getline(ss, p, '.')) parts.push_back(p);
  top = FindClass(parts, nullptr);
  if (!top && !program_.files.empty())
    for (const auto& c : program_.files[0]->classes)
      if (c->name == parts[0]) top = FindClass(parts, c.get());
  if (top) return top;
  auto& d = diags_.Error(DiagCode::NotAModel, Span{}, "no class named '" + options_.model + "'");
  LoadWholeLibrary();  // the hint considers every class
  std::vector<std::string> names;
  for (auto& [k, v] : classes_) names.push_back(k);
  std::string best = ClosestName(options_.model, names);
  if (!best.empty()) d.hint = "did you mean '" + best + "'?";
  return nullptr;
}

// Every import of the user's file must name something.
bool Elaborator::CheckImports(const ast::StoredDefinition& f) {
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

void Elaborator::CheckImport(const std::string& q, bool wildcard, Span span) {
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

// The experiment annotation: StartTime, StopTime, Tolerance, Interval.
void Elaborator::ReadExperiment(const ast::Modification& ex, const ast::ClassDef* top) {
  static const std::vector<std::string> kKnown{"StartTime", "StopTime", "Tolerance", "Interval"};
  Ctx ctx{root_.get(), nullptr};
  auto& x = m_->experiment;
  for (const auto& a : ex.args) {
    if (a.path.size() != 1 || !a.mod || !a.mod->value) continue;
    const std::string& key = a.path[0];
    if (std::find(kKnown.begin(), kKnown.end(), key) == kKnown.end()) {
      auto& d = diags_.Warning(DiagCode::UnknownModifier, a.name_span, "unknown experiment setting '" + key + "' (ignored)");
      std::string best = ClosestName(key, kKnown);
      if (!best.empty()) d.hint = "did you mean '" + best + "'?";
      continue;
    }
    double v = 0;
    if (!Structural(Eval(*a.mod->value, ctx), a.mod->value->span, &v, key.c_str())) continue;
    if (key == "StartTime") x.start_time = v, x.has_start = true;
    else if (key == "StopTime") x.stop_time = v, x.has_stop = true;
    else if (key == "Tolerance") x.tolerance = v, x.has_tolerance = true;
    else x.interval = v, x.has_interval = true;
  }
  if (x.stop_time <= x.start_time)
    diags_.Error(DiagCode::BadValue, top->name_span, "experiment StopTime must be after StartTime");
  if (x.tolerance <= 0 || x.tolerance >= 1)
    diags_.Error(DiagCode::BadValue, top->name_span, "experiment Tolerance must be in (0, 1)");
  if (x.has_interval && x.interval <= 0)
    diags_.Error(DiagCode::BadValue, top->name_span, "experiment Interval must be positive");
}

}  // namespace elab

bool Elaborate(const Program& program, const ElaborateOptions& options, flat::Mechanism* out, Diagnostics& diags) {
  *out = flat::Mechanism{};
  if (diags.HasErrors()) return false;
  elab::Elaborator e(program, options, out, diags);
  return e.Run();
}

std::vector<std::string> StdlibModels(const Program& program) {
  std::vector<std::string> out;
  std::vector<std::shared_ptr<const ast::StoredDefinition>> files = program.files;
  if (program.library)
    for (int u = 0; u < program.library->NumUnits(); ++u) files.push_back(program.library->Unit(u));
  for (const auto& f : files) {
    if (ast::JoinName(f->within) != "Kanesim") continue;
    for (const auto& c : f->classes)
      if (c->kind == ast::ClassKind::Model && !c->partial) out.push_back("Kanesim." + c->name);
  }
  return out;
}

}  // namespace kanesim::lang
