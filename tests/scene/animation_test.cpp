// `kanesim run --animation` as a user runs it: every stdlib shape, a MeshBody and a bare Body
// on joints of several kinds, written as .glb and as .gltf, then parsed back against the CSV
// of the same run (check_animation.py) and validated by the Khronos glTF validator.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "tests/support/cli_util.h"
#include "tests/support/mesh_fixtures.h"
#include "tests/scene/shapes_model.h"

namespace kanesim {
namespace {

using clitest::Kanesim;
using scenetest::kBodies;
using scenetest::kShapesDrawn;
using scenetest::ShapesDir;

std::string Python() { return "python3 " + clitest::kSrc + "/tests/scene/check_animation.py "; }

// If this fails, the animation does not show the simulated motion (see check_animation.py
// for each way), or a format is not written.
TEST(Animation, ShapesParsedBackEqualTheCsvPoses) {
  const std::string dir = ShapesDir("animation");
  for (const char* file : {"shapes.glb", "shapes.gltf"}) {
    clitest::Result r = Kanesim(std::string("run shapes.mech --output '*.r[*]' --output '*.R[*]' -o shapes.csv "
                                            "--animation ") + file, dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(clitest::CsvRows(dir + "/shapes.csv"), 101);
    const std::string cmd = "cd '" + dir + "' && " + Python() + file + " shapes.csv --up 0,0,1" + kBodies +
                            kShapesDrawn + " > check.out 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << clitest::Slurp(dir + "/check.out");
  }
  EXPECT_TRUE(std::filesystem::exists(dir + "/shapes.bin"));  // the .gltf's buffer beside it
}

// If this fails, the default CSV changed because of --animation (the poses must ride along
// without being written), or a bad --animation path is accepted.
TEST(Animation, CsvUnchangedAndBadPathsRefused) {
  const std::string dir = ShapesDir("animation_csv");
  ASSERT_EQ(Kanesim("run shapes.mech -o plain.csv", dir).rc, 0);
  ASSERT_EQ(Kanesim("run shapes.mech -o anim.csv --animation a.glb", dir).rc, 0);
  EXPECT_EQ(clitest::Slurp(dir + "/plain.csv"), clitest::Slurp(dir + "/anim.csv"));
  clitest::Result r = Kanesim("run shapes.mech -o x.csv --animation a.obj", dir);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(clitest::Has(r.err, "must end in .glb")) << r.err;
  r = Kanesim("run shapes.mech -o x.csv --animation no/such/dir/a.glb", dir);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(clitest::Has(r.err, "cannot write the animation")) << r.err;
}

// If this fails, the file kanesim writes is not valid glTF 2.0 for the Khronos validator.
TEST(Animation, KhronosValidatorFindsNoError) {
  const std::string tools = clitest::kSrc + "/tests/tools";
  if (!std::filesystem::exists(tools + "/node_modules/gltf-validator"))
    GTEST_SKIP() << "gltf-validator not installed (scripts/setup.sh: npm ci in tests/tools)";
  const std::string dir = ShapesDir("animation_valid");
  ASSERT_EQ(Kanesim("run shapes.mech -o s.csv --animation s.glb", dir).rc, 0);
  ASSERT_EQ(Kanesim("run shapes.mech -o s.csv --animation s.gltf", dir).rc, 0);
  const std::string cmd =
      "cd '" + dir + "' && node '" + tools + "/validate_gltf.js' s.glb s.gltf > validator.out 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << clitest::Slurp(dir + "/validator.out");
  const std::string out = clitest::Slurp(dir + "/validator.out");
  EXPECT_TRUE(clitest::Has(out, "s.glb: 0 errors, 0 warnings")) << out;
  EXPECT_TRUE(clitest::Has(out, "s.gltf: 0 errors, 0 warnings")) << out;
}

}  // namespace
}  // namespace kanesim
