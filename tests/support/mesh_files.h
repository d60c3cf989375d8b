// Mesh files written by the tests themselves, in the formats assimp reads: the tests own
// their data (no downloaded models). Each writer takes a solid with shared vertices.
#pragma once

#include <string>
#include <vector>

#include "geometry/mesh_load.h"
#include "geometry/tri_mesh.h"

namespace kanesim::geometry::testing {

// Binary STL: 80-byte header, triangle count, 50 bytes per triangle (float normal, 3 float
// vertices, attribute count). Coordinates are multiplied by `unit` (e.g. 1000 for mm).
void WriteBinaryStl(const std::string& path, const TriMesh& mesh, double unit = 1.0);
// ASCII STL ("solid … facet normal … outer loop … vertex …").
void WriteAsciiStl(const std::string& path, const TriMesh& mesh);
// Wavefront OBJ with an .mtl beside it; triangle f goes to material f % n_materials (each
// material a group of faces: assimp returns one mesh per material).
void WriteObj(const std::string& path, const TriMesh& mesh, int n_materials);
// ASCII PLY with vertex and face elements.
void WritePly(const std::string& path, const TriMesh& mesh);
// glTF 2.0 (JSON, buffer embedded as a base64 data URI): one mesh on a child node translated
// by `translation` under a root node, so a reader must apply node transforms.
void WriteGltf(const std::string& path, const TriMesh& mesh, const Vec3& translation);
// Binary glTF (.glb): the same document with the buffer as the BIN chunk.
void WriteGlb(const std::string& path, const TriMesh& mesh, const Vec3& translation);
// Binary little-endian PLY (float coordinates, uchar count and int indices per face).
void WriteBinaryPly(const std::string& path, const TriMesh& mesh);
// Any text.
void WriteText(const std::string& path, const std::string& text);

// Load options with this scale and the default limits.
inline LoadMeshOptions Scaled(double scale) {
  LoadMeshOptions options;
  options.scale = scale;
  return options;
}

// A fresh directory under the system temp dir for one test.
std::string TempDir(const std::string& name);

}  // namespace kanesim::geometry::testing
