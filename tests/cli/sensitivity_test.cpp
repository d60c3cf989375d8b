// Issue 44 §2: `kanesim run --sensitivity p1,p2` writes d(y)/d(p) beside every output y
// (sim/sensitivity.h). Checked against closed forms (the simple pendulum's period, the
// forced oscillator) and against central differences of whole runs at a tight tolerance
// (a double pendulum, a closed loop, the rolling disk).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_util.h"
#include "tests/support/csv_table.h"

namespace kanesim::clitest {
namespace {

// A CSV's columns by name (tests/support/csv_table.h).
std::map<std::string, std::vector<double>> ReadColumns(const std::string& path) {
  const test::CsvTable t = test::ReadCsvTable(path);
  std::map<std::string, std::vector<double>> cols;
  for (const std::vector<double>& row : t.rows)
    for (size_t i = 0; i < t.names.size() && i < row.size(); ++i) cols[t.names[i]].push_back(row[i]);
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

// A sensitivity as a sweep metric (`--metric final:d(slider.q)/d(k)`): per scenario, the
// closed form's derivative at the stop time.
TEST(Sensitivity, SweepMetricEqualsTheClosedForm) {
  const std::string d = Work("sens_sweep");
  Result r = Kanesim("sweep " + kSrc +
                         "/examples/spring_mass.mech --grid k=40,50,60 --stop-time 2 --rtol 1e-10 --no-progress "
                         "--metric 'final:d(slider.q)/d(k)' --metric final:slider.q -o out",
                     d);
  ASSERT_EQ(r.rc, 0) << r.err;
  const test::CsvTable t = test::ReadCsvTable(d + "/out/summary.csv");
  const int k = t.Column("k"), dx = t.Column("final:d(slider.q)/d(k)"), x = t.Column("final:slider.q");
  ASSERT_GE(k, 0);
  ASSERT_GE(dx, 0);
  ASSERT_GE(x, 0);
  ASSERT_EQ(t.rows.size(), 3u);
  for (const std::vector<double>& row : t.rows) {
    const double kk = row[static_cast<size_t>(k)], h = 1e-4;
    const double want = (SpringMassX(2.0, kk + h) - SpringMassX(2.0, kk - h)) / (2 * h);
    EXPECT_NEAR(row[static_cast<size_t>(x)], SpringMassX(2.0, kk), 1e-8) << "k = " << kk;
    EXPECT_NEAR(row[static_cast<size_t>(dx)], want, 1e-6 * std::fabs(want)) << "k = " << kk;
  }
  Result bad = Kanesim("sweep " + kSrc + "/examples/spring_mass.mech --grid k=40,50 --no-progress "
                       "--metric 'final:d(slider.q)/d(nosuch)' -o bad", d);
  EXPECT_EQ(bad.rc, 1);
  EXPECT_TRUE(Has(bad.err, "not a Real, non-structural parameter")) << bad.err;
}

// `--stats` estimates the differences' error (|D(h) - D(2h)| / 3 + eps |f| / h). The
// oscillator's acceleration is f = (F - k x - c v) / m: df/dm = -f / m and d3f/dm3 = -6 f / m^3,
// so D(h)'s truncation error is (h / m)^2 of |df/dm| and the round-off eps m / h, both
// eps^(2/3) = 3.7e-11 with h = cbrt(eps) m: about 7e-11 in all. f is linear in k: no
// truncation, round-off only.
TEST(Sensitivity, StatsEstimateTheDifferencesErrorAsTheAnalysisPredicts) {
  const std::string d = Work("sens_stats");
  Result r = Kanesim("run " + kSrc + "/examples/spring_mass.mech --stop-time 2 --sensitivity mass,k --stats -o out.csv", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  auto ratio = [&](const std::string& param, const std::string& what) {
    const size_t line = r.err.find("  " + param + " ");
    if (line == std::string::npos) return -1.0;
    const size_t at = r.err.find(what + " ", line);
    double error = -1, scale = -1;
    std::sscanf(r.err.c_str() + at + what.size(), " %lf / %lf", &error, &scale);
    return scale > 0 ? error / scale : -1.0;
  };
  const double mass = ratio("mass", "df/dp"), k = ratio("k", "df/dp"), s = ratio("mass", "(df/dy) s");
  EXPECT_GT(mass, 4e-11) << r.err;
  EXPECT_LT(mass, 1.5e-10) << r.err;
  EXPECT_GE(k, 0.0) << r.err;
  EXPECT_LT(k, 1e-9) << r.err;
  EXPECT_GE(s, 0.0) << r.err;
  EXPECT_LT(s, 1e-8) << r.err;
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

// Start values as parameters (`--sensitivity j.q.start`): s(t0) is a unit vector. At a small
// amplitude the pendulum is linear, q - q_b = (q0 - q_b) cos(w t) + u0 sin(w t) / w, so
// dq/dq0 = cos(w t), dq/du0 = sin(w t) / w, du/dq0 = -w sin(w t); 0.01 rad off the bottom the
// frequency's shift (a^2 / 16 relative) leaves them 1e-5 off over a second.
TEST(Sensitivity, SimplePendulumByStartValuesEqualsTheLinearClosedForm) {
  const std::string d = Work("sens_start");
  Write(d + "/m.mech", kSimple);
  Result r = Kanesim("run m.mech --stop-time 1.5 --rtol 1e-10 --sensitivity pivot.q.start,pivot.u.start -o out.csv", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  auto c = ReadColumns(d + "/out.csv");
  const auto &t = c["time"], &dq0 = c["d(pivot.q)/d(pivot.q.start)"], &du0 = c["d(pivot.q)/d(pivot.u.start)"],
             &dudq0 = c["d(pivot.u)/d(pivot.q.start)"];
  ASSERT_EQ(dq0.size(), t.size());
  ASSERT_EQ(du0.size(), t.size());
  ASSERT_EQ(dudq0.size(), t.size());
  const double w = std::sqrt(9.81 / 1.5);
  EXPECT_NEAR(dq0[0], 1.0, 1e-10);  // the starts at q0 +/- delta, compiled again: round-off
  EXPECT_NEAR(du0[0], 0.0, 1e-10);
  double err = 0.0;
  for (size_t i = 0; i < t.size(); ++i) {
    err = std::max(err, std::fabs(dq0[i] - std::cos(w * t[i])));
    err = std::max(err, std::fabs(du0[i] - std::sin(w * t[i]) / w));
    err = std::max(err, std::fabs(dudq0[i] + w * std::sin(w * t[i])) / w);
  }
  EXPECT_LT(err, 1e-4);
  EXPECT_GT(err, 1e-7);  // the closed form is the linear one: the run sees the amplitude
}

TEST(Sensitivity, StartValueEqualsDifferencesOfRuns) {
  const std::string d = Work("sens_start_runs");
  Write(d + "/m.mech", kSimple);
  ExpectEqualsDifferences("start_simple", d + "/m.mech", "--stop-time 1.5", "pivot.q.start", -M_PI / 2 + 0.01, 1e-5,
                          {"pivot.q", "pivot.u"}, 1e-6);
  ExpectEqualsDifferences("start_double", kSrc + "/examples/double_pendulum.mech", "--stop-time 2", "elbow.u.start",
                          0.0, 1e-5, {"shoulder.q", "elbow.q", "elbow.u"}, 1e-5);
}

// A closed loop: the start moves the dependent coordinates and speeds too (the assembly,
// compiled again at q0 +/- delta); against runs with --set at q0 +/- h.
TEST(Sensitivity, ClosedLoopStartValuesEqualDifferencesOfRuns) {
  ExpectEqualsDifferences("fourbar_q0", kSrc + "/examples/fourbar.mech", "--stop-time 1", "crank_pivot.q.start", 0.3,
                          1e-5, {"crank_pivot.q", "rocker_pivot.q", "rocker_pivot.u"}, 1e-5);
  ExpectEqualsDifferences("fourbar_u0", kSrc + "/examples/fourbar.mech", "--stop-time 1", "crank_pivot.u.start", 6.0,
                          1e-5, {"crank_pivot.q", "rocker_pivot.q", "rocker_pivot.u"}, 1e-5);
}

// Names that have no derivative are refused before anything runs (exit 1).
TEST(Sensitivity, RefusesWhatIsNotARealParameter) {
  const std::string d = Work("sens_refuse");
  Result r = Kanesim("run " + kSrc + "/examples/double_pendulum.mech --sensitivity nosuch -o out.csv", d);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.err, "--sensitivity nosuch: no parameter")) << r.err;
  for (auto [name, why] : {std::pair{"nosuch.q.start", "no joint 'nosuch'"}, {"shoulder.q[2].start", "has 1 coordinate"},
                           {"coupler_rocker.q.start", "no coordinates of its own"}}) {
    const std::string model = std::string(name).rfind("coupler", 0) == 0 ? "fourbar" : "double_pendulum";
    Result s = Kanesim("run " + kSrc + "/examples/" + model + ".mech --sensitivity " + name + " -o out.csv", d);
    EXPECT_EQ(s.rc, 1) << name;
    EXPECT_TRUE(Has(s.err, why)) << s.err;
  }
}

}  // namespace
}  // namespace kanesim::clitest
