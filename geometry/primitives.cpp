#include "geometry/primitives.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "geometry/mass_properties.h"

namespace kanesim::geometry {
namespace {

constexpr double kPi = std::numbers::pi;

// Index of the midpoint of edge {a, b}, made once and pushed onto the unit sphere.
uint32_t Midpoint(uint32_t a, uint32_t b, std::vector<Vec3>& v, std::map<std::pair<uint32_t, uint32_t>, uint32_t>& made) {
  const auto key = std::minmax(a, b);
  auto [it, inserted] = made.try_emplace({key.first, key.second}, static_cast<uint32_t>(v.size()));
  if (inserted) v.push_back((v[a] + v[b]).normalized());
  return it->second;
}

EquivalentShape Equivalent(double m, const Vec3& p_BBcm, const Mat3& I, double k) {
  const PrincipalInertia p = Principal(I);
  const Vec3& J = p.moments;
  EquivalentShape s;
  s.R_BP = p.R_MP;
  s.p_BBcm = p_BBcm;
  for (int i = 0; i < 3; ++i) {
    const double radicand = k * (J[(i + 1) % 3] + J[(i + 2) % 3] - J[i]) / m;
    s.size[i] = radicand > 0 ? std::sqrt(radicand) : 0.0;
  }
  return s;
}

}  // namespace

TriMesh BoxSolid(const Vec3& size) {
  TriMesh m;
  const Vec3 h = 0.5 * size;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  // Two triangles per face, counter-clockwise seen from outside.
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},   // z = −h, z = +h
                 {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},   // y = −h, y = +h
                 {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};  // x = −h, x = +h
  return m;
}

TriMesh CylinderSolid(double radius, double length, int segments) {
  TriMesh m;
  const auto n = static_cast<uint32_t>(std::max(segments, 3));
  for (int side = 0; side < 2; ++side) {
    const double x = side == 0 ? -0.5 * length : 0.5 * length;
    for (uint32_t i = 0; i < n; ++i) {
      const double phi = 2 * kPi * i / n;
      m.vertices.emplace_back(x, radius * std::cos(phi), radius * std::sin(phi));
    }
  }
  const uint32_t c0 = 2 * n, c1 = 2 * n + 1;  // cap centres
  m.vertices.emplace_back(-0.5 * length, 0, 0);
  m.vertices.emplace_back(0.5 * length, 0, 0);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    m.triangles.push_back({i, j, n + j});      // side, outward normal (0, cos, sin)
    m.triangles.push_back({i, n + j, n + i});
    m.triangles.push_back({c0, j, i});         // cap at −x, normal −x
    m.triangles.push_back({c1, n + i, n + j}); // cap at +x, normal +x
  }
  return m;
}

TriMesh IcosphereSolid(double radius, int subdivisions) {
  // The icosahedron: the cyclic permutations of (0, ±1, ±φ).
  const double phi = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> v = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0}, {0, -1, phi}, {0, 1, phi},
                         {0, -1, -phi}, {0, 1, -phi}, {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (Vec3& p : v) p.normalize();
  std::vector<Tri> t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                        {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                        {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> made;
    std::vector<Tri> finer;
    finer.reserve(4 * t.size());
    for (const Tri& f : t) {
      const uint32_t a = Midpoint(f[0], f[1], v, made), b = Midpoint(f[1], f[2], v, made),
                     c = Midpoint(f[2], f[0], v, made);
      finer.push_back({f[0], a, c});
      finer.push_back({f[1], b, a});
      finer.push_back({f[2], c, b});
      finer.push_back({a, b, c});
    }
    t = std::move(finer);
  }
  for (Vec3& p : v) p *= radius;
  return {std::move(v), std::move(t)};
}

TriMesh EllipsoidSolid(const Vec3& semi_axes, int subdivisions) {
  TriMesh m = IcosphereSolid(1.0, subdivisions);
  for (Vec3& p : m.vertices) p = p.cwiseProduct(semi_axes);
  return m;
}

VisualMesh DrawBox(const Vec3& size) { return ToVisual(BoxSolid(size)); }

VisualMesh DrawCylinder(double radius, double length, int segments) {
  return ToVisual(CylinderSolid(radius, length, segments));
}

VisualMesh DrawEllipsoid(const Vec3& semi_axes, int subdivisions) {
  return ToVisual(EllipsoidSolid(semi_axes, subdivisions));
}

VisualMesh DrawSphere(double radius, int subdivisions) { return ToVisual(IcosphereSolid(radius, subdivisions)); }

VisualMesh DrawRod(double length, double radius, int segments) {
  VisualMesh m = DrawCylinder(radius, length, segments);
  Transform(m, Mat3::Identity(), Vec3(0.5 * length, 0, 0));
  return m;
}

VisualMesh DrawDisk(double radius, double thickness, const Vec3& axis, int segments) {
  VisualMesh m = DrawCylinder(radius, thickness, segments);
  const Mat3 R = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitX(), axis.normalized()).toRotationMatrix();
  Transform(m, R, Vec3::Zero());
  return m;
}

VisualMesh DrawGrid(const Vec3& normal, double half_size, double spacing, double line_width) {
  const Vec3 n = normal.normalized();
  // Two directions in the plane: e1 ⟂ n, e2 = n × e1.
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  const int per_side = static_cast<int>(std::min(100.0, std::floor(half_size / spacing)));
  const double step = per_side > 0 ? std::max(spacing, half_size / per_side) : spacing;
  VisualMesh grid;
  for (int direction = 0; direction < 2; ++direction) {
    const Vec3 along = direction == 0 ? e1 : e2, across = direction == 0 ? e2 : e1;
    Mat3 R;  // box x along the line, y across it, z along the normal
    R.col(0) = along;
    R.col(1) = across;
    R.col(2) = along.cross(across);
    for (int i = -per_side; i <= per_side; ++i) {
      VisualMesh line = DrawBox(Vec3(2 * half_size, line_width, line_width / 5));
      Transform(line, R, i * step * across);
      Append(grid, line);
    }
  }
  return grid;
}

std::array<VisualMesh, 3> DrawAxes(double length) {
  std::array<VisualMesh, 3> axes;
  for (int i = 0; i < 3; ++i) {
    axes[i] = DrawRod(length, length / 25, 12);
    const Mat3 R = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitX(), Vec3::Unit(i)).toRotationMatrix();
    Transform(axes[i], R, Vec3::Zero());
  }
  return axes;
}

EquivalentShape InertiaBox(double m, const Vec3& p_BBcm, const Mat3& I_Bcm_B) {
  return Equivalent(m, p_BBcm, I_Bcm_B, 6.0);
}

EquivalentShape InertiaEllipsoid(double m, const Vec3& p_BBcm, const Mat3& I_Bcm_B) {
  return Equivalent(m, p_BBcm, I_Bcm_B, 2.5);
}

VisualMesh Draw(const EquivalentShape& shape, bool ellipsoid) {
  VisualMesh m = ellipsoid ? DrawEllipsoid(shape.size) : DrawBox(shape.size);
  Transform(m, shape.R_BP, shape.p_BBcm);
  return m;
}

}  // namespace kanesim::geometry
