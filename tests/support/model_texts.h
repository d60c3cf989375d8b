// The test models that suites kept writing out again, one builder each with a comment saying
// what the model is: a rod (L = 1, m = 1) hung on one joint in gravity along -y, the two-rod
// pendulum below it, the four-bar example, the plane-friction carriage and leg, the rack pair,
// the carrier with an inclined slider, the double pendulum with an elbow.
// Text for LoadModel(text, ..., true) or a .mech file; each suite adds its joint's modifiers,
// declarations and equations.
#pragma once

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/load_util.h"  // kRoot

namespace kanesim::test {

// x in a model text, every digit kept (%.17g).
inline std::string Num(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

// model <model>
// <decls>  World world(g = {0, -9.81, 0});
//   <joint> <name>(axis = <axis><mods>);
//   Rod rod(L = 1, m = 1);
// equation  (world -> joint -> rod)  <equations>
// end <model>;
struct PendulumText {
  std::string model = "P";
  std::string decls{};              // lines before the world ("  input Real tau;\n")
  std::string joint = "Revolute";   // the joint's class
  std::string name = "j1";          // ... and its name
  std::string axis = "{0, 0, 1}";
  std::string mods{};               // after the axis: ", q(start = 0.5), u(start = 0)"
  std::string equations{};          // lines after the two connects
  std::string Text() const {
    return "model " + model + "\n" + decls + "  World world(g = {0, -9.81, 0});\n  " + joint + " " + name +
           "(axis = " + axis + mods + ");\n  Rod rod(L = 1, m = 1);\nequation\n  connect(world.frame_b, " + name +
           ".frame_a);\n  connect(" + name + ".frame_b, rod.frame_a);\n" + equations + "end " + model + ";\n";
  }
};

// model D: world -> j1 -> rod1 (L = 1, m = 1) -> j2 -> rod2 (L = 0.8, m = 0.7), both joints
// Revolute about z; j1_mods / j2_mods follow each axis (", q(start = 0.3)"), `equations`
// the connects.
inline std::string TwoRodText(const std::string& j1_mods, const std::string& j2_mods, const std::string& equations = "") {
  return "model D\n"
         "  World world(g = {0, -9.81, 0});\n"
         "  Revolute j1(axis = {0, 0, 1}" + j1_mods + ");\n"
         "  Revolute j2(axis = {0, 0, 1}" + j2_mods + ");\n"
         "  Rod rod1(L = 1, m = 1);\n"
         "  Rod rod2(L = 0.8, m = 0.7);\n"
         "equation\n"
         "  connect(world.frame_b, j1.frame_a);\n"
         "  connect(j1.frame_b, rod1.frame_a);\n"
         "  connect(rod1.frame_b, j2.frame_a);\n"
         "  connect(j2.frame_b, rod2.frame_a);\n" + equations +
         "end D;\n";
}

// examples/fourbar.mech (crank a = 0.2, coupler b = 0.6, rocker c = 0.5: uniform rods of
// 0.5, 1.0, 0.8 kg; ground d = 0.6; crank at theta0 = 0.3, fixed; gravity along -y) with the
// loop suites' edits, the example itself the one text. "" when the example lost a piece an
// edit needs (the suite's LoadModel then fails).
struct FourBarText {
  double omega0 = 6;                    // the crank's start rate (rad/s)
  bool gravity = true;                  // false: g = {0, 0, 0}
  std::string crank_mods{};             // after the crank pivot's u(start = omega0): ", q_min = 0.3"
  std::string coupler_mods{};           // after crank_coupler's q(start = 1.0)
  std::string rocker_mods{};            // after rocker_pivot's q(start = 1.6)
  std::string base = "world.frame_b";   // the frame the crank's pivot and the ground hang on
  std::string decls{};                  // declarations before `equation` ("  Body carrier(m = 1);\n")
  std::string connects{};               // lines right after `equation`
  std::string equations{};              // lines before the annotation (drives, when clauses)
  std::string Text() const {
    std::ifstream in(kRoot + "/examples/fourbar.mech");
    std::stringstream buf;
    buf << in.rdbuf();
    std::string text = buf.str();
    bool ok = true;
    auto put = [&](const std::string& from, const std::string& to) {
      const size_t at = text.find(from);
      ok = ok && at != std::string::npos;
      if (at != std::string::npos) text.replace(at, from.size(), to);
    };
    if (omega0 != 6) put("\"rad/s\") = 6", "\"rad/s\") = " + Num(omega0));
    if (!gravity) put("g = {0, -9.81, 0}", "g = {0, 0, 0}");
    put("u(start = omega0)", "u(start = omega0)" + crank_mods);
    put("q(start = 1.0)", "q(start = 1.0)" + coupler_mods);
    put("q(start = 1.6)", "q(start = 1.6)" + rocker_mods);
    put("connect(world.frame_b, crank_pivot.frame_a)", "connect(" + base + ", crank_pivot.frame_a)");
    put("connect(world.frame_b, ground.frame_a)", "connect(" + base + ", ground.frame_a)");
    put("equation\n", decls + "equation\n" + connects);
    put("  annotation(experiment", equations + "  annotation(experiment");
    return ok ? text : "";
  }
};

// The plane-friction suites' carriage and leg (docs/stdlib.md "PlaneContact"): a carriage
// (m_c = 2) on a prismatic joint cx along x with Coulomb friction mu = 0.3, on it a revolute
// leg about z at the carriage's origin, a massless rod of length L = 1 and a point mass
// m_l = 0.5 at its tip, which touches the floor y = -L cos(phi) (PlaneContact foot, phi = 0.6)
// at the leg's angle q = phi; gravity g along -y. `decls` follow the foot, `equations` the
// six connects (a second path's connects, the drive).
struct CarriageLegText {
  static constexpr double kMc = 2.0, kMl = 0.5, kL = 1.0, kPhi = 0.6, kMu = 0.3;
  std::string model = "L";
  double g = 9.81;
  double uc0 = 0;      // cx's start speed
  double q0 = kPhi;    // the leg's start angle
  double w0 = 0;       // ... and rate
  double e = 0;        // the foot's restitution
  std::string law{};   // cx's modifiers after mu: ", friction_exact = true"
  std::string decls{};
  std::string equations{};
  std::string Text() const {
    return "model " + model + "\n"
           "  World world(g = {0, " + Num(-g) + ", 0});\n"
           "  Prismatic cx(axis = {1, 0, 0}, u(start = " + Num(uc0) + "), mu = " + Num(kMu) + law + ");\n"
           "  Body carriage(m = " + Num(kMc) + ");\n"
           "  Revolute leg(axis = {0, 0, 1}, q(start = " + Num(q0) + "), u(start = " + Num(w0) + "));\n"
           "  FixedTranslation rod(r = {0, " + Num(-kL) + ", 0});\n"
           "  Body tip(m = " + Num(kMl) + ");\n"
           "  PlaneContact foot(n = {0, 1, 0}, d = " + Num(-kL * std::cos(kPhi)) + ", restitution = " + Num(e) + ");\n" +
           decls +
           "equation\n"
           "  connect(world.frame_b, cx.frame_a);\n"
           "  connect(cx.frame_b, carriage.frame_a);\n"
           "  connect(carriage.frame_a, leg.frame_a);\n"
           "  connect(leg.frame_b, rod.frame_a);\n"
           "  connect(rod.frame_b, tip.frame_a);\n"
           "  connect(rod.frame_b, foot.frame_a);\n" +
           equations + "end " + model + ";\n";
  }
};

// model Rack, the rack pair: two blocks on prismatic joints along x geared q2 = r q1
// (JointCoupling, r = -1/2), gravity g = 9.81 along -y; block 1 (m1 = 1) on j1 at the origin
// with a stop q_min = 0, block 2 (m2 = 2) on j2 one metre above with Coulomb friction
// mu = 0.3; by default driven by tau1 = 5 (t - 0.5).
struct RackPairText {
  // the numbers in the text, for the suites' hand statics
  static constexpr double kM1 = 1.0, kM2 = 2.0, kR = -0.5, kMu = 0.3, kG = 9.81;
  std::string j1_mods = ", restitution = 0";       // after j1's q_min = 0
  std::string j2_law = ", friction_exact = true";  // after j2's mu
  std::string equations = "  j1.tau = 5 * (time - 0.5);\n";
  std::string Text() const {
    return "model Rack\n"
           "  World world(g = {0, -9.81, 0});\n"
           "  Prismatic j1(axis = {1, 0, 0}, q_min = 0" + j1_mods + ");\n"
           "  Body b1(m = 1);\n"
           "  FixedTranslation base(r = {0, 1, 0});\n"
           "  Prismatic j2(axis = {1, 0, 0}, mu = 0.3" + j2_law + ");\n"
           "  Body b2(m = 2);\n"
           "  JointCoupling gear(ratio = -0.5);\n"
           "equation\n"
           "  connect(world.frame_b, j1.frame_a);\n"
           "  connect(j1.frame_b, b1.frame_a);\n"
           "  connect(world.frame_b, base.frame_a);\n"
           "  connect(base.frame_b, j2.frame_a);\n"
           "  connect(j2.frame_b, b2.frame_a);\n"
           "  connect(j1.drive, gear.flange_a);\n"
           "  connect(j2.drive, gear.flange_b);\n" +
           equations + "end Rack;\n";
  }
};

// model <model>: a carrier (m_c = 2) on a prismatic joint cx along x and on it a slider
// (m_s = 0.5) on a prismatic joint s along (cos th, sin th, 0) with Coulomb friction mu, whose
// normal force comes from the carrier's motion and gravity (gravity's y component `gy`, a
// text). `cx_mods` follow cx's axis (", u(start = 1)"), `friction` s's mu, `equations` the
// four connects.
struct CarrierSliderText {
  static constexpr double kMc = 2.0, kMs = 0.5;
  std::string model = "C";
  std::string gy = "0";
  std::string cx_mods{};
  double th = 0.6;      // the slider's axis angle from x (rad)
  double mu = 0.4;
  double us0 = 0;       // the slider's start speed
  std::string friction{};
  std::string equations{};
  std::string Text() const {
    return "model " + model + "\n"
           "  World world(g = {0, " + gy + ", 0});\n"
           "  Prismatic cx(axis = {1, 0, 0}" + cx_mods + ");\n"
           "  Body carrier(m = " + Num(kMc) + ");\n"
           "  Prismatic s(axis = {cos(" + Num(th) + "), sin(" + Num(th) + "), 0}, u(start = " + Num(us0) +
           "), mu = " + Num(mu) + friction + ");\n"
           "  Body slider(m = " + Num(kMs) + ");\n"
           "equation\n"
           "  connect(world.frame_b, cx.frame_a);\n"
           "  connect(cx.frame_b, carrier.frame_a);\n"
           "  connect(carrier.frame_a, s.frame_a);\n"
           "  connect(s.frame_b, slider.frame_a);\n" +
           equations + "end " + model + ";\n";
  }
};

// model DP, a double pendulum in the vertical plane (gravity along -y): body b1 (m = 1, centre
// 0.5 along x, I_zz = `i1`, a text) on a revolute j1 about z at the origin, an elbow 1 along x,
// and b2 (m = 0.5, centre 0.4, I_zz = 0.02) on a revolute j2 about z there. `j1_mods`,
// `j2_mods` follow the joints' axes.
struct ElbowPendulumText {
  std::string j1_mods{};
  std::string i1 = "0.1";
  std::string j2_mods{};
  std::string Text() const {
    return "model DP\n"
           "  World world(g = {0, -9.81, 0});\n"
           "  Revolute j1(axis = {0, 0, 1}" + j1_mods + ");\n"
           "  Body b1(m = 1, r_CM = {0.5, 0, 0}, I = [0.001, 0, 0; 0, " + i1 + ", 0; 0, 0, " + i1 + "]);\n"
           "  FixedTranslation elbow(r = {1, 0, 0});\n"
           "  Revolute j2(axis = {0, 0, 1}" + j2_mods + ");\n"
           "  Body b2(m = 0.5, r_CM = {0.4, 0, 0}, I = [0.001, 0, 0; 0, 0.02, 0; 0, 0, 0.02]);\n"
           "equation\n"
           "  connect(world.frame_b, j1.frame_a);\n"
           "  connect(j1.frame_b, b1.frame_a);\n"
           "  connect(j1.frame_b, elbow.frame_a);\n"
           "  connect(elbow.frame_b, j2.frame_a);\n"
           "  connect(j2.frame_b, b2.frame_a);\n"
           "end DP;\n";
  }
};

// model Lift: a sphere (m = 1, radius 0.1) on a FreeMotion, rolling on the plane y = 0
// (RollingSphere `contact`), pulled by the world force {0, pull, 0} (an expression: "2 * time").
inline std::string PulledSphereText(const std::string& pull, const std::string& u_start = "{1, 0, 0, 0, 0, -10}") {
  return "model Lift\n"
         "  World world(g = {0, -9.81, 0});\n"
         "  FreeMotion free(q(start = {0, 0.1, 0, 1, 0, 0, 0}), u(start = " + u_start + "));\n"
         "  Sphere ball(radius = 0.1, m = 1);\n"
         "  RollingSphere contact(radius = 0.1, n = {0, 1, 0});\n"
         "  WorldForce pull(force = {0, " + pull + ", 0});\n"
         "equation\n"
         "  connect(world.frame_b, free.frame_a);\n"
         "  connect(free.frame_b, ball.frame_a);\n"
         "  connect(free.frame_b, contact.frame_a);\n"
         "  connect(free.frame_b, pull.frame_b);\n"
         "end Lift;\n";
}

}  // namespace kanesim::test
