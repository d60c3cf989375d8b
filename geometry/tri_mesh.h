// Triangle meshes: the solid form (shared vertices, for mass properties and topology checks)
// and the drawing form (per-vertex normals), with the small operations both need.
//
// Frames: a mesh's coordinates are resolved in its own frame M (for a MeshBody, frame_a is the
// mesh file's frame; for a shape, the body frame B). Lengths are in metres once a loader has
// applied its scale.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

namespace kanesim::geometry {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Tri = std::array<uint32_t, 3>;

// A triangle mesh with shared vertices. A solid is closed and its triangles are ordered
// counter-clockwise seen from outside (the right-hand rule gives the outward normal).
struct TriMesh {
  std::vector<Vec3> vertices;  // vertex positions from M's origin, resolved in M  (m)  (n_vertices)
  std::vector<Tri> triangles;  // indices into vertices  (n_triangles)
};

// A triangle mesh for drawing: one normal per vertex (vertices are split where the surface
// has a crease, so a cube has 24).
struct VisualMesh {
  std::vector<Vec3> vertices;  // vertex positions from M's origin, resolved in M  (m)  (n_vertices)
  std::vector<Vec3> normals;   // unit outward normals, resolved in M  (n_vertices)
  std::vector<Tri> triangles;  // counter-clockwise seen from outside  (n_triangles)
};

// Merges vertices with bitwise-equal coordinates (+0 and -0 count as equal) and renumbers the
// triangles. Order of first appearance is kept. Returns the welded mesh.
TriMesh WeldByPosition(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles);

// The drawing form of a solid: a vertex keeps one normal for all triangles around it that are
// within crease_angle (rad) of each other, and is split where they are not. Normals are the
// area-weighted mean of the face normals of those triangles. Degenerate triangles get the
// normal of a neighbour or +z.
VisualMesh ToVisual(const TriMesh& mesh, double crease_angle = 0.6);

// Moves a mesh: every vertex p becomes R p + t, every normal R n (R a rotation).
void Transform(VisualMesh& mesh, const Mat3& R, const Vec3& t);
void Transform(TriMesh& mesh, const Mat3& R, const Vec3& t);

// Appends b to a (indices renumbered).
void Append(VisualMesh& a, const VisualMesh& b);

}  // namespace kanesim::geometry
