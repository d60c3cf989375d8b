// Shapes for drawing (geometry/primitives.h), the drawing form of meshes (ToVisual), and the
// lazy loading of assimp (geometry/assimp_module.h).
#include "geometry/primitives.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "geometry/mass_properties.h"
#include "geometry/mesh_check.h"
#include "geometry/mesh_load.h"
#include "tests/support/mesh_files.h"

namespace kanesim::geometry {
namespace {

// Wrong if a solid primitive has holes, reversed triangles or a wrong volume: each passes
// CheckSolid cleanly with the closed-form volume of what it is (box abc; prism N r² sin(2π/N)
// L / 2; ellipsoid scaled icosphere = 4/3 π abc times the unit icosphere's ratio).
TEST(Primitives, SolidsAreClosedWithClosedFormVolume) {
  TriMesh box = BoxSolid(Vec3(0.3, 0.2, 0.1));
  SolidReport r = CheckSolid(box);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_NEAR(r.volume, 0.006, 1e-15);

  TriMesh cyl = CylinderSolid(0.1, 0.5, 12);
  r = CheckSolid(cyl);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_NEAR(r.volume, 12 * 0.01 * std::sin(2 * std::numbers::pi / 12) / 2 * 0.5, 1e-15);

  TriMesh unit = IcosphereSolid(1, 2), ell = EllipsoidSolid(Vec3(0.3, 0.2, 0.1), 2);
  const double v_unit = CheckSolid(unit).volume;
  r = CheckSolid(ell);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_NEAR(r.volume, v_unit * 0.3 * 0.2 * 0.1, 1e-15);
  EXPECT_EQ(unit.triangles.size(), 320u);
  EXPECT_EQ(unit.vertices.size(), 162u);
}

// Wrong if ToVisual smooths across creases or splits smooth surfaces: a box has 24 vertices
// (4 per face) with the face normals; a sphere keeps 1 vertex per point with the radial normal.
TEST(Primitives, DrawingNormals) {
  const VisualMesh box = DrawBox(Vec3(1, 2, 3));
  EXPECT_EQ(box.vertices.size(), 24u);
  EXPECT_EQ(box.triangles.size(), 12u);
  for (size_t i = 0; i < box.vertices.size(); ++i) {
    const Vec3 n = box.normals[i];
    EXPECT_NEAR(n.cwiseAbs().maxCoeff(), 1, 1e-15);  // an axis
    const int axis = n.cwiseAbs().maxCoeff() == std::abs(n.x()) ? 0 : (std::abs(n.y()) == 1 ? 1 : 2);
    EXPECT_NEAR(box.vertices[i][axis], 0.5 * n[axis] * Vec3(1, 2, 3)[axis], 1e-15);  // on that face
  }
  const VisualMesh sphere = DrawSphere(2.0, 2);
  EXPECT_EQ(sphere.vertices.size(), 162u);
  for (size_t i = 0; i < sphere.vertices.size(); ++i)
    EXPECT_GT(sphere.normals[i].dot(sphere.vertices[i].normalized()), 0.99);
  const VisualMesh cyl = DrawCylinder(1, 1, 32);
  EXPECT_EQ(cyl.vertices.size(), 32u * 2 + 2 * 33u);  // side: 2 rings; caps: ring + centre each
}

// Wrong if the rod or disk are placed wrongly: the rod spans x = 0..L, the disk's flat faces
// are normal to its axis.
TEST(Primitives, RodAndDiskPlacement) {
  const VisualMesh rod = DrawRod(2.0, 0.01);
  double lo = 1e9, hi = -1e9;
  for (const Vec3& p : rod.vertices) {
    lo = std::min(lo, p.x());
    hi = std::max(hi, p.x());
  }
  EXPECT_NEAR(lo, 0, 1e-15);
  EXPECT_NEAR(hi, 2, 1e-15);
  const Vec3 axis = Vec3(0, 1, 1).normalized();
  const VisualMesh disk = DrawDisk(0.5, 0.02, Vec3(0, 3, 3));
  int on_faces = 0;
  for (size_t i = 0; i < disk.vertices.size(); ++i) {
    const double along = disk.vertices[i].dot(axis);
    EXPECT_LE(std::abs(along), 0.01 + 1e-12);
    if (std::abs(std::abs(disk.normals[i].dot(axis)) - 1) < 1e-12) {
      ++on_faces;
      EXPECT_NEAR(std::abs(along), 0.01, 1e-12);
    }
  }
  EXPECT_EQ(on_faces, 2 * 49);
}

// Wrong if the drawing of an inertia-equivalent box does not have that inertia: the box mesh
// drawn for a body, taken as a solid of the body's mass, gives back the body's inertia.
TEST(Primitives, DrawnEquivalentBoxHasTheInertia) {
  Mat3 I;
  I << 0.30, 0.02, -0.01, 0.02, 0.25, 0.03, -0.01, 0.03, 0.12;
  const double m = 4.0;
  const Vec3 c(0.1, -0.2, 0.3);
  const EquivalentShape s = InertiaBox(m, c, I);
  TriMesh box = BoxSolid(s.size);
  Transform(box, s.R_BP, s.p_BBcm);
  const MassProperties mp = ComputeMassProperties(box, MassSpec::Mass(m));
  EXPECT_LE((mp.I_Bcm_M - I).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((mp.p_MBcm - c).norm(), 1e-14);
  EXPECT_EQ(Draw(s, false).vertices.size(), 24u);
}

// Wrong if the grid leaves its plane or its extent, or the axes point the wrong way: every grid
// vertex is within the line thickness of the plane and within half_size (+ the half width) of
// the origin along the plane; 11 lines each way of 24 vertices; axis i spans 0..length along i.
TEST(Primitives, GridAndAxes) {
  const Vec3 n = Vec3(0, 1, 0.2).normalized();
  const VisualMesh grid = DrawGrid(n, 1.0, 0.2, 0.01);
  EXPECT_EQ(grid.vertices.size(), 2u * 11u * 24u);
  for (const Vec3& p : grid.vertices) {
    EXPECT_LE(std::abs(p.dot(n)), 0.001 + 1e-12);
    const Vec3 in_plane = p - p.dot(n) * n;
    EXPECT_LE(in_plane.cwiseAbs().maxCoeff(), std::sqrt(2.0) * (1.0 + 0.005) + 1e-12);
  }
  const auto axes = DrawAxes(0.5);
  for (int i = 0; i < 3; ++i) {
    double lo = 1e9, hi = -1e9;
    for (const Vec3& p : axes[i].vertices) {
      lo = std::min(lo, p[i]);
      hi = std::max(hi, p[i]);
      EXPECT_LE((p - p[i] * Vec3::Unit(i)).norm(), 0.02 + 1e-12);
    }
    EXPECT_NEAR(lo, 0, 1e-12);
    EXPECT_NEAR(hi, 0.5, 1e-12);
  }
  EXPECT_LE(DrawGrid(Vec3::UnitY(), 100.0, 0.001, 0.01).vertices.size(), 2u * 201u * 24u);
}

bool AssimpMapped() {
  std::ifstream maps("/proc/self/maps");
  std::stringstream text;
  text << maps.rdbuf();
  return text.str().find("libassimp") != std::string::npos;
}

// Wrong if linking kanesim_geometry maps libassimp at start (a run without meshes would pay
// for it): it appears in this process only once a mesh is loaded. ctest runs each test in a
// process of its own, so nothing has loaded it before.
TEST(LazyAssimp, MappedOnlyWhenAMeshIsRead) {
  const MassProperties mp = ComputeMassProperties(BoxSolid(Vec3(1, 1, 1)), MassSpec::Density(1));
  EXPECT_NEAR(mp.volume, 1, 1e-15);
  if (AssimpMapped()) GTEST_SKIP() << "an earlier test in this process loaded a mesh (run it alone)";
  const std::string dir = testing::TempDir("lazy");
  testing::WriteBinaryStl(dir + "/box.stl", BoxSolid(Vec3(1, 1, 1)));
  EXPECT_TRUE(LoadMesh(dir + "/box.stl").ok());
  EXPECT_TRUE(AssimpMapped());
}

}  // namespace
}  // namespace kanesim::geometry
