// The test model of tests/scene: every stdlib shape, a MeshBody and a bare Body on revolute,
// spherical and prismatic joints, and what each body looks like (shared by the animation and
// viewer tests).
#pragma once

#include <filesystem>
#include <string>

#include "tests/support/cli_util.h"
#include "tests/support/mesh_fixtures.h"

namespace kanesim::scenetest {

// Gravity along −z (so the export must turn the world: up = +z becomes glTF's +Y).
inline const char* kShapes = R"(model Shapes
  World world(g = {0, 0, -9.81});
  Revolute j1(axis = {0, 1, 0}, q(start = 0.3));
  Box arm(lx = 0.5, ly = 0.08, lz = 0.04, density = 2700, color = "#FF0000");
  Revolute j2(axis = {0, 1, 0}, q(start = -0.5), u(start = 1));
  MeshBody link(file = "meshes/link.stl", density = 2700);
  FixedTranslation tip(r = {1, 0, 0});
  Spherical j3(u(start = {0.5, 1, 2}));
  Cylinder cyl(length = 0.3, radius = 0.03);
  Revolute j4(axis = {1, 0, 0}, u(start = 3));
  Sphere ball(radius = 0.05, density = 7800);
  Prismatic s(axis = {1, 0, 0}, u(start = 0.2));
  Body slab(m = 2, I = diagonal({0.02, 0.03, 0.04}));
  Revolute j5(axis = {0, 1, 0}, q(start = 1));
  Rod rod(L = 0.4, m = 0.5);
  Sphere hidden(radius = 0.02, m = 0.1, visual = false);
equation
  connect(world.frame_b, j1.frame_a);
  connect(j1.frame_b, arm.frame_a);
  connect(arm.frame_b, j2.frame_a);
  connect(j2.frame_b, link.frame_a);
  connect(link.frame_a, tip.frame_a);
  connect(tip.frame_b, j3.frame_a);
  connect(j3.frame_b, cyl.frame_a);
  connect(cyl.frame_b, j4.frame_a);
  connect(j4.frame_b, ball.frame_a);
  connect(world.frame_b, s.frame_a);
  connect(s.frame_b, slab.frame_a);
  connect(slab.frame_a, j5.frame_a);
  connect(j5.frame_b, rod.frame_a);
  connect(rod.frame_b, hidden.frame_a);
  annotation(experiment(StopTime = 1, Interval = 0.01));
end Shapes;
)";

// node = canonical frame of the body : the body whose R is written.
inline const char* kBodies =
    " --body arm=j1.frame_b:arm.body --body link=j2.frame_b:link.body --body cyl=j3.frame_b:cyl.body"
    " --body ball=j4.frame_b:ball.body --body slab=s.frame_b:slab --body rod=j5.frame_b:rod.body";
// Drawings in their body frames: the Box and the mesh (the box 1 × 0.1 × 0.05 m) span
// x = 0 .. length centred in y and z, the Cylinder too (32 segments reach ±r on y and z);
// the bare Body is its inertia-equivalent box, sides sqrt(6 (I2 + I3 − I1) / m) =
// sqrt(0.15), sqrt(0.09), sqrt(0.03) m (primitives.h); the Sphere's farthest vertex is r;
// the arm's color "#FF0000" is linear (1, 0, 0); `hidden` (visual = false) has no node.
inline const char* kShapesDrawn =
    " --bounds arm=0,0.5,-0.04,0.04,-0.02,0.02 --bounds link=0,1,-0.05,0.05,-0.025,0.025"
    " --bounds cyl=0,0.3,-0.03,0.03,-0.03,0.03"
    " --bounds slab=-0.19364916731,0.19364916731,-0.15,0.15,-0.08660254038,0.08660254038"
    " --radius ball=0.05 --color arm=1,0,0";

// A fresh work folder with shapes.mech and meshes/link.stl.
inline std::string ShapesDir(const std::string& name) {
  const std::string dir = clitest::Work(name);
  std::filesystem::create_directories(dir + "/meshes");
  if (!meshfix::WriteMeshFixture(dir + "/meshes/link.stl", "box")) return "";
  clitest::Write(dir + "/shapes.mech", kShapes);
  return dir;
}

}  // namespace kanesim::scenetest
