// The test models that suites kept writing out again: a rod (L = 1, m = 1) hung on one joint
// in gravity along -y, and the two-rod pendulum below it. Text for LoadModel(text, ..., true)
// or a .mech file; each suite adds its joint's modifiers, declarations and equations.
#pragma once

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/load_util.h"  // kRoot

namespace kanesim::test {

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
    char w[40];
    std::snprintf(w, sizeof w, "%.17g", omega0);
    if (omega0 != 6) put("\"rad/s\") = 6", std::string("\"rad/s\") = ") + w);
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

}  // namespace kanesim::test
