#include "tests/support/mesh_fixtures.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <utility>

#include "geometry/primitives.h"
#include "tests/support/mesh_files.h"

namespace kanesim::meshfix {

namespace g = kanesim::geometry;

std::string MeshFixtureDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("kanesim_mesh_" + std::to_string(static_cast<long>(getpid())) + "_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

bool WriteMeshFixture(const std::string& path, const std::string& kind) {
  g::TriMesh box = g::BoxSolid(g::Vec3(1, 0.1, 0.05));
  g::Transform(box, g::Mat3::Identity(), g::Vec3(0.5, 0, 0));
  if (kind == "box") {
    g::testing::WriteBinaryStl(path, box);
  } else if (kind == "box_mm") {
    g::testing::WriteBinaryStl(path, box, 1000.0);
  } else if (kind == "open") {
    // BoxSolid's last two triangles are one face.
    box.triangles.resize(box.triangles.size() - 2);
    g::testing::WriteAsciiStl(path, box);
  } else if (kind == "misoriented") {
    std::swap(box.triangles[0][1], box.triangles[0][2]);
    g::testing::WriteObj(path, box, 1);
  } else if (kind == "inside_out") {
    for (g::Tri& t : box.triangles) std::swap(t[1], t[2]);
    g::testing::WritePly(path, box);
  } else if (kind == "flat") {
    g::testing::WriteText(path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 1 3 2\nf 1 4 3\n");
  } else if (kind == "degenerate") {
    box.triangles.push_back({0, 1, 1});
    g::testing::WriteBinaryStl(path, box);
  } else if (kind == "huge") {
    { std::ofstream(path, std::ios::binary) << "solid huge\n"; }
    std::filesystem::resize_file(path, 257ull << 20);
  } else if (kind == "junk") {
    g::testing::WriteText(path, "this is not a mesh\n");
  } else {
    return false;
  }
  return true;
}

}  // namespace kanesim::meshfix
