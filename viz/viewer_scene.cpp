#include "viz/viewer_scene.h"

#include <fmt/format.h>

#include <cmath>
#include <set>

namespace kanesim::viz {
namespace {

// A quaternion may be off unit length by this much (it is then normalised); more is an error
// (the same tolerance as the glTF export).
constexpr double kUnitTolerance = 1e-4;

std::string CheckMesh(const VisualMesh& m, const std::string& what) {
  if (m.normals.size() != m.vertices.size())
    return fmt::format("{}: {} normals for {} vertices", what, m.normals.size(), m.vertices.size());
  for (const geometry::Tri& t : m.triangles)
    for (uint32_t i : t)
      if (i >= m.vertices.size())
        return fmt::format("{}: a triangle refers to vertex {} of {}", what, i, m.vertices.size());
  for (size_t i = 0; i < m.vertices.size(); ++i)
    if (!m.vertices[i].allFinite() || !m.normals[i].allFinite())
      return fmt::format("{}: vertex {} has a non-finite position or normal", what, i);
  return "";
}

std::string CheckColour(const std::array<float, 4>& rgba, const std::string& what) {
  for (float c : rgba)
    if (!(c >= 0 && c <= 1)) return fmt::format("{}: colour components must be in [0, 1]", what);
  return "";
}

std::string CheckBodies(const ViewerScene& scene) {
  std::set<std::string> names;
  for (const ViewerBody& b : scene.bodies) {
    if (b.name.empty()) return "a body has an empty name";
    if (!names.insert(b.name).second) return fmt::format("two bodies are named '{}'", b.name);
    const std::string what = fmt::format("body '{}'", b.name);
    std::string error = CheckMesh(b.mesh, what);
    if (error.empty()) error = CheckColour(b.rgba, what);
    if (!error.empty()) return error;
  }
  for (size_t i = 0; i < scene.decorations.size(); ++i) {
    const ViewerDecoration& d = scene.decorations[i];
    const std::string what = fmt::format("decoration {} ('{}')", i, d.name);
    if (d.body < -1 || d.body >= static_cast<int>(scene.bodies.size()))
      return fmt::format("{}: carried by body {}, but there are {} bodies", what, d.body, scene.bodies.size());
    std::string error = CheckMesh(d.mesh, what);
    if (error.empty()) error = CheckColour(d.rgba, what);
    if (!error.empty()) return error;
  }
  return "";
}

std::string CheckMotion(const ViewerScene& scene) {
  const geometry::PoseSequence& poses = scene.poses;
  const size_t n = poses.times.size();
  const size_t n_bodies = scene.bodies.size();
  if (n == 0) return "no instants to show";
  if (poses.p_WB.size() != n * n_bodies || poses.q_WB.size() != n * n_bodies)
    return fmt::format("{} positions and {} rotations for {} instants of {} bodies (need {} each)", poses.p_WB.size(),
                       poses.q_WB.size(), n, n_bodies, n * n_bodies);
  for (size_t k = 0; k < n; ++k) {
    const double t = poses.times[k];
    if (!std::isfinite(t)) return fmt::format("time {} at instant {} is not finite", t, k);
    if (k > 0 && t < poses.times[k - 1])
      return fmt::format("times must not decrease: {} after {} at instant {}", t, poses.times[k - 1], k);
  }
  for (size_t i = 0; i < n * n_bodies; ++i) {
    const double norm = poses.q_WB[i].norm();
    if (!poses.p_WB[i].allFinite() || !std::isfinite(norm) || std::abs(norm - 1) > kUnitTolerance)
      return fmt::format("body '{}' at t = {}: position not finite or rotation not a unit quaternion (norm {})",
                         scene.bodies[i % n_bodies].name, poses.times[i / n_bodies], norm);
  }
  return "";
}

std::string CheckSignals(const ViewerScene& scene) {
  std::set<std::string> names;
  for (const ViewerSignal& s : scene.signals) {
    if (s.name.empty()) return "a signal has an empty name";
    if (!names.insert(s.name).second) return fmt::format("two signals are named '{}'", s.name);
    if (s.values.size() != scene.poses.times.size())
      return fmt::format("signal '{}' has {} values for {} instants", s.name, s.values.size(),
                         scene.poses.times.size());
  }
  return "";
}

}  // namespace

std::string CheckScene(const ViewerScene& scene) {
  if (!scene.up_W.allFinite() || scene.up_W.norm() == 0) return "the up direction must be a finite non-zero vector";
  std::string error = CheckBodies(scene);
  if (error.empty()) error = CheckMotion(scene);
  if (error.empty()) error = CheckSignals(scene);
  for (const ViewerEvent& e : scene.events)
    if (error.empty() && !std::isfinite(e.time)) error = fmt::format("event '{}' at a time that is not finite", e.element);
  return error;
}

}  // namespace kanesim::viz
