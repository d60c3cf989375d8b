// CheckSolid on meshes built in memory (geometry/mesh_check.h): the edge counts each defect
// must produce, independently counted by hand for these small meshes.
#include "geometry/mesh_check.h"

#include <gtest/gtest.h>

#include "geometry/primitives.h"

namespace kanesim::geometry {
namespace {

bool Has(const SolidReport& r, MeshProblemKind kind) {
  for (const MeshProblem& p : r.problems)
    if (p.kind == kind) return true;
  return false;
}

// Wrong if the table and the enum disagree (InfoOf indexes by the enum) or an id repeats.
TEST(MeshProblemTable, RowsInEnumOrderWithUniqueIds) {
  const auto table = MeshProblemTable();
  for (size_t i = 0; i < table.size(); ++i) {
    EXPECT_EQ(static_cast<size_t>(table[i].kind), i);
    for (size_t j = 0; j < i; ++j) EXPECT_STRNE(table[i].id, table[j].id);
  }
  EXPECT_EQ(table.size(), static_cast<size_t>(MeshProblemKind::kDeclaredBeyondFile) + 1);
}

// Wrong if a good box reports anything: 18 edges (12 sides + 6 face diagonals), volume 1.
TEST(CheckSolid, ClosedBoxIsClean) {
  TriMesh box = BoxSolid(Vec3(1, 1, 1));
  const SolidReport r = CheckSolid(box);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.edges, 18u);
  EXPECT_NEAR(r.volume, 1.0, 1e-14);
}

// Wrong if a hole is missed: a box without one triangle has its 3 edges open.
TEST(CheckSolid, MissingTriangleOpensThreeEdges) {
  TriMesh box = BoxSolid(Vec3(1, 1, 1));
  box.triangles.pop_back();
  const SolidReport r = CheckSolid(box);
  EXPECT_EQ(r.open_edges, 3u);
  ASSERT_TRUE(Has(r, MeshProblemKind::kNotClosed));
  EXPECT_NE(r.problems[0].message.find("3 open edges"), std::string::npos) << r.problems[0].message;
}

// Wrong if one reversed triangle goes unnoticed: its 3 edges are traversed the same way twice.
TEST(CheckSolid, OneReversedTriangle) {
  TriMesh box = BoxSolid(Vec3(1, 1, 1));
  std::swap(box.triangles[4][1], box.triangles[4][2]);
  const SolidReport r = CheckSolid(box);
  EXPECT_EQ(r.misoriented_edges, 3u);
  EXPECT_TRUE(Has(r, MeshProblemKind::kInconsistentOrientation));
  EXPECT_FALSE(Has(r, MeshProblemKind::kInsideOut));
}

// Wrong if an inside-out mesh is not flipped (with a warning) to positive volume.
TEST(CheckSolid, InsideOutIsFlipped) {
  TriMesh box = BoxSolid(Vec3(2, 1, 1));
  for (Tri& t : box.triangles) std::swap(t[1], t[2]);
  const SolidReport r = CheckSolid(box);
  EXPECT_TRUE(r.flipped);
  EXPECT_NEAR(r.volume, 2.0, 1e-14);
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].kind, MeshProblemKind::kInsideOut);
  EXPECT_EQ(r.problems[0].severity, Severity::kWarning);
  EXPECT_FALSE(HasError(r.problems));
}

// Wrong if a flat closed surface (a square and its reverse) passes as a solid.
TEST(CheckSolid, FlatClosedSurfaceHasZeroVolume) {
  TriMesh flat{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}, {0, 2, 1}, {0, 3, 2}}};
  const SolidReport r = CheckSolid(flat);
  EXPECT_TRUE(Has(r, MeshProblemKind::kZeroVolume));
}

// Wrong if the trust test ignores distance from the origin: a 1 µm cube 1 km away has a
// volume far below its float uncertainty.
TEST(CheckSolid, TinyFarAwayBoxIsUntrusted) {
  TriMesh box = BoxSolid(Vec3(1e-6, 1e-6, 1e-6));
  Transform(box, Mat3::Identity(), Vec3(1000, 0, 0));
  EXPECT_TRUE(Has(CheckSolid(box), MeshProblemKind::kZeroVolume));
  TriMesh near = BoxSolid(Vec3(1e-3, 1e-3, 1e-3));
  EXPECT_TRUE(CheckSolid(near).problems.empty());
}

// Wrong if degenerate triangles are not counted, or if those with a repeated vertex are not
// dropped (a box plus the triangle (0, 0, 1) stays a valid solid, with a warning).
TEST(CheckSolid, DegenerateTrianglesCountedAndDropped) {
  TriMesh box = BoxSolid(Vec3(1, 1, 1));
  box.triangles.push_back({0, 0, 1});
  const SolidReport r0 = CheckSolid(box);
  EXPECT_EQ(r0.degenerate_triangles, 1u);
  EXPECT_EQ(r0.dropped_triangles, 1u);
  EXPECT_EQ(box.triangles.size(), 12u);
  EXPECT_TRUE(Has(r0, MeshProblemKind::kDegenerateTriangles));
  EXPECT_FALSE(HasError(r0.problems));
}

// Wrong if two boxes sharing an edge (4 triangles on it, balanced) are refused: the volume is
// well defined; only a warning, and the volume is the sum.
TEST(CheckSolid, BalancedNonManifoldEdgeWarns) {
  TriMesh a = BoxSolid(Vec3(1, 1, 1)), b = BoxSolid(Vec3(1, 1, 1));
  Transform(a, Mat3::Identity(), Vec3(0.5, 0.5, 0));
  Transform(b, Mat3::Identity(), Vec3(-0.5, -0.5, 0));
  TriMesh both = a;
  const auto offset = static_cast<uint32_t>(a.vertices.size());
  both.vertices.insert(both.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const Tri& t : b.triangles) both.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  TriMesh welded = WeldByPosition(both.vertices, both.triangles);
  EXPECT_EQ(welded.vertices.size(), 14u);  // the shared edge's two end points
  const SolidReport r = CheckSolid(welded);
  EXPECT_EQ(r.non_manifold_edges, 1u);
  EXPECT_TRUE(Has(r, MeshProblemKind::kNonManifold));
  EXPECT_FALSE(HasError(r.problems));
  EXPECT_NEAR(r.volume, 2.0, 1e-14);
}

// Wrong if NaN coordinates reach the volume computation.
TEST(CheckSolid, NonFiniteVertex) {
  TriMesh box = BoxSolid(Vec3(1, 1, 1));
  box.vertices[3].y() = NAN;
  const SolidReport r = CheckSolid(box);
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_EQ(r.problems[0].kind, MeshProblemKind::kNonFinite);
  EXPECT_EQ(r.problems[0].count, 1u);
}

// Wrong if +0 and −0 weld apart, or distinct points weld together.
TEST(WeldByPosition, SignedZeroAndDistinctPoints) {
  const TriMesh m = WeldByPosition({{0, 0, 0}, {-0.0, 0, 0}, {1e-300, 0, 0}}, {{0, 1, 2}});
  EXPECT_EQ(m.vertices.size(), 2u);
  EXPECT_EQ(m.triangles[0][0], m.triangles[0][1]);
}

}  // namespace
}  // namespace kanesim::geometry
