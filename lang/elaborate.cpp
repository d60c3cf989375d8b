// Loading a program, and the elaboration's driver: its phases in order.
#include "lang/elaborate.h"

#include <memory>
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

// The model file `f`, already in program->sources, parsed, then the standard library added.
static bool ParseWithStdlib(int f, const std::vector<std::pair<std::string, std::string>>& stdlib_files,
                            Program* program, Diagnostics& diags, std::string_view stdlib_image) {
  ParseInto(program, f, diags);
  AddStdlib(stdlib_files, stdlib_image, program, diags);
  return !diags.HasErrors();
}

bool LoadProgramFromText(const std::string& name, const std::string& text,
                         const std::vector<std::pair<std::string, std::string>>& stdlib_files, Program* program,
                         Diagnostics& diags, std::string_view stdlib_image) {
  return ParseWithStdlib(program->sources.Add(name, text), stdlib_files, program, diags, stdlib_image);
}

bool LoadProgram(const std::string& path, const std::vector<std::pair<std::string, std::string>>& stdlib_files,
                 Program* program, Diagnostics& diags, std::string_view stdlib_image) {
  std::string text, message;
  switch (ReadSourceFile(path, &text, &message)) {
    case ReadStatus::Ok:  // the text read moves into the sources, not copied
      return ParseWithStdlib(program->sources.Add(path, std::move(text)), stdlib_files, program, diags, stdlib_image);
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

// An elaboration's object kept to the process's exit (ElaborateOptions::leave_to_exit).
template <class T>
static void LeaveToExit(std::unique_ptr<T> object) {
  static auto* kept = new std::vector<std::shared_ptr<void>>();
  kept->emplace_back(std::move(object));
}

// The phases, in order (each declared in its header, lang/elab_*.h): lookup picks the
// model and checks the imports; --set overrides become the root's modifiers; instantiate
// builds the instance tree, asking evaluate for sizes and conditions; the subscripted
// --set values are bound; connect binds the equations and turns connect() into frame
// identities; emit writes the flat mechanism, evaluating what it reads.
bool Elaborate(const Program& program, const ElaborateOptions& options, flat::Mechanism* out, Diagnostics& diags) {
  *out = flat::Mechanism{};
  if (diags.HasErrors()) return false;
  elab::ClassLookup lookup(program, diags);
  const ast::ClassDef* top = lookup.PickModel(options.model);
  if (!top) return false;
  if (!program.files.empty() && !lookup.CheckImports(*program.files[0])) return false;
  out->model_name = lookup.QualifiedName(top);
  out->description = top->description;
  for (int f = 0; f < program.sources.NumFiles(); ++f) out->source_files.push_back(program.sources.Name(f));

  elab::SourcePlaces places(program.sources);
  elab::Evaluator eval(out, places, diags);
  eval.ReadDataFrom(options.data_files);
  auto tree_owner = std::make_unique<elab::InstanceTree>();
  elab::InstanceTree& tree = *tree_owner;
  tree.root = tree.arena.New();
  elab::SetOverrides sets(diags);
  if (!sets.Parse(options.overrides, program, tree.root.get())) return false;
  // Kept to the end with its per-class caches: freeing them between the phases fragments
  // the heap, and repeated loads in one process then peak higher
  // (docs/benchmarks/2026-11-28_elaborator_phases.md).
  auto instantiator = std::make_unique<elab::Instantiator>(lookup, eval, places, diags, sets.AnySubscripted(),
                                                            options.share_siblings, &tree);
  instantiator->Run(top);
  sets.Bind();
  if (diags.HasErrors()) return false;

  const elab::Links links = elab::BindEquations(tree.root.get(), eval, diags);
  if (diags.HasErrors()) return false;
  // Every parameter is one element of a scalar variable, all counted in tree.instances.
  eval.ReserveParams(static_cast<size_t>(tree.instances));
  const elab::Connections connections = elab::Connect(tree, links, places, out);
  // Units are checked on the emitter's walk, and reported once the model is otherwise sound.
  std::optional<elab::UnitCheck> units;
  if (options.check_units) units.emplace(tree, links, &program.sources);
  elab::Emit(tree, connections, links.whens, eval, places, diags, out, units ? &*units : nullptr);
  if (units) units->Finish(tree, diags, out);
  if (const ast::Modification* ex = lookup.FindAnnotation(top, "experiment"))
    elab::EmitExperiment(*ex, top, tree.root.get(), eval, diags, out);
  if (const ast::Modification* sp = lookup.FindAnnotation(top, "speeds")) elab::EmitSpeeds(*sp, diags, out);
  if (out->worlds.size() != 1 && !diags.HasErrors()) {
    auto& d = diags.Error(DiagCode::WorldCount, top->name_span,
                          "'" + top->name + "' has " + std::to_string(out->worlds.size()) +
                              " World components; a mechanism needs exactly one");
    if (out->worlds.empty()) d.hint = "add 'World world;' and connect the first joint to world.frame_b";
  }
  if (options.leave_to_exit) {
    LeaveToExit(std::move(instantiator));
    LeaveToExit(std::move(tree_owner));
  }
  return !diags.HasErrors();
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
