// `kanesim run --speeds diagonal` and `kanesim check --speeds diagonal` (the binary): the
// columns w[i], d[i], T_w[i], the motion against the joint speeds', d against Lesser's
// figure 1 in closed form along the motion, the construction printed, refusals with exit 1.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

struct Csv {
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;
  size_t Col(const std::string& name) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
};

Csv ReadCsv(const std::string& path) {
  Csv c;
  std::ifstream in(path);
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> row;
    while (std::getline(ss, cell, ',')) {
      if (header) c.names.push_back(cell);
      else row.push_back(std::stod(cell));
    }
    if (!header) c.rows.push_back(row);
    header = false;
  }
  return c;
}

const std::string kLesser = kSrc + "/tests/sim/models/lesser_fig1.mech";

TEST(DiagonalSpeedsCli, RunAddsColumnsAndKeepsTheMotion) {
  const std::string dir = Work("diagonal_run");
  Result a = Kanesim("run '" + kLesser + "' --stop-time 2 -o joint.csv", dir);
  Result b = Kanesim("run '" + kLesser + "' --stop-time 2 --speeds diagonal -o diag.csv", dir);
  ASSERT_EQ(a.rc, 0) << a.err;
  ASSERT_EQ(b.rc, 0) << b.err;
  const Csv ja = ReadCsv(dir + "/joint.csv"), db = ReadCsv(dir + "/diag.csv");
  ASSERT_EQ(ja.rows.size(), db.rows.size());
  for (const char* col : {"w[1]", "w[2]", "d[1]", "d[2]", "T_w[1]", "T_w[2]"}) db.Col(col);
  const double l = 0.7, s = 0.4, M1 = 1.3, M2 = 2.1, I = 0.35;
  for (size_t r = 0; r < db.rows.size(); ++r) {
    const std::vector<double>& x = db.rows[r];
    for (const char* q : {"pivot.q", "hinge.q", "pivot.u", "hinge.u"})
      EXPECT_NEAR(x[db.Col(q)], ja.rows[r][ja.Col(q)], 1e-7) << q << " row " << r;  // rtol 1e-10 over 2 s
    // M in the joint speeds from Lesser's (eqs. 77-78) M_L: M_K = S^T M_L S, S = [1 0; 1 1];
    // d1 = M_K(1,1), d2 = det M / d1, w2 = hinge.u, w1 = u1 + (M_K(2,1) / d1) u2.
    const double c = M2 * l * s * std::cos(x[db.Col("hinge.q")]);
    const double A = 4 * l * l * M1 + l * l * M2, C = M2 * s * s + I;
    const double d1 = A + 2 * c + C, m21 = c + C, d2 = (A * C - c * c) / d1;
    EXPECT_NEAR(x[db.Col("d[1]")], d1, 1e-12 * d1);
    EXPECT_NEAR(x[db.Col("d[2]")], d2, 1e-12 * d1);
    const double u1 = x[db.Col("pivot.u")], u2 = x[db.Col("hinge.u")];
    EXPECT_NEAR(x[db.Col("w[2]")], u2, 1e-12 * (1 + std::abs(u2)));
    EXPECT_NEAR(x[db.Col("w[1]")], u1 + m21 / d1 * u2, 1e-12 * (1 + std::abs(u1) + std::abs(u2)));
  }
}

TEST(DiagonalSpeedsCli, CheckPrintsTheConstruction) {
  Result r = Kanesim("check '" + kSrc + "/examples/double_pendulum.mech' --speeds diagonal");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(Has(r.out, "w[1] = shoulder.u + L[2,1] elbow.u\n")) << r.out;
  EXPECT_TRUE(Has(r.out, "w[2] = elbow.u\n")) << r.out;
  Result o = Kanesim("check '" + kSrc + "/examples/double_pendulum.mech' --speeds diagonal --speed-order elbow");
  ASSERT_EQ(o.rc, 0) << o.err;
  EXPECT_TRUE(Has(o.out, "w[1] = elbow.u + L[2,1] shoulder.u\n")) << o.out;
  // A closed loop: over the independent speed of the partition at the start (the crank's).
  Result loop = Kanesim("check '" + kSrc + "/examples/fourbar.mech' --speeds diagonal");
  ASSERT_EQ(loop.rc, 0) << loop.err;
  EXPECT_TRUE(Has(loop.out, "on the constrained basis")) << loop.out;
  EXPECT_TRUE(Has(loop.out, "  w[1] = ")) << loop.out;
  EXPECT_FALSE(Has(loop.out, "  w[2] = ")) << "one degree of freedom: " << loop.out;
}

TEST(DiagonalSpeedsCli, RefusalsExitOne) {
  Result loop = Kanesim("run '" + kSrc + "/examples/fourbar.mech' --speeds diagonal --solver sparse --stop-time 0.1");
  EXPECT_EQ(loop.rc, 1);
  EXPECT_TRUE(Has(loop.err, "multiplier form")) << loop.err;
  Result name = Kanesim("run '" + kSrc + "/examples/double_pendulum.mech' --speeds diagonal --speed-order knee");
  EXPECT_EQ(name.rc, 1);
  EXPECT_TRUE(Has(name.err, "no joint named 'knee'")) << name.err;
}

// annotation(speeds(...)) chooses them in the model; the command line wins; a bad joint name
// is a diagnostic at its place.
TEST(DiagonalSpeedsCli, ModelAnnotationChoosesThem) {
  const std::string dir = Work("diagonal_annotation");
  std::string text = Slurp(kSrc + "/examples/double_pendulum.mech");
  const std::string ex = "annotation(experiment(";
  ASSERT_NE(text.find(ex), std::string::npos);
  Write(dir + "/ann.mech", std::string(text).replace(text.find(ex), ex.size(),
                                                     "annotation(speeds(kind = \"diagonal\", order = {\"elbow\"}), experiment("));
  Result r = Kanesim("run ann.mech --stop-time 0.1 -o ann.csv", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(Has(Slurp(dir + "/ann.csv"), ",w[1],w[2],d[1],d[2],T_w[1],T_w[2]")) << Slurp(dir + "/ann.csv");
  Result c = Kanesim("check ann.mech", dir);
  EXPECT_TRUE(Has(c.out, "w[1] = elbow.u + L[2,1] shoulder.u\n")) << c.out;
  Result j = Kanesim("run ann.mech --stop-time 0.1 --speeds joint -o joint.csv", dir);
  ASSERT_EQ(j.rc, 0) << j.err;
  EXPECT_FALSE(Has(Slurp(dir + "/joint.csv"), "w[1]"));
  Write(dir + "/bad.mech", std::string(text).replace(text.find(ex), ex.size(),
                                                     "annotation(speeds(kind = \"diagonal\", order = {\"knee\"}), experiment("));
  Result b = Kanesim("run bad.mech --stop-time 0.1", dir);
  EXPECT_EQ(b.rc, 1);
  EXPECT_TRUE(Has(b.err, "bad.mech:")) << b.err;
  EXPECT_TRUE(Has(b.err, "no joint named 'knee'")) << b.err;
}

}  // namespace
}  // namespace kanesim::clitest
