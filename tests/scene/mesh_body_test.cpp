// MeshBody as a user writes it: mass properties from a mesh file against closed forms and
// against the stdlib Box of the same solid, paths relative to the .mech file, the check
// report, and a pendulum whose link is a mesh moving like the same Box.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "lang/elaborate.h"
#include "stdlib/stdlib.h"
#include "tests/support/cli_util.h"
#include "tests/support/mesh_fixtures.h"

namespace kanesim {
namespace {

using clitest::Kanesim;
using clitest::Work;

// Coordinates reach us as single-precision floats (docs/visualization.md, "Precision"):
// 0.1 and 0.05 are rounded by up to 2^-24 relative, so sizes, volumes and inertias agree
// with the closed forms to a few 1e-8, not to 1e-15.
constexpr double kFloatRel = 5e-7;

struct Elab {
  lang::Program program;
  flat::Mechanism mech;
  std::string diags;
  bool ok = false;
};

// Elaborates `text` as if it were the file `path` (its mesh paths resolve against its folder).
std::unique_ptr<Elab> ElaborateAs(const std::string& path, const std::string& text) {
  auto e = std::make_unique<Elab>();
  lang::Diagnostics diags(&e->program.sources);
  e->ok = lang::LoadProgramFromText(path, text, stdlib::Files(), &e->program, diags) &&
          lang::Elaborate(e->program, {}, &e->mech, diags) && !diags.HasErrors();
  e->diags = diags.RenderAll();
  return e;
}

struct BodyProps {
  double m = 0, c[3] = {0, 0, 0}, I[9] = {};
};

BodyProps PropsOf(const flat::Mechanism& mech, const std::string& body) {
  const std::vector<double> p = flat::EvaluateParams(mech);
  for (const auto& b : mech.bodies) {
    if (b.name != body) continue;
    BodyProps r;
    r.m = flat::EvalParamExpr(mech, p, b.mass);
    for (int i = 0; i < 3; ++i) r.c[i] = flat::EvalParamExpr(mech, p, b.r_cm[static_cast<size_t>(i)]);
    for (int i = 0; i < 9; ++i) r.I[i] = flat::EvalParamExpr(mech, p, b.inertia[static_cast<size_t>(i)]);
    return r;
  }
  ADD_FAILURE() << "no body " << body;
  return {};
}

std::string Model(const std::string& parts) {
  return "model M\n  World world;\n  Revolute j(axis = {0, 0, 1});\n" + parts +
         "equation\n  connect(world.frame_b, j.frame_a);\n  connect(j.frame_b, link.frame_a);\nend M;\n";
}

// The uniform box lx × ly × lz spanning x = 0 .. lx: m = ρ lx ly lz, c = (lx/2, 0, 0),
// I = m/12 diag(ly² + lz², lx² + lz², lx² + ly²).
BodyProps BoxClosedForm(double rho, double lx, double ly, double lz) {
  BodyProps r;
  r.m = rho * lx * ly * lz;
  r.c[0] = lx / 2;
  r.I[0] = r.m / 12 * (ly * ly + lz * lz);
  r.I[4] = r.m / 12 * (lx * lx + lz * lz);
  r.I[8] = r.m / 12 * (lx * lx + ly * ly);
  return r;
}

void ExpectNear(const BodyProps& a, const BodyProps& b, const std::string& what) {
  EXPECT_NEAR(a.m, b.m, kFloatRel * b.m) << what;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a.c[i], b.c[i], kFloatRel) << what << " c" << i;
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(a.I[i], b.I[i], kFloatRel * b.I[4]) << what << " I" << i;
}

// If this fails, a MeshBody's mass, centre of mass or inertia is not that of its solid:
// the density, the scale, a given mass or the inertia's reference point is mishandled.
TEST(MeshBody, MassPropertiesMatchClosedForms) {
  const std::string dir = meshfix::MeshFixtureDir("mass");
  std::filesystem::create_directories(dir + "/meshes");
  ASSERT_TRUE(meshfix::WriteMeshFixture(dir + "/meshes/link.stl", "box"));
  ASSERT_TRUE(meshfix::WriteMeshFixture(dir + "/meshes/link_mm.stl", "box_mm"));
  const BodyProps closed = BoxClosedForm(2700, 1, 0.1, 0.05);

  auto e = ElaborateAs(dir + "/m.mech", Model("  MeshBody link(file = \"meshes/link.stl\", density = 2700);\n"));
  ASSERT_TRUE(e->ok) << e->diags;
  ExpectNear(PropsOf(e->mech, "link.body"), closed, "density");

  e = ElaborateAs(dir + "/m.mech",
                  Model("  MeshBody link(file = \"meshes/link_mm.stl\", scale = 0.001, density = 2700);\n"));
  ASSERT_TRUE(e->ok) << e->diags;
  ExpectNear(PropsOf(e->mech, "link.body"), closed, "millimetres, scale 0.001");

  // A given mass keeps the distribution: the inertia scales by m / (ρ V).
  e = ElaborateAs(dir + "/m.mech", Model("  MeshBody link(file = \"meshes/link.stl\", m = 5);\n"));
  ASSERT_TRUE(e->ok) << e->diags;
  ExpectNear(PropsOf(e->mech, "link.body"), BoxClosedForm(5.0 / (1 * 0.1 * 0.05), 1, 0.1, 0.05), "m = 5");

  // The same solid as the stdlib Box (its closed forms are the library's own, elaborated).
  e = ElaborateAs(dir + "/m.mech", Model("  Box link(lx = 1, ly = 0.1, lz = 0.05, density = 2700);\n"));
  ASSERT_TRUE(e->ok) << e->diags;
  ExpectNear(PropsOf(e->mech, "link.body"), closed, "stdlib Box");  std::filesystem::remove_all(dir);
}

// If this fails, a mesh path is read relative to the working directory instead of the
// .mech file that names it, or an error does not point at the declaration.
TEST(MeshBody, PathsAreRelativeToTheMechFile) {
  const std::string dir = Work("paths");
  std::filesystem::create_directories(dir + "/model/meshes");
  ASSERT_TRUE(meshfix::WriteMeshFixture(dir + "/model/meshes/link.stl", "box"));
  clitest::Write(dir + "/model/m.mech", Model("  MeshBody link(file = \"meshes/link.stl\", density = 2700);\n"));
  clitest::Write(dir + "/model/bad.mech", Model("  MeshBody link(file = \"meshes/nothere.stl\");\n"));
  clitest::Result r = Kanesim("check model/m.mech", dir);
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(clitest::Has(r.out, "mesh bodies 1")) << r.out;
  EXPECT_TRUE(clitest::Has(r.out, "model/meshes/link.stl")) << r.out;
  EXPECT_TRUE(clitest::Has(r.out, "mass 13.5")) << r.out;  // 2700 · 1 · 0.1 · 0.05, to 10 digits
  r = Kanesim("check model/bad.mech", dir);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(clitest::Has(r.err, "model/bad.mech:4:24: error[E230]")) << r.err;
  EXPECT_TRUE(clitest::Has(r.err, "model/meshes/nothere.stl")) << r.err;
}

std::vector<std::vector<double>> ReadCsv(const std::string& path, std::vector<std::string>* header) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> row;
    std::vector<std::string> names;
    while (std::getline(ss, cell, ',')) {
      if (header && header->empty() && rows.empty()) names.push_back(cell);
      else row.push_back(std::stod(cell));
    }
    if (!names.empty()) *header = names;
    else rows.push_back(row);
  }
  return rows;
}

// If this fails, the mesh pendulum's dynamics differ from the same Box's: a mass property
// from the mesh (or the frame it is resolved in) is wrong in a way the numbers alone may hide.
TEST(MeshBody, PendulumMovesLikeTheSameBox) {
  const std::string dir = Work("pendulum");
  std::filesystem::create_directories(dir + "/meshes");
  // Off-axis on purpose: the link is turned about x so that every inertia term matters.
  ASSERT_TRUE(meshfix::WriteMeshFixture(dir + "/meshes/link.stl", "box"));
  const std::string head =
      "model P\n  World world(g = {0, -9.81, 0});\n"
      "  Revolute j(axis = {0, 0.6, 0.8}, q(start = 1.0), u(start = 0.5));\n";
  const std::string tail =
      "equation\n  connect(world.frame_b, j.frame_a);\n  connect(j.frame_b, link.frame_a);\n"
      "  annotation(experiment(StopTime = 3, Interval = 0.01));\nend P;\n";
  clitest::Write(dir + "/mesh.mech", head + "  MeshBody link(file = \"meshes/link.stl\", density = 2700);\n" + tail);
  clitest::Write(dir + "/box.mech", head + "  Box link(lx = 1, ly = 0.1, lz = 0.05, density = 2700);\n" + tail);
  for (const char* name : {"mesh", "box"}) {
    clitest::Result r = Kanesim(std::string("run ") + name + ".mech --rtol 1e-10 -o " + name + ".csv", dir);
    ASSERT_EQ(r.rc, 0) << r.err;
  }
  std::vector<std::string> hm, hb;
  auto mesh = ReadCsv(dir + "/mesh.csv", &hm), box = ReadCsv(dir + "/box.csv", &hb);
  ASSERT_EQ(hm, hb);
  ASSERT_EQ(mesh.size(), 301u);
  ASSERT_EQ(box.size(), mesh.size());
  // Tolerance: the integrator's (rtol 1e-10 over 3 s of motion) plus the float rounding of
  // the mesh's coordinates (~1e-8 relative in the inertia).
  double worst = 0;
  for (size_t i = 0; i < mesh.size(); ++i)
    for (size_t k = 0; k < mesh[i].size(); ++k) worst = std::max(worst, std::fabs(mesh[i][k] - box[i][k]));
  EXPECT_LT(worst, 1e-6);
  // And the motion is not trivial: the pendulum swings through more than a radian.
  double lo = 1e9, hi = -1e9;
  for (const auto& row : mesh) lo = std::min(lo, row[1]), hi = std::max(hi, row[1]);
  EXPECT_GT(hi - lo, 1.0);
}

}  // namespace
}  // namespace kanesim
