// Mesh functions of the language: the mass properties of the solid a closed triangle mesh
// encloses, read once per elaboration and file (geometry; assimp is loaded only
// here, the first time a scene names a mesh). The stdlib's MeshBody is written with them:
//
//   meshVolume(file, scale)   V  (m³)                        the enclosed volume
//   meshCentre(file, scale)   p_MBcm  (m), Real[3]           centre of the volume, in the file's frame M
//   meshInertia(file, scale)  I_Bcm_M / ρ  (m⁵), Real[3, 3]  inertia about it of unit density, resolved in M
//
// so that a MeshBody's m = density * V (or a given m) and I = m / V * meshInertia stay
// parameter expressions (a sweep over density or m needs no new elaboration; file and scale
// are structural). Equations and sources: docs/visualization.md ("Mass properties").
//
// Paths are relative to the file that gives the mesh's name: the `.mech` file of the
// modifier `file = "..."` (followed through parameters that pass it on), or the working
// directory for a `--set`. The mesh's problems become diagnostics at that place (codes
// E230-E235, W302-W303; the mapping is MeshDiagCode below).
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/core.h>

#include "lang/elab_eval.h"
#include "geometry/mass_properties.h"
#include "geometry/mesh_load.h"

namespace kanesim::lang::elab {

namespace {

// One row per geometry::MeshProblemKind: the diagnostic a mesh problem becomes.
DiagCode MeshDiagCode(geometry::MeshProblemKind k) {
  using K = geometry::MeshProblemKind;
  switch (k) {
    case K::kFileMissing: return DiagCode::MeshFileMissing;
    case K::kFileUnreadable:
    case K::kModuleMissing:
    case K::kImportFailed:
    case K::kNoTriangles:
    case K::kNotRegularFile:
    case K::kDeclaredBeyondFile:
    case K::kNonFinite: return DiagCode::MeshUnreadable;
    case K::kTooLarge: return DiagCode::MeshTooLarge;
    case K::kBadScale: return DiagCode::BadValue;
    case K::kNotClosed: return DiagCode::MeshNotClosed;
    case K::kInconsistentOrientation: return DiagCode::MeshOrientation;
    case K::kZeroVolume: return DiagCode::MeshZeroVolume;
    case K::kInsideOut: return DiagCode::MeshInsideOut;
    case K::kDegenerateTriangles:
    case K::kNonManifold: return DiagCode::MeshDegenerate;
  }
  return DiagCode::MeshUnreadable;
}

const char* MeshHint(geometry::MeshProblemKind k) {
  using K = geometry::MeshProblemKind;
  switch (k) {
    case K::kFileMissing: return "paths are relative to the .mech file that names the mesh";
    case K::kNotClosed:
    case K::kInconsistentOrientation:
      return "a MeshBody needs a closed, consistently oriented surface (a watertight solid); repair it in the "
             "modelling tool, or give the mass properties with a Body";
    case K::kZeroVolume: return "is the mesh flat, or is `scale` far too small?";
    case K::kTooLarge: return "decimate the mesh; the limits are in docs/visualization.md";
    case K::kNotRegularFile: return "name a regular mesh file; a pipe or a device cannot be read as a mesh";
    case K::kDeclaredBeyondFile:
      return "the file's header claims more data than the file has: it is truncated or was written wrongly; "
             "export the mesh again";
    case K::kInsideOut: return "the mass properties are those of the flipped (outward) surface";
    default: return "";
  }
}

}  // namespace

std::string Evaluator::MeshPath(const std::string& file, Span origin) const {
  namespace fs = std::filesystem;
  fs::path p(file);
  if (p.is_absolute() || !origin.valid() || origin.file >= places_.Sources().NumFiles()) return file;
  const std::string& from = places_.Sources().Name(origin.file);
  if (from.empty() || from[0] == '<') return file;  // the standard library, a --set: the working directory
  return (fs::path(from).parent_path() / p).lexically_normal().string();
}

Span Evaluator::ValueOrigin(const ast::Expr& arg, const Ctx& ctx) {
  Span origin = arg.span;
  const ast::Expr* e = &arg;
  Ctx c = ctx;
  for (int hops = 0; hops < 16 && e->kind == ast::ExprKind::Ref; ++hops) {
    Node* var = ResolveNode(*e, c, nullptr);
    if (!var || var->kind != Node::kVar) break;
    const ModValue* b = var->Modifiers().value ? &*var->Modifiers().value : var->eq_binding ? &*var->eq_binding : nullptr;
    if (!b) break;
    origin = b->span;
    if (!b->expr) break;
    e = b->expr;
    c = Ctx{b->scope, b->iters.get()};
  }
  return origin;
}

const Evaluator::MeshEntry* Evaluator::LoadMeshFor(const std::string& path, double scale, Span where) {
  const std::string key = fmt::format("{}\n{:a}", path, scale);
  auto it = meshes_.find(key);
  if (it == meshes_.end()) {
    MeshEntry entry;
    geometry::LoadMeshOptions options;
    options.scale = scale;
    const auto given = data_from_ ? data_from_->find(path) : std::map<std::string, std::string>::const_iterator{};
    geometry::MeshLoadResult r;
    if (!data_from_ || given != data_from_->end()) {
      r = geometry::LoadMesh(data_from_ ? given->second : path, options);
    } else {
      r.problems.push_back(geometry::MakeProblem(geometry::MeshProblemKind::kFileMissing,
                                                 "mesh file not among the files given with the model: " + path));
    }
    if (std::find(m_->data_files.begin(), m_->data_files.end(), path) == m_->data_files.end())
      m_->data_files.push_back(path);
    entry.problems = r.problems;
    if (r.ok()) {
      geometry::MassProperties mp = geometry::ComputeMassProperties(r.mesh, geometry::MassSpec::Density(1.0));
      entry.ok = true;
      entry.triangles = r.mesh.triangles.size();
      entry.volume = mp.volume;
      entry.centre = mp.p_MBcm;
      entry.unit_inertia = mp.I_Bcm_M;
    }
    it = meshes_.emplace(key, std::move(entry)).first;
  }
  MeshEntry& entry = it->second;
  // Each place that names the mesh hears of its problems once.
  if (where.valid() && entry.reported.insert({where.file, where.begin}).second) {
    for (const geometry::MeshProblem& p : entry.problems) {
      DiagCode code = MeshDiagCode(p.kind);
      auto& d = p.severity == geometry::Severity::kError ? diags_.Error(code, where, p.message)
                                                          : diags_.Warning(code, where, p.message);
      d.hint = MeshHint(p.kind);
    }
  }
  return entry.ok ? &entry : nullptr;
}

Value Evaluator::EvalMeshCall(const std::string& fn, const ast::Expr& e, const std::vector<Value>& args,
                              const Ctx& ctx) {
  auto& pool = m_->exprs;
  if (args.size() != 2) {
    diags_.Error(DiagCode::BadCall, e.span,
                 "'" + fn + "' takes 2 argument(s) (file, scale), got " + std::to_string(args.size()));
    return Value::Invalid();
  }
  if (args[0].type != VType::String || !args[0].shape.empty() || args[0].strings.size() != 1) {
    diags_.Error(DiagCode::TypeMismatch, e.args[0]->span, "'" + fn + "' needs the mesh file's name as a String");
    return Value::Invalid();
  }
  double scale = 1;
  if (!Structural(args[1], e.args[1]->span, &scale, "the mesh scale")) return Value::Invalid();
  const Span origin = ValueOrigin(*e.args[0], ctx);
  if (args[0].strings[0].empty()) {
    diags_.Error(DiagCode::MeshFileMissing, origin, "no mesh file given (file = \"\")").hint =
        "name the mesh, e.g. MeshBody crank(file = \"meshes/crank.stl\", density = 7800)";
    return Value::Invalid();
  }
  const MeshEntry* mesh = LoadMeshFor(MeshPath(args[0].strings[0], origin), scale, origin);
  if (!mesh) return Value::Invalid();
  Value v;
  if (fn == "meshVolume") {
    v.elements = {pool.Constant(mesh->volume)};
  } else if (fn == "meshCentre") {
    v.shape = {3};
    for (int i = 0; i < 3; ++i) v.elements.push_back(pool.Constant(mesh->centre[i]));
  } else {
    v.shape = {3, 3};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) v.elements.push_back(pool.Constant(mesh->unit_inertia(i, j)));
  }
  return v;
}

}  // namespace kanesim::lang::elab
