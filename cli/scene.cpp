// The drawn bodies of a mechanism and the recorder of their poses (cli/scene.h).
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "cli/scene.h"
#include "geometry/mesh_load.h"
#include "geometry/primitives.h"
#include "runtime/program/program.h"

namespace kanesim::cli {

namespace {

using geometry::Mat3;
using geometry::Vec3;
using geometry::VisualMesh;

// Distinct, readable colours (linear RGB), one per body in turn.
constexpr std::array<std::array<float, 4>, 8> kPalette{{{0.80f, 0.25f, 0.20f, 1.0f},
                                                       {0.20f, 0.45f, 0.80f, 1.0f},
                                                       {0.90f, 0.65f, 0.15f, 1.0f},
                                                       {0.30f, 0.65f, 0.35f, 1.0f},
                                                       {0.55f, 0.35f, 0.75f, 1.0f},
                                                       {0.20f, 0.65f, 0.70f, 1.0f},
                                                       {0.75f, 0.45f, 0.55f, 1.0f},
                                                       {0.55f, 0.55f, 0.58f, 1.0f}}};

// "#rrggbb" (sRGB, as written by lang/elab_shapes.cpp) as linear RGBA (glTF's and the
// viewer's base colour): c = ((s + 0.055) / 1.055)^2.4, or s / 12.92 below 0.04045.
std::array<float, 4> LinearRgba(const std::string& hex) {
  std::array<float, 4> out{0, 0, 0, 1};
  for (int i = 0; i < 3; ++i) {
    const double s = std::stoi(hex.substr(1 + 2 * static_cast<size_t>(i), 2), nullptr, 16) / 255.0;
    out[static_cast<size_t>(i)] =
        static_cast<float>(s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4));
  }
  return out;
}

// The drawing of a stdlib shape in its body frame, with this run's sizes (flat::Shape).
VisualMesh DrawShape(const flat::Shape& s, const std::vector<double>& size, std::string* error) {
  VisualMesh mesh;
  switch (s.kind) {
    case flat::ShapeKind::Rod:
      // A thin rod has no thickness of its own: drawn 1/50 of its length across.
      if (size[0] > 0) mesh = geometry::DrawRod(size[0], size[0] / 100);
      break;
    case flat::ShapeKind::Box:
      if (size[0] > 0 && size[1] > 0 && size[2] > 0) {
        mesh = geometry::DrawBox(Vec3(size[0], size[1], size[2]));
        geometry::Transform(mesh, Mat3::Identity(), Vec3(size[0] / 2, 0, 0));
      }
      break;
    case flat::ShapeKind::Cylinder:
      if (size[0] > 0 && size[1] > 0) {
        mesh = geometry::DrawCylinder(size[1], size[0]);
        geometry::Transform(mesh, Mat3::Identity(), Vec3(size[0] / 2, 0, 0));
      }
      break;
    case flat::ShapeKind::Sphere:
      if (size[0] > 0) mesh = geometry::DrawSphere(size[0]);
      break;
    case flat::ShapeKind::Mesh: {
      geometry::LoadMeshOptions options;
      options.scale = size[0];
      geometry::VisualMeshResult r = geometry::LoadVisualMesh(s.mesh_file, options);
      for (const auto& p : r.problems)
        if (p.severity == geometry::Severity::kError) {
          *error = fmt::format("{}:{}:{}: cannot draw '{}': {}", s.loc.file.str(), s.loc.line, s.loc.col, s.name, p.message);
          return {};
        }
      mesh = std::move(r.mesh);
      break;
    }
  }
  return mesh;
}

// A bare Body: its inertia-equivalent box, as MuJoCo shows inertias; a point mass (or an
// inertia too thin to see) as a small sphere at its centre of mass.
VisualMesh DrawBareBody(double m, const Vec3& c, const Mat3& I) {
  if (!(m > 0)) return {};
  geometry::EquivalentShape box = geometry::InertiaBox(m, c, I);
  const double largest = box.size.maxCoeff();
  if (largest > 0 && box.size.minCoeff() > 1e-3 * largest) return geometry::Draw(box, false);
  // Radius of a sphere of steel of this mass (a sensible size for a point mass), or the
  // box's largest side when it has one.
  const double r = largest > 0 ? largest / 4 : std::cbrt(3 * m / (4 * M_PI * 7800));
  VisualMesh s = geometry::DrawSphere(r, 2);
  geometry::Transform(s, Mat3::Identity(), c);
  return s;
}

// --show-frames: each joint's frame_a and frame_b (once each) as three nodes. A frame F is
// fixed in a simulated body B; its rotation is not a signal, but that of a body frame G on the
// same B is (<body>.R): R_WF = R_WG R_BG^T R_BF, so the node takes G's rotation and F's origin,
// and its axes are drawn turned by the constant R_GF = R_BG^T R_BF. Frames fixed in the world
// are not drawn (the viewer's world axes show W).
void AddFrameAxes(const flat::Mechanism& mech, const rt::Program& program,
                  const std::unordered_set<std::string>& have, double length, SceneBodies* out) {
  if (!(length > 0)) {
    double extent = 0;
    for (const auto& b : out->bodies)
      for (const auto& v : b.mesh.vertices) extent = std::max(extent, v.norm());
    length = extent > 0 ? extent / 10 : 0.1;
  }
  const std::array<VisualMesh, 3> axes = geometry::DrawAxes(length);
  static constexpr std::array<std::array<float, 4>, 3> kAxisColor{
      {{0.85f, 0.1f, 0.1f, 1.0f}, {0.1f, 0.7f, 0.1f, 1.0f}, {0.1f, 0.2f, 0.9f, 1.0f}}};
  std::unordered_set<int> done;
  for (const flat::Joint& j : mech.joints) {
    for (const std::int32_t f : {j.frame_a, j.frame_b}) {
      if (f < 0 || !done.insert(f).second) continue;
      const rt::FramePlace& place = program.frames[static_cast<size_t>(f)];
      if (place.body < 0) continue;  // the world's, or not simulated
      const std::string& frame = mech.frames[static_cast<size_t>(f)].name;
      const rt::BodySignalSource* g = nullptr;
      for (const auto& bs : program.body_signals)
        if (program.frames[static_cast<size_t>(bs.frame)].body == place.body) {
          g = &bs;
          break;
        }
      if (!g) continue;  // a body without mass properties: no rotation signal to follow
      std::vector<std::string> signals;
      for (int k = 1; k <= 3; ++k) signals.push_back(fmt::format("{}.r[{}]", frame, k));
      for (int k = 0; k < 9; ++k) signals.push_back(fmt::format("{}.R[{},{}]", g->name, k / 3 + 1, k % 3 + 1));
      if (!std::all_of(signals.begin(), signals.end(), [&](const std::string& s) { return have.count(s) > 0; }))
        continue;
      const Mat3 R_GF = program.frames[static_cast<size_t>(g->frame)].R_BF.transpose() * place.R_BF;
      for (int i = 0; i < 3; ++i) {
        geometry::AnimatedBody ab;
        ab.name = fmt::format("axes_{}_{}", frame, "xyz"[i]);
        ab.mesh = axes[static_cast<size_t>(i)];
        geometry::Transform(ab.mesh, R_GF, Vec3::Zero());
        ab.rgba = kAxisColor[static_cast<size_t>(i)];
        out->bodies.push_back(std::move(ab));
        out->labels.push_back(fmt::format("{} axis of frame {} (joint {})", "xyz"[i], frame, j.name));
        out->pose_signals.insert(out->pose_signals.end(), signals.begin(), signals.end());
      }
    }
  }
}

}  // namespace

bool BuildSceneBodies(const flat::Mechanism& mech, const rt::Program& program, SceneBodies* out, std::string* error,
                      bool show_frames, double frame_axes_length) {
  *out = SceneBodies{};
  const std::vector<double> p = flat::EvaluateParams(mech);
  auto val = [&](flat::ExprId e) { return e == flat::kNoExpr ? 0.0 : flat::EvalParamExpr(mech, p, e); };
  if (!mech.worlds.empty()) {
    const auto& g = mech.worlds[0].gravity;
    const Vec3 gW(val(g[0]), val(g[1]), val(g[2]));
    if (gW.allFinite() && gW.norm() > 0) out->up_W = -gW.normalized();
  }
  std::vector<const flat::Shape*> shape_of(mech.bodies.size(), nullptr);
  for (const auto& s : mech.shapes)
    if (s.body >= 0) shape_of[static_cast<size_t>(s.body)] = &s;
  // The RollingDisk contact whose centre is frame f, if any.
  auto disk_of = [&](std::int32_t f) -> const flat::Contact* {
    for (const flat::Contact& c : mech.contacts)
      if (c.type == flat::ContactType::RollingDisk && c.frame == f) return &c;
    return nullptr;
  };
  const std::vector<std::string> available = rt::AvailableSignals(program);
  const std::unordered_set<std::string> have(available.begin(), available.end());
  for (size_t i = 0; i < mech.bodies.size(); ++i) {
    const flat::Body& b = mech.bodies[i];
    if (b.frame < 0) continue;
    const std::string& frame = mech.frames[static_cast<size_t>(b.frame)].name;
    std::vector<std::string> signals;
    for (int k = 1; k <= 3; ++k) signals.push_back(fmt::format("{}.r[{}]", frame, k));
    for (int k = 0; k < 9; ++k) signals.push_back(fmt::format("{}.R[{},{}]", b.name, k / 3 + 1, k % 3 + 1));
    if (!std::all_of(signals.begin(), signals.end(), [&](const std::string& s) { return have.count(s) > 0; }))
      continue;  // not simulated (connected to nothing that moves or is grounded)
    if (shape_of[i] && !shape_of[i]->visual) continue;  // visual = false
    geometry::AnimatedBody ab;
    ab.rgba = kPalette[out->bodies.size() % kPalette.size()];
    std::string label;
    if (const flat::Shape* s = shape_of[i]) {
      if (!s->color.empty()) ab.rgba = LinearRgba(s->color);
      std::vector<double> size{val(s->size[0]), val(s->size[1]), val(s->size[2])};
      ab.name = s->name;
      ab.mesh = DrawShape(*s, size, error);
      if (!error->empty()) return false;
      static const char* kClass[] = {"Rod", "Box", "Cylinder", "Sphere", "MeshBody"};
      const bool looks_only = s->kind == flat::ShapeKind::Mesh && mech.FindParam(s->name + ".volume") < 0;
      label = fmt::format("{} {}", looks_only ? "BodyShape" : kClass[static_cast<int>(s->kind)], s->name);
      if (s->kind == flat::ShapeKind::Mesh) label += " (" + s->mesh_file + ")";
    } else if (const flat::Contact* d = disk_of(b.frame)) {
      // A bare Body rolling on a RollingDisk contact: the disk, centred on the contact's frame
      // (its centre) with its axis, radius / 10 thick.
      const double radius = val(d->radius);
      ab.name = b.name;
      const Vec3 axis(val(d->axis[0]), val(d->axis[1]), val(d->axis[2]));
      if (radius > 0 && axis.allFinite() && axis.norm() > 0) ab.mesh = geometry::DrawDisk(radius, radius / 10, axis);
      label = fmt::format("Body {} (rolling disk {}, radius {:.6g} m)", b.name, d->name, radius);
    } else {
      const Vec3 c(val(b.r_cm[0]), val(b.r_cm[1]), val(b.r_cm[2]));
      Mat3 I;
      for (int k = 0; k < 9; ++k) I(k / 3, k % 3) = val(b.inertia[static_cast<size_t>(k)]);
      ab.name = b.name;
      ab.mesh = DrawBareBody(val(b.mass), c, I);
      label = fmt::format("Body {} (inertia-equivalent box)", b.name);
    }
    const flat::SourceLoc& at = shape_of[i] ? shape_of[i]->loc : b.loc;
    if (!at.file.empty()) label += fmt::format(", {}:{}", at.file.str(), at.line);
    out->bodies.push_back(std::move(ab));
    out->labels.push_back(label);
    out->pose_signals.insert(out->pose_signals.end(), signals.begin(), signals.end());
  }
  if (show_frames) AddFrameAxes(mech, program, have, frame_axes_length, out);
  return true;
}

bool PoseRecorder::Begin(const std::vector<std::string>& names) {
  shown_names_.assign(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(std::min(n_shown_, names.size())));
  return inner_ ? inner_->Begin(shown_names_) : true;
}

bool PoseRecorder::Row(double t, const double* values, size_t count) {
  if (count < n_shown_ + 12 * n_bodies_) return false;
  if (inner_ && !inner_->Row(t, values, n_shown_)) return false;
  if (keep_shown_) shown_.insert(shown_.end(), values, values + n_shown_);
  poses_.times.push_back(t);
  for (size_t b = 0; b < n_bodies_; ++b) {
    const double* x = values + n_shown_ + 12 * b;
    poses_.p_WB.emplace_back(x[0], x[1], x[2]);
    Mat3 R;
    for (int k = 0; k < 9; ++k) R(k / 3, k % 3) = x[3 + k];
    Eigen::Quaterniond q(R);
    poses_.q_WB.push_back(q.normalized());
  }
  return true;
}

}  // namespace kanesim::cli
