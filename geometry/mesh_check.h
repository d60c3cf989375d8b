// Problems a mesh file or a mesh can have, defined once (kMeshProblems), and the checks that
// make a triangle mesh a solid whose mass properties can be trusted.
//
// The integration turns each MeshProblem into a diagnostic at the declaration that names the
// mesh (file:line:col); `id` is stable and maps to one diagnostic code.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "geometry/tri_mesh.h"

namespace kanesim::geometry {

enum class Severity : uint8_t { kError, kWarning };

enum class MeshProblemKind : uint8_t {
  kFileMissing,              // no file at the path tried
  kFileUnreadable,           // the path exists but cannot be opened (a directory, no permission)
  kModuleMissing,            // the mesh support library (assimp) could not be loaded
  kImportFailed,             // assimp could not read the file (its message)
  kTooLarge,                 // over a limit of MeshLimits
  kBadScale,                 // scale not finite and > 0
  kNoTriangles,              // the file has no triangles (only points or lines, or empty)
  kNonFinite,                // a coordinate is NaN or infinite
  kDegenerateTriangles,      // triangles of zero area (warning; those with a repeated vertex are dropped)
  kNotClosed,                // edges used by one triangle only (open boundary)
  kNonManifold,              // edges shared by more than two triangles, balanced (warning)
  kInconsistentOrientation,  // edges traversed the same way more often than the other way
  kInsideOut,                // negative enclosed volume: the triangles were flipped (warning)
  kZeroVolume,               // the enclosed volume is zero or below its float uncertainty
  kNotRegularFile,           // a FIFO, a device or a socket: reading it could block forever or never end
  kDeclaredBeyondFile,       // the header declares more data than the file holds (mesh_header.h)
};

struct MeshProblemInfo {
  MeshProblemKind kind;
  const char* id;      // stable name, e.g. "mesh-not-closed"
  Severity severity;
  const char* what;    // one line for a table of diagnostics
};

// The table (one row per kind, in enum order).
std::span<const MeshProblemInfo> MeshProblemTable();
const MeshProblemInfo& InfoOf(MeshProblemKind kind);

struct MeshProblem {
  MeshProblemKind kind;
  Severity severity;
  std::string message;  // human-readable, with the numbers (path, counts, a location)
  uint64_t count = 0;   // the number of offending items (edges, triangles, vertices), when counted
};

MeshProblem MakeProblem(MeshProblemKind kind, std::string message, uint64_t count = 0);
bool HasError(const std::vector<MeshProblem>& problems);

// What CheckSolid found.
struct SolidReport {
  std::vector<MeshProblem> problems;
  uint64_t edges = 0;                 // distinct undirected edges
  uint64_t open_edges = 0;            // used by one triangle
  uint64_t non_manifold_edges = 0;    // used by three or more
  uint64_t misoriented_edges = 0;     // traversed a→b more often than b→a (or the reverse)
  uint64_t degenerate_triangles = 0;  // zero area (kDegenerateArea below)
  uint64_t dropped_triangles = 0;     // degenerate ones with a repeated vertex, removed
  bool flipped = false;               // the mesh was inside out and has been flipped
  double volume = 0;                  // enclosed volume after any flip  (m³)
};

// Relative area below which a triangle is degenerate: |(b−a)×(c−a)| <= kDegenerateArea · D²,
// D the bounding box's diagonal.
inline constexpr double kDegenerateArea = 1e-14;
// The enclosed volume must exceed kVolumeTrust times its uncertainty from coordinates stored
// in single precision: δV = A · 2⁻²⁴ · max|r| (A the surface area, r the vertices).
inline constexpr double kVolumeTrust = 100.0;

// Checks that a welded mesh (shared vertices: WeldByPosition) bounds a solid: finite
// coordinates, at least one triangle, every edge used by triangles equally often in both
// directions (closed and consistently oriented), outward orientation (flips an inside-out
// mesh and warns), a trustworthy volume. Drops triangles with a repeated vertex. The mesh is
// fit for ComputeMassProperties when the report has no error.
SolidReport CheckSolid(TriMesh& mesh);

}  // namespace kanesim::geometry
