// The test models that suites kept writing out again: a rod (L = 1, m = 1) hung on one joint
// in gravity along -y, and the two-rod pendulum below it. Text for LoadModel(text, ..., true)
// or a .mech file; each suite adds its joint's modifiers, declarations and equations.
#pragma once

#include <string>

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

}  // namespace kanesim::test
