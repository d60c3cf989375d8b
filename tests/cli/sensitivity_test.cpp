// Issue 44 §2: `kanesim run --sensitivity p1,p2` writes d(y)/d(p) beside every output y
// (sim/sensitivity.h). Checked against closed forms (the simple pendulum's period, the
// forced oscillator) and against central differences of whole runs at a tight tolerance
// (a double pendulum, a closed loop, the rolling disk).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

// A CSV's columns by name.
std::map<std::string, std::vector<double>> ReadColumns(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> names;
  std::map<std::string, std::vector<double>> cols;
  auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::string cur;
    bool quoted = false;
    for (char c : s) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) out.push_back(cur), cur.clear();
      else cur += c;
    }
    out.push_back(cur);
    return out;
  };
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (names.empty()) {
      names = split(line);
      continue;
    }
    std::vector<std::string> v = split(line);
    for (size_t i = 0; i < names.size() && i < v.size(); ++i) cols[names[i]].push_back(std::stod(v[i]));
  }
  return cols;
}

// A point mass on a massless arm of length l (simple pendulum), 0.01 rad from the bottom.
const char* kSimple = R"(model Simple
  parameter Real l(unit = "m") = 1.5;
  World world(g = {0, -9.81, 0});
  Revolute pivot(axis = {0, 0, 1}, q(start = -pi / 2 + 0.01), u(start = 0));
  FixedTranslation arm(r = {l, 0, 0});
  Body bob(m = 1, I = identity(3) * 1e-9);
equation
  connect(world.frame_b, pivot.frame_a);
  connect(pivot.frame_b, arm.frame_a);
  connect(arm.frame_b, bob.frame_a);
end Simple;
)";

// T = sqrt(l / g) F(amplitude), so dT/dl = T / (2 l) at any amplitude, and pi / sqrt(g l) for a
// small one. The first crossing of the bottom is at T / 4; there dt/dl = -(dq/dl) / u.
TEST(Sensitivity, SimplePendulumPeriodByLength) {
  const std::string d = Work("sens_simple");
  Write(d + "/m.mech", kSimple);
  Result r = Kanesim("run m.mech --stop-time 0.7 --interval 1e-4 --rtol 1e-10 --sensitivity l -o out.csv", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  auto c = ReadColumns(d + "/out.csv");
  const auto &t = c["time"], &q = c["pivot.q"], &u = c["pivot.u"], &dq = c["d(pivot.q)/d(l)"];
  ASSERT_FALSE(dq.empty());
  const double l = 1.5, g = 9.81, bottom = -M_PI / 2;
  size_t i = 1;
  while (i < q.size() && (q[i - 1] - bottom) * (q[i] - bottom) > 0) ++i;
  ASSERT_LT(i, q.size());
  const double w = (bottom - q[i - 1]) / (q[i] - q[i - 1]);  // linear interpolation to the crossing
  auto at = [&](const std::vector<double>& x) { return x[i - 1] + w * (x[i] - x[i - 1]); };
  const double quarter = at(t), dtdl = -at(dq) / at(u);
  EXPECT_NEAR(4 * dtdl, 4 * quarter / (2 * l), 1e-7);     // T / (2 l), T from the same run
  EXPECT_NEAR(4 * dtdl, M_PI / std::sqrt(g * l), 2e-5);   // small angle: 1.6e-5 relative for 0.01 rad
}

// The forced, damped oscillator of examples/spring_mass.mech: x(t) in closed form, its
// derivative by k by a central difference of the closed form (step 1e-4: 1e-11 off).
double SpringMassX(double t, double k) {
  const double m = 2, c = 1, F0 = 1, w = 4, x0 = 0.1, v0 = 0;
  const double D = (k - m * w * w) * (k - m * w * w) + (c * w) * (c * w);
  const double A = F0 * (k - m * w * w) / D, B = F0 * c * w / D;
  const double wn = std::sqrt(k / m), z = c / (2 * std::sqrt(k * m)), wd = wn * std::sqrt(1 - z * z), s = z * wn;
  const double C1 = x0 - A, C2 = (v0 - B * w + s * C1) / wd;
  return std::exp(-s * t) * (C1 * std::cos(wd * t) + C2 * std::sin(wd * t)) + A * std::cos(w * t) + B * std::sin(w * t);
}

TEST(Sensitivity, SpringMassByStiffnessEqualsTheClosedForm) {
  const std::string d = Work("sens_spring");
  for (const char* integrator : {"dop853", "cvode-bdf", "ida"}) {
    SCOPED_TRACE(integrator);
    Result r = Kanesim("run " + kSrc + "/examples/spring_mass.mech --rtol 1e-10 --integrator " + integrator +
                           " --sensitivity k,mass -o out.csv",
                       d);
    ASSERT_EQ(r.rc, 0) << r.err;
    auto c = ReadColumns(d + "/out.csv");
    const auto &t = c["time"], &dx = c["d(slider.q)/d(k)"];
    ASSERT_EQ(dx.size(), t.size());
    ASSERT_FALSE(c["d(slider.u)/d(mass)"].empty());
    double err = 0.0, scale = 0.0;
    for (size_t i = 0; i < t.size(); ++i) {
      const double h = 1e-4, want = (SpringMassX(t[i], 50 + h) - SpringMassX(t[i], 50 - h)) / (2 * h);
      err = std::max(err, std::fabs(dx[i] - want));
      scale = std::max(scale, std::fabs(want));
    }
    EXPECT_LT(err, 1e-6 * scale) << "scale " << scale;
  }
}

// d(y)/d(p) at every row against (y(p + h) - y(p - h)) / (2 h) of two whole runs at rtol
// 1e-12; `bound` relative to the largest derivative.
void ExpectEqualsDifferences(const std::string& name, const std::string& model, const std::string& extra,
                             const std::string& p, double value, double h, const std::vector<std::string>& ys,
                             double bound) {
  const std::string d = Work("sens_" + name);
  Result r = Kanesim("run " + model + " " + extra + " --rtol 1e-11 --sensitivity " + p + " -o s.csv", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  for (double sign : {1.0, -1.0}) {
    std::ostringstream set;
    set.precision(17);
    set << p << "=" << value + sign * h;
    Result e = Kanesim("run " + model + " " + extra + " --rtol 1e-12 --set " + set.str() + " -o " +
                           (sign > 0 ? "plus.csv" : "minus.csv"),
                       d);
    ASSERT_EQ(e.rc, 0) << e.err;
  }
  auto s = ReadColumns(d + "/s.csv"), a = ReadColumns(d + "/plus.csv"), b = ReadColumns(d + "/minus.csv");
  for (const std::string& y : ys) {
    SCOPED_TRACE(y);
    const auto& ds = s["d(" + y + ")/d(" + p + ")"];
    ASSERT_EQ(ds.size(), a[y].size());
    double err = 0.0, scale = 0.0;
    for (size_t i = 0; i < ds.size(); ++i) {
      const double want = (a[y][i] - b[y][i]) / (2 * h);
      err = std::max(err, std::fabs(ds[i] - want));
      scale = std::max(scale, std::fabs(want));
    }
    EXPECT_GT(scale, 0.0);
    EXPECT_LT(err, bound * scale) << "scale " << scale << " err " << err;
  }
}

TEST(Sensitivity, DoublePendulumEqualsDifferencesOfRuns) {
  ExpectEqualsDifferences("double", kSrc + "/examples/double_pendulum.mech", "--stop-time 2", "rod1.L", 1.0, 1e-5,
                          {"shoulder.q", "elbow.u"}, 1e-5);
}

TEST(Sensitivity, ClosedLoopEqualsDifferencesOfRuns) {
  ExpectEqualsDifferences("fourbar", kSrc + "/examples/fourbar.mech", "--stop-time 2", "b", 0.6, 1e-5,
                          {"crank_pivot.q", "rocker_pivot.q", "rocker_pivot.u"}, 1e-5);
}

TEST(Sensitivity, RollingDiskEqualsDifferencesOfRuns) {
  ExpectEqualsDifferences("disk", kSrc + "/examples/rolling_disk.mech", "--stop-time 2 --set lean_rate=0.1", "a",
                          0.3, 1e-5, {"lean", "free.q[1]", "free.u[4]"}, 1e-5);
}

// Names that have no derivative are refused before anything runs (exit 1).
TEST(Sensitivity, RefusesWhatIsNotARealParameter) {
  const std::string d = Work("sens_refuse");
  Result r = Kanesim("run " + kSrc + "/examples/double_pendulum.mech --sensitivity nosuch -o out.csv", d);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.err, "--sensitivity nosuch: no parameter")) << r.err;
}

}  // namespace
}  // namespace kanesim::clitest
