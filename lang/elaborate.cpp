// Loading a program, and the elaboration's driver: its phases in order.
#include "lang/elaborate.h"

#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "lang/elab_connect.h"
#include "lang/elab_emit.h"
#include "lang/elab_eval.h"
#include "lang/elab_instantiate.h"
#include "lang/elab_lookup.h"
#include "lang/elab_set.h"
#include "lang/elab_units.h"
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
static void AddStdlib(const std::vector<std::pair<std::string, std::string>>& stdlib_files, std::string_view image,
                      Program* program, Diagnostics& diags) {
  program->library = program->sources.NumFiles() == 1 ? SharedLibrary(stdlib_files, image) : nullptr;
  if (program->library) {
    for (const auto& src : program->library->Sources()) program->sources.AddShared(src);
    return;
  }
  for (const auto& [name, text] : stdlib_files) ParseInto(program, program->sources.Add(name, text), diags);
}

bool LoadProgramFromText(const std::string& name, const std::string& text,
                         const std::vector<std::pair<std::string, std::string>>& stdlib_files, Program* program,
                         Diagnostics& diags, std::string_view stdlib_image) {
  int f = program->sources.Add(name, text);
  ParseInto(program, f, diags);
  AddStdlib(stdlib_files, stdlib_image, program, diags);
  return !diags.HasErrors();
}

bool LoadProgram(const std::string& path, const std::vector<std::pair<std::string, std::string>>& stdlib_files,
                 Program* program, Diagnostics& diags, std::string_view stdlib_image) {
  std::string text, message;
  switch (ReadSourceFile(path, &text, &message)) {
    case ReadStatus::Ok: return LoadProgramFromText(path, text, stdlib_files, program, diags, stdlib_image);
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

Span SourcePlaces::UserSpan(const Node* n) const {
  const SourceManager& sm = sources_;
  for (const Node* a = n; a; a = a->parent) {
    if (!a->decl) continue;
    const Span s = a->decl->name_span;
    // Library and pseudo files are named "<stdlib>/Parts.mech", "<--set>".
    if (s.valid() && s.file < sm.NumFiles() && sm.Name(s.file).rfind('<', 0) != 0) return s;
  }
  return n->decl ? n->decl->name_span : Span{};
}

flat::SourceLoc SourcePlaces::Loc(Span s) const {
  flat::SourceLoc l;
  const SourceManager& sm = sources_;
  if (!s.valid() || s.file >= sm.NumFiles()) return l;
  // Found once per place: the line search and the file name's interning cost ~200
  // instructions a call.
  const std::uint64_t key = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(s.file)) << 32) |
                            static_cast<std::uint32_t>(s.begin);
  auto [it, fresh] = cache_.try_emplace(key);
  if (!fresh) return it->second;
  LineCol lc = sm.Locate(s.file, s.begin);
  l.file = sm.Name(s.file);
  l.line = lc.line;
  l.col = lc.col;
  it->second = l;
  return l;
}

}  // namespace elab

namespace {

// What elaboration builds for itself and drops at its end: the class registry, the
// instance tree, the phases' tables and caches (kept to the end: freeing them between the
// phases fragments the heap, and repeated loads in one process then peak higher;
// docs/benchmarks/2026-11-28_elaborator_phases.md).
struct Scratch {
  Scratch(const Program& program, flat::Mechanism* out, Diagnostics& diags)
      : lookup(program, diags), places(program.sources), eval(out, places, diags), sets(diags) {}
  elab::ClassLookup lookup;
  elab::SourcePlaces places;
  elab::Evaluator eval;
  elab::InstanceTree tree;
  elab::SetOverrides sets;
  std::optional<elab::Instantiator> instantiator;
  std::optional<elab::Links> links;
  std::optional<elab::Connections> connections;
  std::optional<elab::UnitCheck> units;
};

// A one-shot process ends soon after its one elaboration: the scratch, freed node by node
// otherwise (a fourteenth of a robot's load), stays reachable from a static so that leak
// checkers do not count it.
void LeaveToExit(std::unique_ptr<Scratch> s) {
  static std::mutex mutex;
  static auto* kept = new std::vector<std::unique_ptr<Scratch>>();
  std::lock_guard<std::mutex> lock(mutex);
  kept->push_back(std::move(s));
}

// The phases, in order (each declared in its header, lang/elab_*.h): lookup picks the
// model and checks the imports; --set overrides become the root's modifiers; instantiate
// builds the instance tree, asking evaluate for sizes and conditions; the subscripted
// --set values are bound; connect binds the equations and turns connect() into frame
// identities; emit writes the flat mechanism, evaluating what it reads.
bool RunPhases(const Program& program, const ElaborateOptions& options, flat::Mechanism* out, Diagnostics& diags,
               Scratch& s) {
  const ast::ClassDef* top = s.lookup.PickModel(options.model);
  if (!top) return false;
  if (!program.files.empty() && !s.lookup.CheckImports(*program.files[0])) return false;
  out->model_name = s.lookup.QualifiedName(top);
  out->description = top->description;
  for (int f = 0; f < program.sources.NumFiles(); ++f) out->source_files.push_back(program.sources.Name(f));

  elab::InstanceTree& tree = s.tree;
  tree.root = std::make_unique<elab::Node>();
  if (!s.sets.Parse(options.overrides, program, tree.root.get())) return false;
  s.instantiator.emplace(s.lookup, s.eval, s.places, diags, s.sets.AnySubscripted(), &tree);
  s.instantiator->Run(top);
  s.sets.Bind();
  if (diags.HasErrors()) return false;

  const elab::Links& links = s.links.emplace(elab::BindEquations(tree.root.get(), s.eval, diags));
  if (diags.HasErrors()) return false;
  // Every parameter is one element of a scalar variable, all counted in tree.instances.
  s.eval.ReserveParams(static_cast<size_t>(tree.instances));
  const elab::Connections& connections = s.connections.emplace(elab::Connect(tree, links, s.places, out));
  // Units are checked on the emitter's walk, and reported once the model is otherwise sound.
  if (options.check_units) s.units.emplace(tree, links, &program.sources);
  elab::UnitCheck* units = s.units ? &*s.units : nullptr;
  elab::Emit(tree, connections, links.whens, s.eval, s.places, diags, out, units);
  if (units) units->Finish(tree, diags, out);
  if (const ast::Modification* ex = s.lookup.FindAnnotation(top, "experiment"))
    elab::EmitExperiment(*ex, top, tree.root.get(), s.eval, diags, out);
  if (const ast::Modification* sp = s.lookup.FindAnnotation(top, "speeds")) elab::EmitSpeeds(*sp, diags, out);
  if (out->worlds.size() != 1 && !diags.HasErrors()) {
    auto& d = diags.Error(DiagCode::WorldCount, top->name_span,
                          "'" + top->name + "' has " + std::to_string(out->worlds.size()) +
                              " World components; a mechanism needs exactly one");
    if (out->worlds.empty()) d.hint = "add 'World world;' and connect the first joint to world.frame_b";
  }
  return !diags.HasErrors();
}

}  // namespace

bool Elaborate(const Program& program, const ElaborateOptions& options, flat::Mechanism* out, Diagnostics& diags) {
  *out = flat::Mechanism{};
  if (diags.HasErrors()) return false;
  auto scratch = std::make_unique<Scratch>(program, out, diags);
  const bool ok = RunPhases(program, options, out, diags, *scratch);
  if (options.leave_scratch_to_exit) LeaveToExit(std::move(scratch));
  return ok;
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
