// ExportAnimation's input checks, naming, orientation and decimation (geometry/gltf_export.h).
// The written files themselves are parsed back by check_gltf.py and the Khronos validator.
#include "geometry/gltf_export.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "geometry/primitives.h"
#include "tests/support/mesh_files.h"

namespace kanesim::geometry {
namespace {

struct Scene {
  std::vector<AnimatedBody> bodies;
  PoseSequence poses;
};

// n instants at times 0, dt, 2 dt, ... of two bodies at rest.
Scene Make(int n, double dt = 0.01) {
  Scene s;
  s.bodies = {{"a", DrawBox(Vec3(1, 1, 1))}, {"b", DrawSphere(0.5, 1)}};
  for (int k = 0; k < n; ++k) {
    s.poses.times.push_back(k * dt);
    for (int b = 0; b < 2; ++b) {
      s.poses.p_WB.push_back(Vec3(b, k, 0));
      s.poses.q_WB.push_back(Eigen::Quaterniond::Identity());
    }
  }
  return s;
}

std::string Export(const Scene& s, const std::string& name, ExportOptions options = {}) {
  const std::string dir = testing::TempDir("export_" + name);
  return ExportAnimation(dir + "/" + name, s.bodies, s.poses, options).error;
}

// Wrong if bad input reaches assimp (NaN times, garbage rotations) instead of a clear error.
TEST(ExportAnimation, RejectsBadInput) {
  EXPECT_NE(Export(Make(3), "out.obj").find(".glb or .gltf"), std::string::npos);
  Scene s = Make(3);
  s.poses.times[2] = 0.0;
  EXPECT_NE(Export(s, "t.glb").find("must not decrease"), std::string::npos);
  s = Make(3);
  s.poses.times[0] = -1;
  EXPECT_NE(Export(s, "neg.glb").find(">= 0"), std::string::npos);
  s = Make(3);
  s.poses.q_WB[3].coeffs() *= 1.1;
  EXPECT_NE(Export(s, "q.glb").find("unit quaternion"), std::string::npos);
  s = Make(3);
  s.poses.p_WB[1].x() = NAN;
  EXPECT_NE(Export(s, "p.glb").find("not finite"), std::string::npos);
  s = Make(3);
  s.poses.p_WB.pop_back();
  EXPECT_NE(Export(s, "size.glb").find("need 6"), std::string::npos);
  s = Make(3);
  s.bodies[1].rgba[0] = 2;
  EXPECT_NE(Export(s, "color.glb").find("colour"), std::string::npos);
  s = Make(3);
  s.bodies[0].mesh.normals.pop_back();
  EXPECT_NE(Export(s, "normals.glb").find("normals"), std::string::npos);
  s = Make(3);
  s.bodies.clear();
  EXPECT_NE(Export(s, "none.glb").find("no bodies"), std::string::npos);
  ExportOptions zero_up;
  zero_up.up_W = Vec3::Zero();
  EXPECT_NE(Export(Make(3), "up.glb", zero_up).find("up direction"), std::string::npos);
}

// Wrong if the Y-up rotation does not take the world's up to +Y for any up (including −Y).
TEST(ExportAnimation, UpToYTakesUpToPlusY) {
  for (const Vec3& up : {Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(1, 0, 0), Vec3(0.3, -2, 0.7)}) {
    const Eigen::Quaterniond q = UpToY(up);
    EXPECT_NEAR(q.norm(), 1, 1e-15);
    EXPECT_LE((q * up.normalized() - Vec3::UnitY()).norm(), 4e-15) << up.transpose();  // a few ulps
  }
  EXPECT_LE((UpToY(Vec3(0, 3, 0)).toRotationMatrix() - Mat3::Identity()).norm(), 1e-15);
  // Z up becomes Y up as in common converters: x stays, y goes to −z.
  EXPECT_LE((UpToY(Vec3::UnitZ()) * Vec3::UnitY() - Vec3(0, 0, -1)).norm(), 1e-15);
}

// Wrong if two bodies share a node name (assimp then moves only the first) or a name can
// equal an assimp-internal id such as material_0 (the exporter crashes).
TEST(ExportAnimation, NodeNamesUniqueAndPrefixed) {
  std::vector<AnimatedBody> bodies(4);
  bodies[0].name = "arm";
  bodies[1].name = "arm";
  bodies[2].name = "arm_2";
  bodies[3].name = "material_0";
  const std::vector<std::string> names = UniqueNodeNames(bodies);
  EXPECT_EQ(names, (std::vector<std::string>{"body_arm", "body_arm_2", "body_arm_2_2", "body_material_0"}));
}

// Wrong if long runs are not decimated to the limit (every stride-th instant and the last), or
// if instants whose float times coincide are written (glTF needs strictly increasing times).
TEST(ExportAnimation, DecimationAndMergedTimes) {
  const std::string dir = testing::TempDir("decimate");
  Scene s = Make(1001);
  ExportOptions options;
  options.max_keys = 2 * 101;  // 101 keys per body at most
  ExportResult r = ExportAnimation(dir + "/long.glb", s.bodies, s.poses, options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.stride, 10u);
  EXPECT_EQ(r.times_written, 101u);
  options.max_keys = 2 * 100;  // 1000 / 99 → stride 11: 0, 11, …, 990 and 1000
  r = ExportAnimation(dir + "/long.glb", s.bodies, s.poses, options);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.stride, 11u);
  EXPECT_EQ(r.times_written, 92u);

  s = Make(4);
  s.poses.times = {0.0, 1.0, 1.0, 1.0 + 1e-12};  // the last three are one float
  r = ExportAnimation(dir + "/merged.gltf", s.bodies, s.poses);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.times_written, 2u);
  EXPECT_EQ(r.times_merged, 2u);
  ASSERT_EQ(r.files.size(), 2u);
  EXPECT_TRUE(std::filesystem::exists(r.files[0]));
  EXPECT_TRUE(std::filesystem::exists(r.files[1])) << r.files[1];
}

// Wrong if an unwritable path is reported as success (assimp's message must come back).
TEST(ExportAnimation, UnwritablePathFails) {
  const ExportResult r =
      ExportAnimation("/nonexistent/dir/out.glb", Make(2).bodies, Make(2).poses);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("assimp could not write"), std::string::npos) << r.error;
}

}  // namespace
}  // namespace kanesim::geometry
