#include "tests/support/mesh_files.h"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace kanesim::geometry::testing {
namespace {

std::ofstream Open(const std::string& path, bool binary = false) {
  std::ofstream out(path, binary ? std::ios::binary : std::ios::out);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << std::setprecision(17);
  return out;
}

Vec3 Normal(const TriMesh& m, const Tri& t) {
  return (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).normalized();
}

void PutFloat(std::string& s, double x) {
  const float f = static_cast<float>(x);
  char b[4];
  std::memcpy(b, &f, 4);
  s.append(b, 4);
}

void PutU32(std::string& s, uint32_t x) {
  char b[4];
  std::memcpy(b, &x, 4);
  s.append(b, 4);
}

std::string Base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += k[(v >> s) & 63];
  }
  if (i + 1 == in.size()) {
    const uint32_t v = uint8_t(in[i]) << 16;
    out += {k[(v >> 18) & 63], k[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8);
    out += {k[(v >> 18) & 63], k[(v >> 12) & 63], k[(v >> 6) & 63], '='};
  }
  return out;
}

}  // namespace

void WriteBinaryStl(const std::string& path, const TriMesh& mesh, double unit) {
  std::string s(80, ' ');
  s.replace(0, 23, "kanesim test binary STL");
  PutU32(s, static_cast<uint32_t>(mesh.triangles.size()));
  for (const Tri& t : mesh.triangles) {
    const Vec3 n = Normal(mesh, t);
    for (int i = 0; i < 3; ++i) PutFloat(s, n[i]);
    for (uint32_t v : t)
      for (int i = 0; i < 3; ++i) PutFloat(s, unit * mesh.vertices[v][i]);
    s.append(2, '\0');
  }
  Open(path, true) << s;
}

void WriteAsciiStl(const std::string& path, const TriMesh& mesh) {
  std::ofstream out = Open(path);
  out << "solid kanesim_test\n";
  for (const Tri& t : mesh.triangles) {
    const Vec3 n = Normal(mesh, t);
    out << "  facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n    outer loop\n";
    for (uint32_t v : t)
      out << "      vertex " << mesh.vertices[v].x() << ' ' << mesh.vertices[v].y() << ' ' << mesh.vertices[v].z()
          << '\n';
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid kanesim_test\n";
}

void WriteObj(const std::string& path, const TriMesh& mesh, int n_materials) {
  const std::filesystem::path p(path);
  const std::string mtl = p.stem().string() + ".mtl";
  {
    std::ofstream m = Open((p.parent_path() / mtl).string());
    for (int i = 0; i < n_materials; ++i)
      m << "newmtl part" << i << "\nKd " << 0.2 * i << " 0.5 0.5\n";
  }
  std::ofstream out = Open(path);
  out << "mtllib " << mtl << '\n';
  for (const Vec3& v : mesh.vertices) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (int i = 0; i < n_materials; ++i) {
    out << "g part" << i << "\nusemtl part" << i << '\n';
    for (size_t f = i; f < mesh.triangles.size(); f += n_materials) {
      const Tri& t = mesh.triangles[f];
      out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    }
  }
}

void WritePly(const std::string& path, const TriMesh& mesh) {
  std::ofstream out = Open(path);
  out << "ply\nformat ascii 1.0\nelement vertex " << mesh.vertices.size()
      << "\nproperty double x\nproperty double y\nproperty double z\nelement face " << mesh.triangles.size()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vec3& v : mesh.vertices) out << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const Tri& t : mesh.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
}

namespace {

// The glTF JSON of `mesh` under a translated node; *bin receives the buffer's bytes (float
// positions, then uint32 indices) and `buffer_uri` is the buffer's "uri" member (or "").
std::string GltfJson(const TriMesh& mesh, const Vec3& translation, std::string* bin,
                     const std::string& buffer_uri) {
  Vec3 lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const Vec3& v : mesh.vertices) {
    for (int i = 0; i < 3; ++i) PutFloat(*bin, v[i]);
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const size_t index_offset = bin->size();
  for (const Tri& t : mesh.triangles)
    for (uint32_t v : t) PutU32(*bin, v);
  auto f = [](double x) { return std::to_string(static_cast<float>(x)); };
  std::ostringstream j;
  j << std::setprecision(17);
  j << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],)"
    << R"("nodes":[{"name":"root","children":[1]},{"name":"part","mesh":0,"translation":[)" << translation.x() << ','
    << translation.y() << ',' << translation.z() << "]}],"
    << R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"mode":4}]}],)"
    << R"("buffers":[{"byteLength":)" << bin->size() << buffer_uri << R"(}],)"
    << R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":)" << index_offset << R"(,"target":34962},)"
    << R"({"buffer":0,"byteOffset":)" << index_offset << R"(,"byteLength":)" << bin->size() - index_offset
    << R"(,"target":34963}],)"
    << R"("accessors":[{"bufferView":0,"componentType":5126,"count":)" << mesh.vertices.size()
    << R"(,"type":"VEC3","min":[)" << f(lo.x()) << ',' << f(lo.y()) << ',' << f(lo.z()) << R"(],"max":[)"
    << f(hi.x()) << ',' << f(hi.y()) << ',' << f(hi.z()) << "]},"
    << R"({"bufferView":1,"componentType":5125,"count":)" << 3 * mesh.triangles.size() << R"(,"type":"SCALAR"}]})";
  return j.str();
}

}  // namespace

void WriteGltf(const std::string& path, const TriMesh& mesh, const Vec3& translation) {
  std::string bin;
  GltfJson(mesh, translation, &bin, "");
  const std::string uri = R"(,"uri":"data:application/octet-stream;base64,)" + Base64(bin) + "\"";
  bin.clear();
  Open(path) << GltfJson(mesh, translation, &bin, uri);
}

void WriteGlb(const std::string& path, const TriMesh& mesh, const Vec3& translation) {
  std::string bin;
  std::string json = GltfJson(mesh, translation, &bin, "");
  json.append((4 - json.size() % 4) % 4, ' ');  // chunks are 4-byte aligned
  bin.append((4 - bin.size() % 4) % 4, '\0');
  std::string s = "glTF";
  PutU32(s, 2);
  PutU32(s, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  PutU32(s, static_cast<uint32_t>(json.size()));
  s += "JSON" + json;
  PutU32(s, static_cast<uint32_t>(bin.size()));
  s += std::string("BIN\0", 4) + bin;
  Open(path, true) << s;
}

void WriteBinaryPly(const std::string& path, const TriMesh& mesh) {
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(mesh.vertices.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                  std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vec3& v : mesh.vertices)
    for (int i = 0; i < 3; ++i) PutFloat(s, v[i]);
  for (const Tri& t : mesh.triangles) {
    s.push_back(3);
    for (uint32_t v : t) PutU32(s, v);
  }
  Open(path, true) << s;
}

void WriteText(const std::string& path, const std::string& text) { Open(path) << text; }

std::string TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("kanesim_geometry_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace kanesim::geometry::testing
