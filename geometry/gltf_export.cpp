#include "geometry/gltf_export.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <numbers>
#include <set>

#include "geometry/assimp_module.h"

namespace kanesim::geometry {
namespace {

// A quaternion may be off unit length by this much (it is then normalised); more is an error.
constexpr double kUnitTolerance = 1e-4;

// The assimp exporter id for a file name, or empty.
std::string FormatOf(const std::string& path) {
  auto ends = [&](const char* ext) {
    const std::string e(ext);
    if (path.size() < e.size()) return false;
    std::string tail = path.substr(path.size() - e.size());
    for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return tail == e;
  };
  if (ends(".glb")) return "glb2";
  if (ends(".gltf")) return "gltf2";
  return "";
}

std::string CheckBodies(const std::vector<AnimatedBody>& bodies) {
  if (bodies.empty()) return "no bodies to animate";
  for (const AnimatedBody& b : bodies) {
    const VisualMesh& m = b.mesh;
    if (m.normals.size() != m.vertices.size())
      return fmt::format("body '{}': {} normals for {} vertices", b.name, m.normals.size(), m.vertices.size());
    for (const Tri& t : m.triangles)
      for (uint32_t i : t)
        if (i >= m.vertices.size())
          return fmt::format("body '{}': a triangle refers to vertex {} of {}", b.name, i, m.vertices.size());
    for (size_t i = 0; i < m.vertices.size(); ++i)
      if (!m.vertices[i].allFinite() || !m.normals[i].allFinite() || m.normals[i].norm() == 0)
        return fmt::format("body '{}': vertex {} has a non-finite position or normal, or a zero normal", b.name, i);
    for (float c : b.rgba)
      if (!(c >= 0 && c <= 1)) return fmt::format("body '{}': colour components must be in [0, 1]", b.name);
  }
  return "";
}

std::string CheckPoses(const PoseSequence& poses, size_t n_bodies) {
  const size_t n = poses.times.size();
  if (n == 0) return "no instants to animate";
  if (poses.p_WB.size() != n * n_bodies || poses.q_WB.size() != n * n_bodies)
    return fmt::format("{} positions and {} rotations for {} instants of {} bodies (need {} each)", poses.p_WB.size(),
                       poses.q_WB.size(), n, n_bodies, n * n_bodies);
  for (size_t k = 0; k < n; ++k) {
    const double t = poses.times[k];
    if (!std::isfinite(t) || t < 0) return fmt::format("time {} at instant {} is not finite and >= 0", t, k);
    if (k > 0 && t < poses.times[k - 1])
      return fmt::format("times must not decrease: {} after {} at instant {}", t, poses.times[k - 1], k);
  }
  for (size_t i = 0; i < n * n_bodies; ++i) {
    const double norm = poses.q_WB[i].norm();
    if (!poses.p_WB[i].allFinite() || !std::isfinite(norm) || std::abs(norm - 1) > kUnitTolerance)
      return fmt::format("pose {} of body {} at t = {}: position not finite or rotation not a unit quaternion "
                         "(norm {})",
                         i / n_bodies, i % n_bodies, poses.times[i / n_bodies], norm);
  }
  return "";
}

// The instants to write: every stride-th (and the last) when there are more keys than
// max_keys; then an instant whose float time does not advance replaces the one before.
std::vector<size_t> ChooseInstants(const PoseSequence& poses, size_t n_bodies, uint64_t max_keys,
                                   ExportResult& result, std::string& error) {
  const size_t n = poses.times.size();
  const uint64_t per_body = max_keys / n_bodies;
  uint64_t stride = 1;
  if (uint64_t(n) * n_bodies > max_keys) {
    if (per_body < 2) {
      error = fmt::format("{} bodies leave fewer than 2 keys each under the limit of {} keys", n_bodies, max_keys);
      return {};
    }
    stride = (n - 1 + per_body - 2) / (per_body - 1);  // ceil((n − 1) / (per_body − 1))
  }
  std::vector<size_t> chosen;
  for (size_t k = 0; k < n; k += stride) chosen.push_back(k);
  if (chosen.back() != n - 1) chosen.push_back(n - 1);
  std::vector<size_t> kept;
  for (size_t k : chosen) {
    if (!kept.empty() && static_cast<float>(poses.times[k]) <= static_cast<float>(poses.times[kept.back()])) {
      kept.back() = k;
      ++result.times_merged;
    } else {
      kept.push_back(k);
    }
  }
  result.stride = stride;
  return kept;
}

std::array<double, 4> Wxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

}  // namespace

Eigen::Quaterniond UpToY(const Vec3& up_W) {
  const Vec3 up = up_W.normalized();
  if (up.dot(Vec3::UnitY()) < -1 + 1e-12) return Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX()));
  return Eigen::Quaterniond::FromTwoVectors(up, Vec3::UnitY());
}

std::vector<std::string> UniqueNodeNames(const std::vector<AnimatedBody>& bodies) {
  std::set<std::string> used;
  std::vector<std::string> names;
  for (const AnimatedBody& b : bodies) {
    const std::string base = "body_" + b.name;
    std::string name = base;
    for (int i = 2; used.count(name) > 0; ++i) name = fmt::format("{}_{}", base, i);
    used.insert(name);
    names.push_back(name);
  }
  return names;
}

ExportResult ExportAnimation(const std::string& path, const std::vector<AnimatedBody>& bodies,
                             const PoseSequence& poses, const ExportOptions& options) {
  ExportResult result;
  const std::string format = FormatOf(path);
  if (format.empty()) {
    result.error = fmt::format("animation file '{}' must end in .glb or .gltf", path);
    return result;
  }
  if (!options.up_W.allFinite() || options.up_W.norm() == 0) {
    result.error = "the up direction must be a finite non-zero vector";
    return result;
  }
  result.error = CheckBodies(bodies);
  if (result.error.empty()) result.error = CheckPoses(poses, bodies.size());
  if (!result.error.empty()) return result;
  const std::vector<size_t> instants = ChooseInstants(poses, bodies.size(), options.max_keys, result, result.error);
  if (!result.error.empty()) return result;

  assimp_io::ExportRequest request;
  request.path = path;
  request.format = format;
  request.root_name = "kanesim";
  request.world_name = "kanesim_world";
  request.animation_name = "kanesim_motion";
  request.q_GW = Wxyz(UpToY(options.up_W));
  for (size_t k : instants) request.times.push_back(poses.times[k]);
  result.node_names = UniqueNodeNames(bodies);
  const size_t nb = bodies.size();
  for (size_t b = 0; b < nb; ++b) {
    assimp_io::ExportBody body;
    body.node_name = result.node_names[b];
    body.material_name = "material_of_" + result.node_names[b];
    body.mesh = bodies[b].mesh;
    for (Vec3& n : body.mesh.normals) n.normalize();
    body.rgba = bodies[b].rgba;
    Eigen::Quaterniond previous(1, 0, 0, 0);
    for (size_t k : instants) {
      body.positions.push_back(poses.p_WB[k * nb + b]);
      Eigen::Quaterniond q = poses.q_WB[k * nb + b].normalized();
      if (q.dot(previous) < 0) q.coeffs() = -q.coeffs();  // the same rotation, the short way from the last key
      body.rotations.push_back(Wxyz(q));
      previous = q;
    }
    request.bodies.push_back(std::move(body));
  }

  std::string error;
  const assimp_io::ModuleApi* api = assimp_io::Module(&error);
  if (!api) {
    result.error = error;
    return result;
  }
  const assimp_io::ExportReply reply = api->export_scene(request);
  if (!reply.ok) {
    result.error = fmt::format("assimp could not write {}: {}", path, reply.error);
    return result;
  }
  result.ok = true;
  result.times_written = instants.size();
  result.files.push_back(path);
  if (format == "gltf2") result.files.push_back(path.substr(0, path.size() - 5) + ".bin");
  return result;
}

}  // namespace kanesim::geometry
