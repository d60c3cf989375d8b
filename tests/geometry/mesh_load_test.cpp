// Loading mesh files through assimp (geometry/mesh_load.h): every format the tests can write,
// and a file for every problem a mesh file can have. The files are written by the tests
// (mesh_files.h); expected values come from the meshes written, not from assimp.
#include "geometry/mesh_load.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "geometry/mass_properties.h"
#include "geometry/primitives.h"
#include "tests/support/mesh_files.h"

namespace kanesim::geometry {
namespace {

// A 2 x 1 x 0.5 box centred on (1, 2, 3): coordinates exact in float.
TriMesh TestBox() {
  TriMesh box = BoxSolid(Vec3(2, 1, 0.5));
  Transform(box, Mat3::Identity(), Vec3(1, 2, 3));
  return box;
}

const MeshProblem* Find(const std::vector<MeshProblem>& problems, MeshProblemKind kind) {
  for (const MeshProblem& p : problems)
    if (p.kind == kind) return &p;
  return nullptr;
}

bool Has(const std::vector<MeshProblem>& problems, MeshProblemKind kind) { return Find(problems, kind) != nullptr; }

std::string Describe(const std::vector<MeshProblem>& problems) {
  std::string s;
  for (const MeshProblem& p : problems) s += std::string(InfoOf(p.kind).id) + ": " + p.message + "\n";
  return s;
}

// Wrong if a format's corners stay split, its meshes are not merged, or node transforms are
// not applied: every file of the box loads as 8 vertices and 12 triangles with volume 1 and
// centre (1, 2, 3) (the glTF box sits at the origin under a node translated by (1, 2, 3)).
class FormatTest : public ::testing::TestWithParam<std::string> {};

TEST_P(FormatTest, BoxLoadsAsClosedSolid) {
  const std::string dir = testing::TempDir("format_" + GetParam());
  const std::string path = dir + "/box." + (GetParam() == "stlascii" ? std::string("stl") : GetParam());
  const TriMesh box = TestBox();
  if (GetParam() == "stl") testing::WriteBinaryStl(path, box);
  if (GetParam() == "stlascii") testing::WriteAsciiStl(path, box);
  if (GetParam() == "obj") testing::WriteObj(path, box, 3);
  if (GetParam() == "ply") testing::WritePly(path, box);
  if (GetParam() == "gltf") testing::WriteGltf(path, BoxSolid(Vec3(2, 1, 0.5)), Vec3(1, 2, 3));
  const MeshLoadResult r = LoadMesh(path);
  ASSERT_TRUE(r.ok()) << Describe(r.problems);
  EXPECT_TRUE(r.problems.empty()) << Describe(r.problems);
  EXPECT_EQ(r.mesh.vertices.size(), 8u);
  EXPECT_EQ(r.mesh.triangles.size(), 12u);
  const MassProperties mp = ComputeMassProperties(r.mesh, MassSpec::Density(1));
  EXPECT_NEAR(mp.volume, 1.0, 1e-12);
  EXPECT_LE((mp.p_MBcm - Vec3(1, 2, 3)).norm(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Formats, FormatTest, ::testing::Values("stl", "stlascii", "obj", "ply", "gltf"));

// Wrong if a finer mesh is welded wrongly: an icosphere (642 vertices, 1280 triangles) in
// binary STL comes back with the same counts and the volume of the in-memory mesh to float
// precision (the file stores float).
TEST(LoadMesh, IcosphereThroughBinaryStl) {
  const std::string dir = testing::TempDir("icosphere");
  const TriMesh sphere = IcosphereSolid(0.25, 3);
  testing::WriteBinaryStl(dir + "/sphere.stl", sphere);
  const MeshLoadResult r = LoadMesh(dir + "/sphere.stl");
  ASSERT_TRUE(r.ok()) << Describe(r.problems);
  EXPECT_EQ(r.mesh.vertices.size(), sphere.vertices.size());
  EXPECT_EQ(r.mesh.triangles.size(), sphere.triangles.size());
  const double V = ComputeMassProperties(sphere, MassSpec::Density(1)).volume;
  EXPECT_NEAR(ComputeMassProperties(r.mesh, MassSpec::Density(1)).volume, V, 3e-7 * V);
}

// Wrong if the drawing path requires closedness or gives non-unit normals: an open box (one
// face missing) loads, with unit normals that point out of its faces.
TEST(LoadVisualMesh, OpenMeshWithNormals) {
  const std::string dir = testing::TempDir("visual");
  TriMesh open = BoxSolid(Vec3(1, 1, 1));
  open.triangles.resize(10);
  testing::WriteBinaryStl(dir + "/open.stl", open);
  const VisualMeshResult r = LoadVisualMesh(dir + "/open.stl", testing::Scaled(2.0));
  ASSERT_TRUE(r.ok()) << Describe(r.problems);
  EXPECT_EQ(r.mesh.triangles.size(), 10u);
  EXPECT_EQ(r.mesh.vertices.size(), 20u);  // 5 faces x 4 corners, split by normal
  for (size_t i = 0; i < r.mesh.vertices.size(); ++i) {
    EXPECT_NEAR(r.mesh.normals[i].norm(), 1, 1e-6);
    EXPECT_NEAR(r.mesh.vertices[i].cwiseAbs().maxCoeff(), 1.0, 1e-12);  // scaled by 2
    EXPECT_GT(r.mesh.normals[i].dot(r.mesh.vertices[i]), 0.9);          // outward
  }
}

// ---- One file per problem (mesh_check.h's table) ----

TEST(MeshProblems, FileMissingNamesThePath) {
  const MeshLoadResult r = LoadMesh("/nonexistent/dir/crank.stl");
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kFileMissing);
  ASSERT_NE(p, nullptr) << Describe(r.problems);
  EXPECT_NE(p->message.find("/nonexistent/dir/crank.stl"), std::string::npos);
  EXPECT_FALSE(r.ok());
}

TEST(MeshProblems, DirectoryIsUnreadable) {
  const std::string dir = testing::TempDir("unreadable");
  std::filesystem::create_directories(dir + "/part.stl");
  EXPECT_TRUE(Has(LoadMesh(dir + "/part.stl").problems, MeshProblemKind::kFileUnreadable));
  EXPECT_TRUE(Has(LoadVisualMesh(dir + "/part.stl").problems, MeshProblemKind::kFileUnreadable));
}

TEST(MeshProblems, ImportFailureCarriesAssimpsMessage) {
  const std::string dir = testing::TempDir("import");
  testing::WriteText(dir + "/part.xyzzy", "this is not a mesh\n");
  const MeshLoadResult r = LoadMesh(dir + "/part.xyzzy");
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kImportFailed);
  ASSERT_NE(p, nullptr) << Describe(r.problems);
  EXPECT_NE(p->message.find("assimp could not read"), std::string::npos);
  EXPECT_GT(p->message.size(), std::string("assimp could not read mesh file ").size() + dir.size() + 14);
}

TEST(MeshProblems, SizeLimits) {
  const std::string dir = testing::TempDir("limits");
  testing::WriteBinaryStl(dir + "/sphere.stl", IcosphereSolid(1, 2));  // 320 triangles, 162 vertices
  LoadMeshOptions bytes;
  bytes.limits.max_file_bytes = 1000;
  // Keep each result alive while its problem is looked at.
  const MeshLoadResult too_many_bytes = LoadMesh(dir + "/sphere.stl", bytes);
  const MeshProblem* p = Find(too_many_bytes.problems, MeshProblemKind::kTooLarge);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->count, 84u + 50u * 320u);
  LoadMeshOptions triangles;
  triangles.limits.max_triangles = 319;
  const MeshLoadResult too_many_triangles = LoadMesh(dir + "/sphere.stl", triangles);
  p = Find(too_many_triangles.problems, MeshProblemKind::kTooLarge);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->count, 320u);
  LoadMeshOptions vertices;
  vertices.limits.max_vertices = 161;
  const MeshLoadResult too_many_vertices = LoadMesh(dir + "/sphere.stl", vertices);
  p = Find(too_many_vertices.problems, MeshProblemKind::kTooLarge);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->count, 162u);
  vertices.limits.max_vertices = 162;
  EXPECT_TRUE(LoadMesh(dir + "/sphere.stl", vertices).ok());
}

TEST(MeshProblems, BadScale) {
  const std::string dir = testing::TempDir("scale");
  testing::WriteBinaryStl(dir + "/box.stl", TestBox());
  for (double s : {0.0, -1.0, double(NAN), double(INFINITY)})
    EXPECT_TRUE(Has(LoadMesh(dir + "/box.stl", testing::Scaled(s)).problems, MeshProblemKind::kBadScale)) << s;
}

TEST(MeshProblems, NoTriangles) {
  const std::string dir = testing::TempDir("no_triangles");
  testing::WriteText(dir + "/lines.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2 3\n");
  const MeshLoadResult r = LoadMesh(dir + "/lines.obj");
  EXPECT_NE(Find(r.problems, MeshProblemKind::kNoTriangles), nullptr) << Describe(r.problems);
  EXPECT_FALSE(r.ok());
  EXPECT_TRUE(Has(LoadVisualMesh(dir + "/lines.obj").problems, MeshProblemKind::kNoTriangles));
}

TEST(MeshProblems, NonFiniteCoordinates) {
  const std::string dir = testing::TempDir("non_finite");
  TriMesh box = TestBox();
  box.vertices[0].x() = INFINITY;
  testing::WriteBinaryStl(dir + "/box.stl", box);
  const MeshLoadResult r = LoadMesh(dir + "/box.stl");
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kNonFinite);
  ASSERT_NE(p, nullptr) << Describe(r.problems);
  EXPECT_EQ(p->count, 1u);
  EXPECT_TRUE(Has(LoadVisualMesh(dir + "/box.stl").problems, MeshProblemKind::kNonFinite));
}

TEST(MeshProblems, NotClosedCountsOpenEdges) {
  const std::string dir = testing::TempDir("not_closed");
  TriMesh box = TestBox();
  box.triangles.resize(10);  // the +x face is missing: its 4 sides are open
  testing::WriteAsciiStl(dir + "/open.stl", box);
  const MeshLoadResult r = LoadMesh(dir + "/open.stl");
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kNotClosed);
  ASSERT_NE(p, nullptr) << Describe(r.problems);
  EXPECT_EQ(p->count, 4u);
  EXPECT_NE(p->message.find("4 open edges"), std::string::npos) << p->message;
}

TEST(MeshProblems, InconsistentOrientation) {
  const std::string dir = testing::TempDir("orientation");
  TriMesh box = TestBox();
  std::swap(box.triangles[0][1], box.triangles[0][2]);
  testing::WriteObj(dir + "/box.obj", box, 1);
  const MeshLoadResult r = LoadMesh(dir + "/box.obj");
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kInconsistentOrientation);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->count, 3u);
}

TEST(MeshProblems, InsideOutIsFlippedWithWarning) {
  const std::string dir = testing::TempDir("inside_out");
  TriMesh box = TestBox();
  for (Tri& t : box.triangles) std::swap(t[1], t[2]);
  testing::WritePly(dir + "/box.ply", box);
  const MeshLoadResult r = LoadMesh(dir + "/box.ply");
  ASSERT_TRUE(r.ok()) << Describe(r.problems);
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kInsideOut);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->severity, Severity::kWarning);
  EXPECT_NEAR(ComputeMassProperties(r.mesh, MassSpec::Density(1)).volume, 1.0, 1e-12);
}

TEST(MeshProblems, ZeroVolume) {
  const std::string dir = testing::TempDir("zero_volume");
  testing::WriteText(dir + "/flat.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 1 3 2\nf 1 4 3\n");
  EXPECT_TRUE(Has(LoadMesh(dir + "/flat.obj").problems, MeshProblemKind::kZeroVolume));
}

TEST(MeshProblems, DegenerateTriangles) {
  const std::string dir = testing::TempDir("degenerate");
  TriMesh box = TestBox();
  box.triangles.push_back({0, 1, 1});
  testing::WriteBinaryStl(dir + "/box.stl", box);
  const MeshLoadResult r = LoadMesh(dir + "/box.stl");
  ASSERT_TRUE(r.ok()) << Describe(r.problems);
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kDegenerateTriangles);
  ASSERT_NE(p, nullptr) << Describe(r.problems);
  EXPECT_EQ(p->count, 1u);
  EXPECT_EQ(r.mesh.triangles.size(), 12u);
}

TEST(MeshProblems, NonManifoldWarning) {
  const std::string dir = testing::TempDir("non_manifold");
  TriMesh a = BoxSolid(Vec3(1, 1, 1)), b = BoxSolid(Vec3(1, 1, 1));
  Transform(a, Mat3::Identity(), Vec3(0.5, 0.5, 0));
  Transform(b, Mat3::Identity(), Vec3(-0.5, -0.5, 0));
  const auto offset = static_cast<uint32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const Tri& t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  testing::WriteBinaryStl(dir + "/two.stl", a);
  const MeshLoadResult r = LoadMesh(dir + "/two.stl");
  ASSERT_TRUE(r.ok()) << Describe(r.problems);
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kNonManifold);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->count, 1u);
}

// Run by ctest with KANESIM_GEOMETRY_MODULE pointing nowhere (tests/geometry/CMakeLists.txt):
// the loader must say it cannot load the module instead of crashing.
TEST(MeshProblems, ModuleMissing) {
  const char* env = std::getenv("KANESIM_GEOMETRY_MODULE");
  if (!env || std::filesystem::exists(env)) GTEST_SKIP() << "run with KANESIM_GEOMETRY_MODULE set to a missing file";
  const std::string dir = testing::TempDir("module_missing");
  testing::WriteBinaryStl(dir + "/box.stl", TestBox());
  const MeshLoadResult r = LoadMesh(dir + "/box.stl");
  const MeshProblem* p = Find(r.problems, MeshProblemKind::kModuleMissing);
  ASSERT_NE(p, nullptr) << Describe(r.problems);
  EXPECT_NE(p->message.find(env), std::string::npos) << p->message;
}

}  // namespace
}  // namespace kanesim::geometry
