// The last pieces of issue 22's drawings, as a user runs them: a mesh used only for looks on a
// body whose mass properties are given (BodyShape), rolling disks drawn as disks, and the
// joints' frames drawn as small axes (--show-frames); each written by `kanesim run
// --animation` and parsed back against the CSV of the same run (check_animation.py).
#include <gtest/gtest.h>

#include <string>

#include "tests/support/cli_util.h"
#include "tests/support/mesh_fixtures.h"
#include "tests/scene/shapes_model.h"

namespace kanesim {
namespace {

using clitest::Kanesim;

std::string Check(const std::string& dir, const std::string& args) {
  const std::string cmd = "cd '" + dir + "' && python3 " + clitest::kSrc + "/tests/scene/check_animation.py " + args +
                          " > check.out 2>&1";
  return std::system(cmd.c_str()) == 0 ? "" : clitest::Slurp(dir + "/check.out");
}

// A slider with a pendulum whose link is a Body given by its mass properties; `LINK` is
// replaced by the declaration under test.
const char* kPendulum = R"(model P
  World world(g = {0, 0, -9.81});
  Prismatic s(axis = {1, 0, 0}, u(start = 0.3));
  Body cart(m = 3, I = diagonal({0.1, 0.1, 0.1}));
  Revolute j(axis = {0.2, 1, 0.1}, q(start = 0.7), u(start = -1));
  LINK
equation
  connect(world.frame_b, s.frame_a);
  connect(s.frame_b, cart.frame_a);
  connect(cart.frame_a, j.frame_a);
  connect(j.frame_b, link.frame_a);
  annotation(experiment(StopTime = 2, Interval = 0.02));
end P;
)";

std::string Pendulum(const std::string& link) {
  std::string text = kPendulum;
  text.replace(text.find("LINK"), 4, link);
  return text;
}

// If this fails, a mesh used only for looks changed the motion (its mass properties must be
// the ones given, not the mesh's), a mesh that is not closed was refused for drawing, or the
// mesh is not what the animation draws (the box 1 × 0.1 × 0.05 m written in millimetres).
TEST(SceneGaps, BodyShapeMeshIsLooksOnly) {
  const std::string dir = clitest::Work("scenegaps_bodyshape");
  std::filesystem::create_directories(dir + "/meshes");
  ASSERT_TRUE(meshfix::WriteMeshFixture(dir + "/meshes/link_open.stl", "open"));  // not closed: no solid
  ASSERT_TRUE(meshfix::WriteMeshFixture(dir + "/meshes/link_mm.stl", "box_mm"));
  const std::string mass = "m = 2, r_CM = {0.5, 0, 0}, I = diagonal({0.004, 0.17, 0.172})";
  clitest::Write(dir + "/plain.mech", Pendulum("Body link(" + mass + ");"));
  clitest::Write(dir + "/open.mech",
                 Pendulum("BodyShape link(" + mass + ", file = \"meshes/link_open.stl\", color = \"steel\");"));
  clitest::Write(dir + "/mm.mech",
                 Pendulum("BodyShape link(" + mass + ", file = \"meshes/link_mm.stl\", scale = 0.001);"));
  ASSERT_EQ(Kanesim("run plain.mech --output 's.*' --output 'j.*' --output '*energy' -o plain.csv", dir).rc, 0);
  for (const std::string name : {"open", "mm"}) {
    clitest::Result r = Kanesim("run " + name + ".mech --output 's.*' --output 'j.*' --output '*energy' -o " + name +
                                    ".csv --animation " + name + ".glb",
                                dir);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(clitest::Slurp(dir + "/plain.csv"), clitest::Slurp(dir + "/" + name + ".csv")) << name;
    ASSERT_EQ(Kanesim("run " + name + ".mech --output '*.r[*]' --output '*.R[*]' -o " + name + "_pose.csv "
                      "--animation " + name + "_pose.glb", dir).rc, 0);
    EXPECT_EQ(Check(dir, name + "_pose.glb " + name + "_pose.csv --up 0,0,1 --body cart=s.frame_b:cart "
                    "--body link=j.frame_b:link.body --bounds link=0,1,-0.05,0.05,-0.025,0.025"), "") << name;
  }
  // The viewer draws it too: its page holds the body's label with the file.
  clitest::Result v = Kanesim("view mm.mech --html mm.html", dir);
  ASSERT_EQ(v.rc, 0) << v.err;
  EXPECT_TRUE(clitest::Has(clitest::Slurp(dir + "/mm.html"), "BodyShape link (")) << v.err;
  // `check` reports no mesh body: the mesh gives no mass properties.
  clitest::Result c = Kanesim("check mm.mech", dir);
  EXPECT_EQ(c.rc, 0) << c.err;
  EXPECT_FALSE(clitest::Has(c.out, "mesh bodies")) << c.out;
  // A missing file is reported at the declaration when it is drawn.
  clitest::Write(dir + "/missing.mech", Pendulum("BodyShape link(" + mass + ", file = \"meshes/nope.stl\");"));
  ASSERT_EQ(Kanesim("run missing.mech -o m.csv", dir).rc, 0);  // not drawn: not read
  c = Kanesim("run missing.mech -o m.csv --animation m.glb", dir);
  EXPECT_EQ(c.rc, 1);
  EXPECT_TRUE(clitest::Has(c.err, "missing.mech:6:")) << c.err;
  EXPECT_TRUE(clitest::Has(c.err, "nope.stl")) << c.err;
}

// If this fails, the rolling disk of the example is not drawn as a disk of its radius about
// its axis (z of the body frame; radius 0.3 m, a tenth of it thick).
TEST(SceneGaps, RollingDiskDrawnAsDisk) {
  const std::string dir = clitest::Work("scenegaps_disk");
  const std::string ex = clitest::kSrc + "/examples/rolling_disk.mech";
  clitest::Result r = Kanesim("run '" + ex + "' --stop-time 1 --output '*.r[*]' --output '*.R[*]' -o disk.csv "
                              "--animation disk.glb", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(Check(dir, "disk.glb disk.csv --up 0,1,0 --body disk=free.frame_b:disk "
                  "--bounds disk=-0.3,0.3,-0.3,0.3,-0.015,0.015"), "");
  r = Kanesim("view '" + ex + "' --stop-time 1 --html disk.html", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(clitest::Has(clitest::Slurp(dir + "/disk.html"), "rolling disk contact, radius 0.3 m"));
}

// If this fails, --show-frames does not draw each joint frame that moves as three axes at the
// frame's origin (from the CSV), turned with the body it is fixed in, or draws them without
// being asked.
TEST(SceneGaps, ShowFramesDrawsJointFrameAxes) {
  const std::string dir = scenetest::ShapesDir("scenegaps_frames");
  clitest::Result r = Kanesim("run shapes.mech --output '*.r[*]' --output '*.R[*]' -o shapes.csv "
                              "--animation frames.glb --show-frames", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  // Axes 1/10 of the largest drawing (the link, 1.0016 m to its far corner). The world's
  // frames (j1.frame_a, s.frame_a) are not drawn; s.frame_b is j5.frame_a (drawn once).
  const std::string axes =
      " --axes j1.frame_b=0.1:arm.body --axes arm.frame_b=0.1:arm.body --axes j2.frame_b=0.1:link.body"
      " --axes tip.frame_b=0.1:link.body --axes j3.frame_b=0.1:cyl.body --axes cyl.frame_b=0.1:cyl.body"
      " --axes j4.frame_b=0.1:ball.body --axes s.frame_b=0.1:slab --axes j5.frame_b=0.1:rod.body";
  EXPECT_EQ(Check(dir, std::string("frames.glb shapes.csv --up 0,0,1") + scenetest::kBodies + axes), "");
  ASSERT_EQ(Kanesim("run shapes.mech --output '*.r[*]' --output '*.R[*]' -o plain.csv --animation plain.glb", dir).rc,
            0);
  EXPECT_EQ(Check(dir, std::string("plain.glb plain.csv --up 0,0,1") + scenetest::kBodies), "");
  // A frame turned against its body (FixedRotation): its axes turn with it, as the Body
  // `mark` fixed in it does (mark.R is R_WF, computed by the runtime, not by the drawing).
  clitest::Write(dir + "/rot.mech", R"(model R
  World world(g = {0, -9.81, 0});
  Revolute j1(axis = {0, 0, 1}, q(start = 0.4), u(start = 1));
  Body link(m = 1, r_CM = {0.25, 0, 0}, I = diagonal({0.001, 0.02, 0.02}));
  FixedRotation fr(r = {0.5, 0, 0}, n = {1, 1, 0}, angle = 0.6);
  Body mark(m = 0.1);
  Revolute j2(axis = {0, 0, 1}, u(start = -2));
  Body link2(m = 0.5, r_CM = {0.2, 0, 0}, I = diagonal({0.0005, 0.01, 0.01}));
equation
  connect(world.frame_b, j1.frame_a);
  connect(j1.frame_b, link.frame_a);
  connect(link.frame_a, fr.frame_a);
  connect(fr.frame_b, mark.frame_a);
  connect(fr.frame_b, j2.frame_a);
  connect(j2.frame_b, link2.frame_a);
  annotation(experiment(StopTime = 1, Interval = 0.02));
end R;
)");
  r = Kanesim("run rot.mech --output '*.r[*]' --output '*.R[*]' -o rot.csv --animation rot.glb --show-frames", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  // Axes a tenth of the largest drawing: link's inertia box, 0.495 m to its far corner.
  EXPECT_EQ(Check(dir, "rot.glb rot.csv --up 0,1,0 --body link=j1.frame_b:link --body mark=fr.frame_b:mark "
                  "--body link2=j2.frame_b:link2 --axes j1.frame_b=0.0495:link --axes fr.frame_b=0.0495:mark "
                  "--axes j2.frame_b=0.0495:link2"), "");
  // Without --animation the flag has nothing to draw on: refused.
  r = Kanesim("run shapes.mech -o x.csv --show-frames", dir);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(clitest::Has(r.err, "--animation")) << r.err;
  // The viewer takes the same option.
  r = Kanesim("view shapes.mech --show-frames --html frames.html", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(clitest::Has(clitest::Slurp(dir + "/frames.html"), "x axis of frame j1.frame_b"));
}

}  // namespace
}  // namespace kanesim
