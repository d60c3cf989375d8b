// The standard library: every class elaborates on its own, and the shapes' mass
// properties agree with a numerical quadrature of the density over the solid (an
// independent computation, not the closed forms the library uses).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "lang/elaborate.h"
#include "stdlib/stdlib.h"

namespace kanesim::lang {
namespace {

struct Elab {
  Program program;
  flat::Mechanism mech;
  std::string errors;
  bool ok = false;
};

std::unique_ptr<Elab> ElaborateText(const std::string& text) {
  auto e = std::make_unique<Elab>();
  Diagnostics diags(&e->program.sources);
  bool loaded = LoadProgramFromText("test.mech", text, stdlib::Files(), &e->program, diags);
  e->ok = loaded && Elaborate(e->program, {}, &e->mech, diags);
  for (const auto& d : diags.All())
    if (d.severity == Severity::Error) e->errors += diags.Render(d);
  return e;
}

double Param(const flat::Mechanism& m, const std::string& name) {
  int i = m.FindParam(name);
  EXPECT_GE(i, 0) << name;
  return i >= 0 ? flat::EvaluateParams(m)[static_cast<size_t>(i)] : NAN;
}

// If this fails, a standard-library class does not even elaborate: users get errors
// from code they did not write.
TEST(Stdlib, EveryModelElaboratesOnItsOwn) {
  Program program;
  Diagnostics diags(&program.sources);
  ASSERT_TRUE(LoadProgramFromText("empty.mech", "", stdlib::Files(), &program, diags)) << diags.RenderAll();
  std::vector<std::string> models = StdlibModels(program);
  ASSERT_GE(models.size(), 25u);
  for (const auto& m : models) {
    if (m == "Kanesim.World") continue;
    if (m == "Kanesim.MeshBody") continue;  // needs a mesh file: tests/scene/mesh_body_test.cpp
    if (m == "Kanesim.JointCoupling") continue;  // needs two joints' drive flanges: tests/import/mimic_test.cpp
    auto e = ElaborateText("model T\n  World world;\n  " + m + " x;\nend T;\n");
    EXPECT_TRUE(e->ok) << m << "\n" << e->errors;
  }
}

// Midpoint-rule quadrature of mass, centre of mass and central inertia over a solid
// given by an indicator function inside the box [lo, hi].
struct MassProps {
  double m = 0, c[3] = {0, 0, 0}, I[3] = {0, 0, 0};
};
MassProps Quadrature(const std::function<bool(double, double, double)>& inside, const double lo[3],
                     const double hi[3], double density, int n) {
  MassProps p;
  double h[3];
  for (int k = 0; k < 3; ++k) h[k] = (hi[k] - lo[k]) / n;
  double dv = h[0] * h[1] * h[2];
  double s1[3] = {0, 0, 0}, s2[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        double x = lo[0] + (i + 0.5) * h[0], y = lo[1] + (j + 0.5) * h[1], z = lo[2] + (k + 0.5) * h[2];
        if (!inside(x, y, z)) continue;
        double dm = density * dv;
        p.m += dm;
        double r[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) {
          s1[a] += dm * r[a];
          s2[a] += dm * r[a] * r[a];
        }
      }
  for (int a = 0; a < 3; ++a) p.c[a] = s1[a] / p.m;
  double sec[3];
  for (int a = 0; a < 3; ++a) sec[a] = s2[a] - p.m * p.c[a] * p.c[a];  // central second moments
  p.I[0] = sec[1] + sec[2];
  p.I[1] = sec[0] + sec[2];
  p.I[2] = sec[0] + sec[1];
  return p;
}

void ExpectMassProps(const flat::Mechanism& m, const std::string& body, const MassProps& q, double rel) {
  EXPECT_NEAR(Param(m, body + ".m"), q.m, rel * q.m);
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR(Param(m, body + ".r_CM[" + std::to_string(a + 1) + "]"), q.c[a], rel * 1.0) << a;
  for (int a = 0; a < 3; ++a) {
    std::string idx = std::to_string(a + 1);
    EXPECT_NEAR(Param(m, body + ".I[" + idx + "," + idx + "]"), q.I[a], rel * (q.I[0] + q.I[1] + q.I[2])) << a;
  }
}

// Quadrature on 60^3 cells: the midpoint rule's error is O(h^2) ~ 1e-3 for the curved
// solids (their boundary cells are cut), below 1e-3 for the box.
constexpr int kCells = 60;

TEST(StdlibShapes, BoxMassPropertiesMatchQuadrature) {
  auto e = ElaborateText("model T World world; Box b(lx = 0.6, ly = 0.2, lz = 0.1, density = 2700); end T;");
  ASSERT_TRUE(e->ok) << e->errors;
  double lo[3] = {0, -0.1, -0.05}, hi[3] = {0.6, 0.1, 0.05};
  auto q = Quadrature([](double, double, double) { return true; }, lo, hi, 2700, kCells);
  ExpectMassProps(e->mech, "b.body", q, 1e-3);
}

TEST(StdlibShapes, CylinderMassPropertiesMatchQuadrature) {
  auto e = ElaborateText("model T World world; Cylinder c(length = 0.5, radius = 0.1, density = 1000); end T;");
  ASSERT_TRUE(e->ok) << e->errors;
  double lo[3] = {0, -0.1, -0.1}, hi[3] = {0.5, 0.1, 0.1};
  auto q = Quadrature([](double, double y, double z) { return y * y + z * z <= 0.01; }, lo, hi, 1000, kCells);
  ExpectMassProps(e->mech, "c.body", q, 5e-3);
}

TEST(StdlibShapes, SphereMassPropertiesMatchQuadrature) {
  auto e = ElaborateText("model T World world; Sphere s(radius = 0.2, density = 500); end T;");
  ASSERT_TRUE(e->ok) << e->errors;
  double lo[3] = {-0.2, -0.2, -0.2}, hi[3] = {0.2, 0.2, 0.2};
  auto q = Quadrature([](double x, double y, double z) { return x * x + y * y + z * z <= 0.04; }, lo, hi, 500,
                      kCells);
  ExpectMassProps(e->mech, "s.body", q, 5e-3);
}

// A thin rod is the limit of a cylinder of vanishing radius with the same mass.
TEST(StdlibShapes, RodIsTheThinLimitOfACylinder) {
  auto e = ElaborateText(
      "model T World world; Rod r(L = 2, m = 3); Cylinder c(length = 2, radius = 1e-6, m = 3); end T;");
  ASSERT_TRUE(e->ok) << e->errors;
  for (const char* k : {"m", "r_CM[1]", "I[2,2]", "I[3,3]"})
    EXPECT_NEAR(Param(e->mech, std::string("r.body.") + k), Param(e->mech, std::string("c.body.") + k), 1e-9) << k;
}

// Mass given explicitly overrides the density binding (Modelica's modifier semantics).
TEST(StdlibShapes, ExplicitMassOverridesDensity) {
  auto e = ElaborateText("model T World world; Box b(lx = 1, ly = 1, lz = 1, m = 5); end T;");
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(Param(e->mech, "b.body.m"), 5.0);
  EXPECT_DOUBLE_EQ(Param(e->mech, "b.body.I[1,1]"), 5.0 * 2 / 12);
}

// FixedRotation's matrix must be a proper rotation turning frame_a's x axis about z.
TEST(StdlibParts, FixedRotationIsAProperRotation) {
  auto e = ElaborateText("model T World world; FixedRotation f(n = {0, 0, 2}, angle = 0.7); end T;");
  ASSERT_TRUE(e->ok) << e->errors;
  double R[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      R[i][j] = Param(e->mech, "f.R[" + std::to_string(i + 1) + "," + std::to_string(j + 1) + "]");
  EXPECT_NEAR(R[0][0], std::cos(0.7), 1e-15);
  EXPECT_NEAR(R[1][0], std::sin(0.7), 1e-15);  // b's x axis resolved in a
  EXPECT_NEAR(R[2][2], 1.0, 1e-15);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double dot = 0;
      for (int k = 0; k < 3; ++k) dot += R[k][i] * R[k][j];
      EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 1e-15);
    }
}

}  // namespace
}  // namespace kanesim::lang
