// The boundary between kanesim_geometry (static, no assimp) and the assimp module
// libkanesim_geometry_assimp.so, which kanesim_geometry loads with dlopen the first time a
// mesh is read or an animation written. A program that never does either never maps
// libassimp (docs/visualization.md, "Loading assimp lazily").
//
// Both sides are built together by this project's CMake with one compiler and standard
// library, so the structs below cross the boundary as C++ types; kAbiVersion guards against
// a stale module.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "geometry/tri_mesh.h"

namespace kanesim::geometry::assimp_io {

inline constexpr int kAbiVersion = 1;

struct ImportRequest {
  std::string path;
  bool with_normals = false;  // false: positions only (solid); true: normals, joined vertices (drawing)
};

struct ImportReply {
  bool ok = false;
  std::string error;           // assimp's message when !ok
  std::vector<Vec3> vertices;  // all meshes of the file, node transforms applied, in file units
  std::vector<Vec3> normals;   // per vertex when with_normals (may be unnormalised), else empty
  std::vector<Tri> triangles;  // indices into vertices
};

// An animation ready to write: names unique, keys checked and decimated (gltf_export.cpp).
struct ExportBody {
  std::string node_name;
  std::string material_name;
  VisualMesh mesh;                   // in the body frame
  std::array<float, 4> rgba{};       // base colour, linear RGBA
  std::vector<Vec3> positions;       // p_WB at each time  (n_times)
  std::vector<std::array<double, 4>> rotations;  // q_WB as (w, x, y, z) at each time  (n_times)
};

struct ExportRequest {
  std::string path;
  std::string format;  // assimp exporter id: "glb2" or "gltf2"
  std::string root_name, world_name, animation_name;
  std::array<double, 4> q_GW{1, 0, 0, 0};  // world W to glTF frame G (Y up) as (w, x, y, z)
  std::vector<double> times;  // seconds, strictly increasing as floats, >= 0
  std::vector<ExportBody> bodies;
};

struct ExportReply {
  bool ok = false;
  std::string error;
};

struct ModuleApi {
  int abi_version;
  ImportReply (*import_mesh)(const ImportRequest&);
  ExportReply (*export_scene)(const ExportRequest&);
};

// The entry point the module exports (extern "C" so that dlsym finds it by this name).
inline constexpr const char* kEntryPoint = "kanesim_geometry_assimp_api";
using EntryFunction = const ModuleApi* (*)();

// The module, loaded once per process (thread-safe). Null with *error set when it cannot be
// found or is stale. Where: $KANESIM_GEOMETRY_MODULE when set (and nowhere else), otherwise
// the directory of the running executable, then the build tree's copy.
const ModuleApi* Module(std::string* error);

}  // namespace kanesim::geometry::assimp_io
