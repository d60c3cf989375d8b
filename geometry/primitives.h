// Shapes for drawing (and, as closed solids, for tests of the mass properties), and the
// inertia-equivalent box or ellipsoid of a bare body.
//
// Every shape is centred on its frame's origin; the stdlib shapes place theirs (docs/
// visualization.md): Box and Cylinder span x = 0 .. length, so translate by (length/2, 0, 0);
// Rod is a thin cylinder along x from 0 to L; Sphere is centred.
#pragma once

#include <array>

#include "geometry/tri_mesh.h"

namespace kanesim::geometry {

// Closed solids with shared vertices, outward-oriented.
TriMesh BoxSolid(const Vec3& size);  // sides (lx, ly, lz) along x, y, z  (m)
// A prism of `segments` sides inscribed in the cylinder of `radius` around x, from
// x = −length/2 to length/2; the two caps are fans around their centres.
TriMesh CylinderSolid(double radius, double length, int segments);
// The icosahedron inscribed in the sphere of `radius`, each triangle split into 4
// `subdivisions` times with the new vertices pushed onto the sphere: 20·4^s triangles.
TriMesh IcosphereSolid(double radius, int subdivisions);
// The icosphere of radius 1 scaled by the semi-axes.
TriMesh EllipsoidSolid(const Vec3& semi_axes, int subdivisions);

// The same for drawing (crease angle 0.6 rad: flat box faces and cylinder caps, smooth
// round surfaces).
VisualMesh DrawBox(const Vec3& size);
VisualMesh DrawCylinder(double radius, double length, int segments = 32);
VisualMesh DrawEllipsoid(const Vec3& semi_axes, int subdivisions = 3);
VisualMesh DrawSphere(double radius, int subdivisions = 3);
// A thin cylinder along x from x = 0 to x = length.
VisualMesh DrawRod(double length, double radius, int segments = 16);
// A disk of `radius` and `thickness` centred on the origin with its axis along `axis`
// (any non-zero vector).
VisualMesh DrawDisk(double radius, double thickness, const Vec3& axis, int segments = 48);

// A ground grid for a contact plane through the origin with unit normal `normal`: lines
// `spacing` apart in both directions of the plane, from −half_size to half_size, each a flat
// box `line_width` wide and line_width / 5 thick. At most 201 lines per direction (the spacing
// is widened beyond that).
VisualMesh DrawGrid(const Vec3& normal, double half_size, double spacing, double line_width);

// Small axes for a frame: thin rods of `length` from the origin along x, y and z (drawn in
// red, green, blue by convention; the caller chooses the materials).
std::array<VisualMesh, 3> DrawAxes(double length);

// The uniform box or ellipsoid with the same mass and principal moments as a body, as MuJoCo
// draws inertias. With principal moments I1, I2, I3 of the central inertia and mass m:
//   box sides        a1 = sqrt(6 (I2 + I3 − I1) / m)     (from I1 = m (a2² + a3²) / 12)
//   ellipsoid axes   e1 = sqrt(5/2 (I2 + I3 − I1) / m)   (from I1 = m (e2² + e3²) / 5)
// and cyclically; a negative radicand (an inertia that violates the triangle inequality by
// round-off) gives 0.
struct EquivalentShape {
  Vec3 size = Vec3::Zero();     // box: full sides; ellipsoid: semi-axes, along the principal axes  (m)
  Mat3 R_BP = Mat3::Identity(); // principal axes resolved in the body frame B (a rotation)
  Vec3 p_BBcm = Vec3::Zero();   // centre, from B's origin  (m)
};
// m > 0; I_Bcm_B symmetric, about the centre of mass, resolved in B.
EquivalentShape InertiaBox(double m, const Vec3& p_BBcm, const Mat3& I_Bcm_B);
EquivalentShape InertiaEllipsoid(double m, const Vec3& p_BBcm, const Mat3& I_Bcm_B);
// Drawings of those, placed in B.
VisualMesh Draw(const EquivalentShape& shape, bool ellipsoid);

}  // namespace kanesim::geometry
