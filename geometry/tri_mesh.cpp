#include "geometry/tri_mesh.h"

#include <cmath>
#include <cstring>
#include <unordered_map>

namespace kanesim::geometry {
namespace {

// The bit pattern of a coordinate, with -0 folded into +0 so that both weld together.
uint64_t Bits(double x) {
  if (x == 0.0) x = 0.0;
  uint64_t b = 0;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

struct PositionKey {
  uint64_t x, y, z;
  bool operator==(const PositionKey&) const = default;
};

struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    // splitmix64-style mixing of the three bit patterns.
    uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (k.y + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2)) * 0xBF58476D1CE4E5B9ull;
    h ^= (k.z + 0x94D049BB133111EBull + (h << 6) + (h >> 2)) * 0x94D049BB133111EBull;
    return static_cast<size_t>(h ^ (h >> 31));
  }
};

PositionKey KeyOf(const Vec3& p) { return {Bits(p.x()), Bits(p.y()), Bits(p.z())}; }

// Twice the area vector of triangle t: (b - a) x (c - a).
Vec3 AreaVector(const std::vector<Vec3>& v, const Tri& t) {
  return (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
}

}  // namespace

TriMesh WeldByPosition(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles) {
  // Open addressing with linear probing: a table of indices into out.vertices, at least twice
  // as large as the number of vertices, so probes stay short.
  TriMesh out;
  size_t size = 16;
  while (size < 2 * vertices.size()) size *= 2;
  constexpr uint32_t kEmpty = UINT32_MAX;
  std::vector<uint32_t> table(size, kEmpty);
  std::vector<PositionKey> keys;
  keys.reserve(vertices.size());
  out.vertices.reserve(vertices.size());
  std::vector<uint32_t> remap(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    const PositionKey key = KeyOf(vertices[i]);
    size_t slot = PositionHash{}(key) & (size - 1);
    while (table[slot] != kEmpty && !(keys[table[slot]] == key)) slot = (slot + 1) & (size - 1);
    if (table[slot] == kEmpty) {
      table[slot] = static_cast<uint32_t>(out.vertices.size());
      out.vertices.push_back(vertices[i]);
      keys.push_back(key);
    }
    remap[i] = table[slot];
  }
  out.triangles.reserve(triangles.size());
  for (const Tri& t : triangles) out.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  return out;
}

VisualMesh ToVisual(const TriMesh& mesh, double crease_angle) {
  const size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  std::vector<Vec3> area(nt), unit(nt);
  for (size_t t = 0; t < nt; ++t) {
    area[t] = AreaVector(mesh.vertices, mesh.triangles[t]);
    const double a = area[t].norm();
    unit[t] = a > 0 ? Vec3(area[t] / a) : Vec3::Zero();
  }
  // Triangles around each vertex, in compressed rows: start[v] .. start[v + 1].
  std::vector<uint32_t> start(nv + 1, 0), around(3 * nt);
  for (const Tri& t : mesh.triangles)
    for (uint32_t v : t) ++start[v + 1];
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (size_t t = 0; t < nt; ++t)
    for (uint32_t v : mesh.triangles[t]) around[fill[v]++] = static_cast<uint32_t>(t);

  const double cos_crease = std::cos(crease_angle);
  VisualMesh out;
  out.triangles.resize(nt);
  struct NormalKey {
    uint32_t vertex;
    uint64_t x, y, z;
    bool operator==(const NormalKey&) const = default;
  };
  struct NormalHash {
    size_t operator()(const NormalKey& k) const {
      return PositionHash{}({k.x ^ k.vertex, k.y, k.z});
    }
  };
  std::unordered_map<NormalKey, uint32_t, NormalHash> made;
  for (size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.triangles[t][k];
      Vec3 n = Vec3::Zero();
      for (uint32_t i = start[v]; i < start[v + 1]; ++i) {
        const uint32_t s = around[i];
        if (unit[t].isZero() || unit[t].dot(unit[s]) >= cos_crease) n += area[s];
      }
      const double len = n.norm();
      n = len > 0 ? Vec3(n / len) : Vec3::UnitZ();
      const NormalKey key{v, Bits(n.x()), Bits(n.y()), Bits(n.z())};
      auto [it, inserted] = made.try_emplace(key, static_cast<uint32_t>(out.vertices.size()));
      if (inserted) {
        out.vertices.push_back(mesh.vertices[v]);
        out.normals.push_back(n);
      }
      out.triangles[t][k] = it->second;
    }
  }
  return out;
}

void Transform(VisualMesh& mesh, const Mat3& R, const Vec3& t) {
  for (Vec3& p : mesh.vertices) p = R * p + t;
  for (Vec3& n : mesh.normals) n = R * n;
}

void Transform(TriMesh& mesh, const Mat3& R, const Vec3& t) {
  for (Vec3& p : mesh.vertices) p = R * p + t;
}

void Append(VisualMesh& a, const VisualMesh& b) {
  const auto offset = static_cast<uint32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
  for (const Tri& t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

}  // namespace kanesim::geometry
