// The solid checks: edge topology, orientation, volume.
//
// A closed, consistently oriented triangle surface traverses every edge once in each
// direction (two triangles meet at an edge and go along it in opposite senses). The
// divergence theorem (mass_properties.cpp) needs only the weaker condition that every
// undirected edge {a, b} is traversed a→b as often as b→a: then the surface is a boundary
// and its enclosed volume does not depend on the reference point. Counts per edge:
//   n = n_ab + n_ba = 1        an open edge                       (kNotClosed, error)
//   n_ab != n_ba, n >= 2       orientation inconsistent here      (kInconsistentOrientation, error)
//   n_ab == n_ba, n >= 4       non-manifold but balanced          (kNonManifold, warning)
#include "geometry/mesh_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "geometry/mass_properties.h"

namespace kanesim::geometry {
namespace {

constexpr std::array<MeshProblemInfo, 16> kMeshProblems{{
    {MeshProblemKind::kFileMissing, "mesh-file-missing", Severity::kError, "no mesh file at the path tried"},
    {MeshProblemKind::kFileUnreadable, "mesh-file-unreadable", Severity::kError, "the mesh file cannot be opened"},
    {MeshProblemKind::kModuleMissing, "mesh-support-missing", Severity::kError,
     "the mesh support library (assimp) could not be loaded"},
    {MeshProblemKind::kImportFailed, "mesh-import-failed", Severity::kError, "assimp could not read the file"},
    {MeshProblemKind::kTooLarge, "mesh-too-large", Severity::kError, "over a stated size limit"},
    {MeshProblemKind::kBadScale, "mesh-bad-scale", Severity::kError, "scale must be finite and positive"},
    {MeshProblemKind::kNoTriangles, "mesh-no-triangles", Severity::kError, "the file has no triangles"},
    {MeshProblemKind::kNonFinite, "mesh-non-finite", Severity::kError, "a coordinate is NaN or infinite"},
    {MeshProblemKind::kDegenerateTriangles, "mesh-degenerate-triangles", Severity::kWarning,
     "triangles of zero area"},
    {MeshProblemKind::kNotClosed, "mesh-not-closed", Severity::kError, "open edges: the surface has holes"},
    {MeshProblemKind::kNonManifold, "mesh-non-manifold", Severity::kWarning,
     "edges shared by more than two triangles"},
    {MeshProblemKind::kInconsistentOrientation, "mesh-inconsistent-orientation", Severity::kError,
     "neighbouring triangles face opposite ways"},
    {MeshProblemKind::kInsideOut, "mesh-inside-out", Severity::kWarning, "triangles face inward; flipped"},
    {MeshProblemKind::kZeroVolume, "mesh-zero-volume", Severity::kError,
     "the enclosed volume is zero or too small to trust"},
    {MeshProblemKind::kNotRegularFile, "mesh-not-regular-file", Severity::kError,
     "a FIFO, device or socket, not a regular file"},
    {MeshProblemKind::kDeclaredBeyondFile, "mesh-declared-beyond-file", Severity::kError,
     "the header declares more data than the file holds"},
}};

std::string Point(const Vec3& p) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", p.x(), p.y(), p.z()); }

// Edges grouped by their smaller vertex: for vertex a, the entries (b, direction) of every
// triangle edge {a, b} with a < b; direction 1 when the triangle goes a→b, 0 when b→a.
struct EdgeBuckets {
  std::vector<uint32_t> start;          // (n_vertices + 1)
  std::vector<uint64_t> other_and_dir;  // (b << 1 | direction)  (3 n_triangles)
};

EdgeBuckets BucketEdges(const TriMesh& mesh) {
  EdgeBuckets e;
  const size_t nv = mesh.vertices.size();
  e.start.assign(nv + 1, 0);
  for (const Tri& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++e.start[std::min(t[k], t[(k + 1) % 3]) + 1];
  for (size_t v = 0; v < nv; ++v) e.start[v + 1] += e.start[v];
  std::vector<uint32_t> fill(e.start.begin(), e.start.end() - 1);
  e.other_and_dir.resize(3 * mesh.triangles.size());
  for (const Tri& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t from = t[k], to = t[(k + 1) % 3];
      const uint32_t a = std::min(from, to), b = std::max(from, to);
      e.other_and_dir[fill[a]++] = (uint64_t{b} << 1) | (from == a ? 1u : 0u);
    }
  }
  return e;
}

// Counts the edge classes of the header comment; keeps one example location of each error.
void CountEdges(const TriMesh& mesh, SolidReport& r, std::array<uint32_t, 2>& open_example,
                std::array<uint32_t, 2>& misoriented_example) {
  EdgeBuckets e = BucketEdges(mesh);
  for (uint32_t a = 0; a + 1 < e.start.size(); ++a) {
    auto first = e.other_and_dir.begin() + e.start[a], last = e.other_and_dir.begin() + e.start[a + 1];
    std::sort(first, last);
    for (auto it = first; it != last;) {
      const uint64_t b = *it >> 1;
      uint64_t forward = 0, backward = 0;
      for (; it != last && (*it >> 1) == b; ++it) (*it & 1 ? forward : backward)++;
      ++r.edges;
      const std::array<uint32_t, 2> edge{a, static_cast<uint32_t>(b)};
      if (forward + backward == 1) {
        if (r.open_edges++ == 0) open_example = edge;
      } else if (forward != backward) {
        if (r.misoriented_edges++ == 0) misoriented_example = edge;
      } else if (forward + backward > 2) {
        ++r.non_manifold_edges;
      }
    }
  }
}

double BoxDiagonal(const std::vector<Vec3>& v) {
  if (v.empty()) return 0;
  Vec3 lo = v[0], hi = v[0];
  for (const Vec3& p : v) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// Removes triangles with a repeated vertex; counts all of zero area.
void DropDegenerate(TriMesh& mesh, SolidReport& r) {
  const double d = BoxDiagonal(mesh.vertices);
  const double tiny = kDegenerateArea * d * d;
  size_t kept = 0;
  for (const Tri& t : mesh.triangles) {
    const bool repeated = t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
    const Vec3 n = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    if (repeated || n.norm() <= tiny) ++r.degenerate_triangles;
    if (repeated) {
      ++r.dropped_triangles;
    } else {
      mesh.triangles[kept++] = t;
    }
  }
  mesh.triangles.resize(kept);
  if (r.degenerate_triangles > 0)
    r.problems.push_back(MakeProblem(
        MeshProblemKind::kDegenerateTriangles,
        fmt::format("{} degenerate triangle{} (zero area; {} with a repeated vertex removed, the others "
                    "kept: they add nothing to the volume)",
                    r.degenerate_triangles, r.degenerate_triangles == 1 ? "" : "s", r.dropped_triangles),
        r.degenerate_triangles));
}

// Volume, inside-out flip, and the trust test (kVolumeTrust).
void CheckVolume(TriMesh& mesh, SolidReport& r) {
  double volume = IntegrateVolume(mesh).volume;
  if (volume < 0) {
    for (Tri& t : mesh.triangles) std::swap(t[1], t[2]);
    r.flipped = true;
    r.problems.push_back(MakeProblem(
        MeshProblemKind::kInsideOut,
        fmt::format("the triangles face inward (enclosed volume {:.6g} m³ is negative); flipped them", volume)));
    volume = -volume;
  }
  double area = 0, r_max = 0;
  for (const Tri& t : mesh.triangles)
    area += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
  for (const Vec3& p : mesh.vertices) r_max = std::max(r_max, p.cwiseAbs().maxCoeff());
  const double uncertainty = area * std::ldexp(1.0, -24) * r_max;
  r.volume = volume;
  if (!(volume > kVolumeTrust * uncertainty))
    r.problems.push_back(MakeProblem(
        MeshProblemKind::kZeroVolume,
        fmt::format("the enclosed volume {:.6g} m³ is not above {:g} times its uncertainty {:.3g} m³ from "
                    "single-precision coordinates (surface area {:.6g} m², farthest coordinate {:.6g} m): "
                    "the mesh is flat or far smaller than its distance from the origin",
                    volume, kVolumeTrust, uncertainty, area, r_max)));
}

}  // namespace

std::span<const MeshProblemInfo> MeshProblemTable() { return kMeshProblems; }

const MeshProblemInfo& InfoOf(MeshProblemKind kind) { return kMeshProblems[static_cast<size_t>(kind)]; }

MeshProblem MakeProblem(MeshProblemKind kind, std::string message, uint64_t count) {
  return {kind, InfoOf(kind).severity, std::move(message), count};
}

bool HasError(const std::vector<MeshProblem>& problems) {
  return std::any_of(problems.begin(), problems.end(),
                     [](const MeshProblem& p) { return p.severity == Severity::kError; });
}

SolidReport CheckSolid(TriMesh& mesh) {
  SolidReport r;
  uint64_t non_finite = 0;
  for (const Vec3& p : mesh.vertices) non_finite += !p.allFinite();
  if (non_finite > 0) {
    r.problems.push_back(MakeProblem(MeshProblemKind::kNonFinite,
                                     fmt::format("{} vert{} NaN or infinite coordinates", non_finite, non_finite == 1 ? "ex has" : "ices have"),
                                     non_finite));
    return r;
  }
  DropDegenerate(mesh, r);
  if (mesh.triangles.empty()) {
    r.problems.push_back(MakeProblem(MeshProblemKind::kNoTriangles, "the mesh has no triangles of non-zero area"));
    return r;
  }
  std::array<uint32_t, 2> open{}, misoriented{};
  CountEdges(mesh, r, open, misoriented);
  if (r.open_edges > 0)
    r.problems.push_back(MakeProblem(
        MeshProblemKind::kNotClosed,
        fmt::format("the surface is not closed: {} open edge{} (used by one triangle only) of {}, e.g. from {} to {} "
                    "m; a solid body needs a closed (watertight) mesh",
                    r.open_edges, r.open_edges == 1 ? "" : "s", r.edges, Point(mesh.vertices[open[0]]),
                    Point(mesh.vertices[open[1]])),
        r.open_edges));
  if (r.misoriented_edges > 0)
    r.problems.push_back(MakeProblem(
        MeshProblemKind::kInconsistentOrientation,
        fmt::format("inconsistently oriented: {} edge{} traversed the same way by two triangles, e.g. from {} to {} "
                    "m; neighbouring triangles must wind the same way",
                    r.misoriented_edges, r.misoriented_edges == 1 ? " is" : "s are", Point(mesh.vertices[misoriented[0]]),
                    Point(mesh.vertices[misoriented[1]])),
        r.misoriented_edges));
  if (r.non_manifold_edges > 0)
    r.problems.push_back(MakeProblem(
        MeshProblemKind::kNonManifold,
        fmt::format("{} edge{} shared by more than two triangles (balanced, so the volume is still well defined)",
                    r.non_manifold_edges, r.non_manifold_edges == 1 ? " is" : "s are"),
        r.non_manifold_edges));
  if (r.open_edges > 0 || r.misoriented_edges > 0) return r;
  CheckVolume(mesh, r);
  return r;
}

}  // namespace kanesim::geometry
