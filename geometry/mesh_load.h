// Reading mesh files (through assimp, loaded lazily: assimp_module.h).
//
// Formats: whatever assimp 5.2 reads — STL (ASCII and binary), OBJ (with several materials:
// merged), PLY, glTF 2.0 (.gltf with .bin, .glb), Collada, 3MF, OFF, and more. Node
// transforms are applied, so the mesh is resolved in the file's own frame. Paths are used as
// given (the caller resolves them relative to the .mech file).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "geometry/mesh_check.h"
#include "geometry/tri_mesh.h"

namespace kanesim::geometry {

// Stated limits (docs/visualization.md). A file over max_file_bytes is not opened; the
// triangle and vertex limits apply to what assimp returns.
struct MeshLimits {
  uint64_t max_file_bytes = 256ull << 20;  // 256 MiB (a binary STL of 5.6 million triangles)
  uint64_t max_triangles = 4'000'000;
  uint64_t max_vertices = 4'000'000;       // after welding (solid) or joining (drawing)
};

struct LoadMeshOptions {
  double scale = 1.0;  // metres per file unit (0.001 for a file in millimetres); finite, > 0
  MeshLimits limits;
};

// A solid body's mesh: welded by position across all meshes of the file, checked
// (CheckSolid: closed, consistently oriented, outward — flipped if it was inside out —, a
// volume that can be trusted), scaled to metres.
struct MeshLoadResult {
  TriMesh mesh;                       // valid when ok(); vertices in metres, resolved in the file's frame
  std::vector<MeshProblem> problems;  // errors and warnings, in the order found
  SolidReport report;                 // the topology counts (zero when loading failed before the checks)
  bool ok() const { return !HasError(problems); }
};
MeshLoadResult LoadMesh(const std::string& path, const LoadMeshOptions& options = {});

// A mesh for drawing only (a body whose mass properties are given): triangles with unit
// per-vertex normals (from the file, or flat ones made by assimp where it has none), not
// required to be closed. Problems: file, import, size, scale, non-finite, no triangles.
struct VisualMeshResult {
  VisualMesh mesh;                    // valid when ok(); metres, file's frame
  std::vector<MeshProblem> problems;
  bool ok() const { return !HasError(problems); }
};
VisualMeshResult LoadVisualMesh(const std::string& path, const LoadMeshOptions& options = {});

}  // namespace kanesim::geometry
