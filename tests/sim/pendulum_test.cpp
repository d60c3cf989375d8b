// End to end through the engine: a simple pendulum built as a flat mechanism, compiled,
// and simulated with sim::Simulate. If these fail, either Kane's equations of a single
// revolute body are wrong, or the integrators do not reach their tolerances on it, or
// the output/failure plumbing from the engine to the CSV is broken.
//
// The pendulum: revolute joint about z at the world origin, a thin rod of mass m and
// length L along body x, mass centre at d = L/2, central inertia I_zz = m L^2 / 12,
// gravity -g y. With the angle q from the x axis, the centre of mass is at
// d (cos q, sin q, 0); the stable equilibrium is q = -pi/2. Then (independent derivation,
// Lagrange):
//   I_O u' = -m g d cos q,  I_O = m L^2/12 + m d^2 = m L^2 / 3                      (1)
//   E = 1/2 I_O u^2 + m g d sin q                                                    (2)
// and for amplitude a about q = -pi/2 the period is (e.g. Landau & Lifshitz, §11)
//   T = 4 sqrt(I_O / (m g d)) K(k),  k = sin(a / 2),                                 (3)
// where K is the complete elliptic integral of the first kind,
//   K(k) = pi / (2 AGM(1, sqrt(1 - k^2)))                                            (4)
// (AGM = arithmetic-geometric mean).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "compiler/compiler.h"
#include "flat/mechanism.h"
#include "sim/csv.h"
#include "sim/simulate.h"

namespace kanesim::sim {
namespace {

constexpr double kMass = 1.0, kLength = 1.0, kG = 9.81;
constexpr double kD = kLength / 2;
constexpr double kIO = kMass * kLength * kLength / 3.0;
constexpr double kAmplitude = 1.5;  // rad from the hanging position

// The flat mechanism; `torque` (if not kNoExpr-producing) drives the joint.
flat::Mechanism Pendulum(double amplitude, bool nan_torque_after_half_second = false) {
  flat::Mechanism m;
  m.model_name = "Pendulum";
  flat::ExprPool& e = m.exprs;
  auto c = [&e](double v) { return e.Constant(v); };
  m.frames.push_back({"world.frame_b", {"world.frame_b", "rev.frame_a"}, {}});
  m.frames.push_back({"rod.frame_a", {"rod.frame_a", "rev.frame_b"}, {}});
  flat::World w;
  w.frame = 0;
  w.gravity = {c(0.0), c(-kG), c(0.0)};
  m.worlds.push_back(w);

  flat::Joint j;
  j.name = "rev";
  j.type = flat::JointType::Revolute;
  j.frame_a = 0;
  j.frame_b = 1;
  j.axis = {c(0.0), c(0.0), c(1.0)};
  j.axis2 = {c(1.0), c(0.0), c(0.0)};
  j.q_start = {c(-M_PI / 2 + amplitude)};
  j.u_start = {c(0.0)};
  j.q_start_fixed = {false};
  j.tau = {flat::kNoExpr};
  j.prescribed = {flat::kNoExpr};
  if (nan_torque_after_half_second)  // sqrt(0.5 - time): NaN once time > 0.5
    j.tau[0] = e.Unary(flat::Op::Sqrt, e.Binary(flat::Op::Sub, c(0.5), e.Time()));
  m.joints.push_back(j);

  flat::Body b;
  b.name = "rod";
  b.frame = 1;
  b.mass = c(kMass);
  b.r_cm = {c(kD), c(0.0), c(0.0)};
  double i_t = kMass * kLength * kLength / 12.0;
  b.inertia = {c(0.0), c(0.0), c(0.0), c(0.0), c(i_t), c(0.0), c(0.0), c(0.0), c(i_t)};
  m.bodies.push_back(b);
  m.experiment.stop_time = 1.0;
  return m;
}

std::shared_ptr<const rt::Program> CompilePendulum(const flat::Mechanism& m) {
  rt::CompileResult r = rt::Compile(m, rt::CompileOptions{});
  for (const rt::CompileMessage& msg : r.errors) ADD_FAILURE() << flat::DiagCodeString(msg.code) << ": " << msg.message;
  return r.program;
}

double Agm(double a, double b) {
  while (std::abs(a - b) > 1e-16 * a) {
    double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return a;
}

double ExactPeriod(double amplitude) {  // Eqs. (3), (4)
  double k = std::sin(amplitude / 2);
  double K = M_PI / (2 * Agm(1.0, std::sqrt(1 - k * k)));
  return 4 * std::sqrt(kIO / (kMass * kG * kD)) * K;
}

double Acceleration(double q) { return -kMass * kG * kD * std::cos(q) / kIO; }  // Eq. (1)
double Energy(double q, double u) { return 0.5 * kIO * u * u + kMass * kG * kD * std::sin(q); }  // Eq. (2)

// Column of `name` in the sink.
size_t Column(const MemorySink& s, const std::string& name) {
  for (size_t i = 0; i < s.names.size(); ++i)
    if (s.names[i] == name) return i;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// Times where u changes sign, each located on the cubic Hermite interpolant of u between
// two rows (u' from Eq. (1)) by bisection: O(h^4) accurate in the row spacing h.
std::vector<double> ZeroCrossingsOfU(const MemorySink& s) {
  size_t iq = Column(s, "rev.q"), iu = Column(s, "rev.u");
  std::vector<double> out;
  for (size_t i = 1; i + 1 < s.times.size(); ++i) {
    double t0 = s.times[i], t1 = s.times[i + 1], h = t1 - t0;
    double u0 = s.rows[i][iu], u1 = s.rows[i + 1][iu];
    if (!(u0 * u1 < 0)) continue;
    double m0 = Acceleration(s.rows[i][iq]) * h, m1 = Acceleration(s.rows[i + 1][iq]) * h;
    auto hermite = [&](double x) {
      double x2 = x * x, x3 = x2 * x;
      return (2 * x3 - 3 * x2 + 1) * u0 + (x3 - 2 * x2 + x) * m0 + (-2 * x3 + 3 * x2) * u1 + (x3 - x2) * m1;
    };
    double lo = 0, hi = 1;
    for (int it = 0; it < 80; ++it) {
      double mid = 0.5 * (lo + hi);
      if ((hermite(mid) < 0) == (u0 < 0))
        lo = mid;
      else
        hi = mid;
    }
    out.push_back(t0 + 0.5 * (lo + hi) * h);
  }
  return out;
}

MemorySink RunPendulum(rt::Integrator kind, double rtol, double stop, double interval) {
  flat::Mechanism m = Pendulum(kAmplitude);
  auto program = CompilePendulum(m);
  MemorySink sink;
  if (!program) return sink;
  SimOptions opt;
  opt.stop_time = stop;
  opt.interval = interval;
  opt.rtol = opt.atol = rtol;
  opt.integrator = kind;
  opt.signals = {"rev.q", "rev.u"};
  SimResult r = Simulate(*program, opt, sink);
  EXPECT_EQ(r.status, SimResult::Status::kOk) << r.message;
  return sink;
}

struct Case {
  rt::Integrator kind;
  const char* name;
};
const Case kCases[] = {{rt::Integrator::IDA, "IDA"},
                       {rt::Integrator::CvodeAdams, "CVODE-Adams"},
                       {rt::Integrator::CvodeBdf, "CVODE-BDF"},
                       {rt::Integrator::ArkodeErk, "ARKODE-ERK"},
                       {rt::Integrator::Dop853, "DOP853"}};

// Period of a large-amplitude swing (1.5 rad) against the elliptic-integral formula.
TEST(SimPendulum, LargeAmplitudePeriodMatchesEllipticIntegral) {
  const double T = ExactPeriod(kAmplitude);
  for (const Case& c : kCases) {
    MemorySink s = RunPendulum(c.kind, 1e-12, 3.2 * T, 1e-3);
    ASSERT_FALSE(s.times.empty()) << c.name;
    std::vector<double> zc = ZeroCrossingsOfU(s);
    ASSERT_EQ(zc.size(), 6u) << c.name;  // u = 0 at k T / 2, k = 1..6 (t = 0 excluded)
    // u(0) = 0 exactly, so the k-th crossing is at k T / 2.
    double T_measured = 2 * zc.back() / static_cast<double>(zc.size());
    double rel = std::abs(T_measured - T) / T;
    std::printf("[ pendulum ] %-12s period %.15f exact %.15f rel.err %.2e\n", c.name, T_measured, T, rel);
    constexpr double kPeriodTolerance = 1e-9;  // issue #3 requirement
    EXPECT_LT(rel, kPeriodTolerance) << c.name;
  }
}

// Energy (2) over 100 periods, relative to the largest kinetic energy m g d (1 - cos a).
// None of these methods conserves energy: the error grows with the number of steps, so
// the bound is a multiple of rtol per period. BDF (IDA, CVODE-BDF) damps oscillations,
// so E decays about linearly; measured at rtol = atol = 1e-8 over 100 periods:
//   IDA 1.6e-5 (16 rtol/period), CVODE-BDF 2.5e-5 (25), CVODE-Adams 2.4e-6 (2.4),
//   ARKODE Verner 6(5) 1.7e-6 (1.7; Fehlberg 8(7) 1.7e-7 before 2026-11-30), DOP853 4.0e-7 (0.40).
// (BDF's drift is not proportional to rtol: 3.1, 16, 21 rtol/period for IDA at
// rtol 1e-6, 1e-8, 1e-10.) If this fails, the integrators or Kane's equations gained
// or lost energy beyond what the method's own damping explains.
TEST(SimPendulum, EnergyDriftOver100PeriodsIsBoundedByRtolPerPeriod) {
  const double T = ExactPeriod(kAmplitude);
  const double scale = kMass * kG * kD * (1 - std::cos(kAmplitude));
  constexpr double kRtol = 1e-8;
  constexpr double kPeriods = 100;
  constexpr double kBdfPerPeriod = 50;         // numerical damping of BDF, 2-3x margin
  constexpr double kNonDampingPerPeriod = 5;   // Adams, explicit RK
  for (const Case& c : kCases) {
    MemorySink s = RunPendulum(c.kind, kRtol, kPeriods * T, T / 50);
    ASSERT_FALSE(s.times.empty()) << c.name;
    EXPECT_EQ(s.times.back(), kPeriods * T);
    size_t iq = Column(s, "rev.q"), iu = Column(s, "rev.u");
    double e0 = Energy(s.rows[0][iq], s.rows[0][iu]), drift = 0;
    for (const auto& row : s.rows) drift = std::max(drift, std::abs(Energy(row[iq], row[iu]) - e0) / scale);
    std::printf("[ pendulum ] %-12s rtol %.0e  energy drift over 100 periods %.2e (= %.1f rtol)\n", c.name, kRtol,
                drift, drift / kRtol);
    bool damping = c.kind == rt::Integrator::IDA || c.kind == rt::Integrator::CvodeBdf;
    double per_period = damping ? kBdfPerPeriod : kNonDampingPerPeriod;
    EXPECT_LT(drift, per_period * kPeriods * kRtol) << c.name;
  }
}

// The automatic choice for a conservative scene keeps energy: the compiler picks DOP853
// (smooth, non-stiff), and the relative energy drift over 100 periods is then a small
// multiple of rtol for the whole run, not per period (measured at rtol 1e-8: DOP853 40 rtol,
// ARKODE 17 rtol with Fehlberg 8(7), 172 with Verner 6(5); BDF's 1600-2500 rtol is the
// reason the compiler avoids it here).
TEST(SimPendulum, AutomaticChoiceKeepsEnergyOver100PeriodsWithinASmallMultipleOfRtol) {
  const double T = ExactPeriod(kAmplitude);
  const double scale = kMass * kG * kD * (1 - std::cos(kAmplitude));
  constexpr double kRtol = 1e-8;
  constexpr double kMultiple = 80;  // measured 40 (DOP853); 5 per period would be 500
  flat::Mechanism m = Pendulum(kAmplitude);
  // The choice depends on the model only (not on the horizon or the tolerance).
  rt::CompileResult cr = rt::Compile(m, rt::CompileOptions{});
  ASSERT_TRUE(cr.program);
  EXPECT_EQ(rt::Summarize(*cr.program).integrator, rt::Integrator::Dop853) << rt::Summarize(*cr.program).integrator_reason;

  SimOptions opt;
  opt.stop_time = 100 * T;
  opt.interval = T / 50;
  opt.rtol = opt.atol = kRtol;
  opt.signals = {"rev.q", "rev.u"};
  MemorySink s;
  SimResult r = Simulate(*cr.program, opt, s);
  ASSERT_EQ(r.status, SimResult::Status::kOk) << r.message;
  double e0 = Energy(s.rows[0][0], s.rows[0][1]), drift = 0;
  for (const auto& row : s.rows) drift = std::max(drift, std::abs(Energy(row[0], row[1]) - e0) / scale);
  std::printf("[ pendulum ] automatic (%s) energy drift over 100 periods %.2e (= %.1f rtol)\n",
              rt::Summarize(*cr.program).integrator == rt::Integrator::Dop853 ? "DOP853" : "other", drift,
              drift / kRtol);
  EXPECT_LT(drift, kMultiple * kRtol);
}

// The engine's energy signals agree with Eq. (2) (only when the engine offers them).
TEST(SimPendulum, EngineEnergySignalsMatchClosedForm) {
  flat::Mechanism m = Pendulum(kAmplitude);
  auto program = CompilePendulum(m);
  ASSERT_TRUE(program);
  std::vector<std::string> avail = rt::AvailableSignals(*program);
  auto has = [&avail](const char* n) { return std::find(avail.begin(), avail.end(), n) != avail.end(); };
  if (!has("kinetic_energy") || !has("potential_energy")) GTEST_SKIP() << "engine has no energy signals";
  SimOptions opt;
  opt.stop_time = 2.0;
  opt.rtol = opt.atol = 1e-10;
  opt.signals = {"rev.q", "rev.u", "kinetic_energy", "potential_energy"};
  MemorySink s;
  SimResult r = Simulate(*program, opt, s);
  ASSERT_EQ(r.status, SimResult::Status::kOk) << r.message;
  for (const auto& row : s.rows) {
    EXPECT_NEAR(row[2], 0.5 * kIO * row[1] * row[1], 1e-12);
    // Potential energy up to a constant: compare differences with row 0.
    EXPECT_NEAR(row[3] - s.rows[0][3], kMass * kG * kD * (std::sin(row[0]) - std::sin(s.rows[0][0])), 1e-12);
  }
}

// Simulate's output grid with the engine: default signals, first row at the start time
// with the initial state, last row exactly at the stop time.
TEST(SimPendulum, SimulateGridAndDefaultSignals) {
  flat::Mechanism m = Pendulum(kAmplitude);
  auto program = CompilePendulum(m);
  ASSERT_TRUE(program);
  SimOptions opt;
  opt.stop_time = 1.2345678;
  MemorySink s;
  SimResult r = Simulate(*program, opt, s);
  ASSERT_EQ(r.status, SimResult::Status::kOk) << r.message;
  EXPECT_EQ(s.names, rt::DefaultSignals(*program));
  ASSERT_EQ(s.times.size(), 501u);  // default (stop - start) / 500
  EXPECT_EQ(s.times.front(), 0.0);
  EXPECT_EQ(s.times.back(), 1.2345678);
  size_t iq = Column(s, "rev.q");
  EXPECT_DOUBLE_EQ(s.rows[0][iq], -M_PI / 2 + kAmplitude);
  EXPECT_GT(r.stats.integrator.steps, 0);
  EXPECT_EQ(r.stats.rows, 501);
}

// A NaN from a user expression (torque sqrt(0.5 - time)) is a numerical failure near
// t = 0.5 with a cause, and the CSV keeps every row before it, flushed.
TEST(SimPendulum, NaNFromExpressionFailsWithRowsKeptInCsv) {
  flat::Mechanism m = Pendulum(kAmplitude, /*nan_torque_after_half_second=*/true);
  auto program = CompilePendulum(m);
  ASSERT_TRUE(program);
  char path[] = "/tmp/kanesim_sim_failXXXXXX";
  int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  std::FILE* f = fdopen(fd, "w");
  CsvWriter w(f);
  SimOptions opt;
  opt.stop_time = 1.0;
  opt.interval = 0.1;
  opt.signals = {"rev.q"};
  SimResult r = Simulate(*program, opt, w);
  std::fclose(f);
  EXPECT_EQ(r.status, SimResult::Status::kNumericalFailure);
  EXPECT_GT(r.fail_time, 0.45);
  EXPECT_LT(r.fail_time, 0.65);
  EXPECT_FALSE(r.message.empty());
  std::FILE* in = std::fopen(path, "r");
  char line[256];
  std::vector<std::string> lines;
  while (std::fgets(line, sizeof line, in)) lines.push_back(line);
  std::fclose(in);
  std::remove(path);
  ASSERT_GE(lines.size(), 5u);  // header + rows at 0, 0.1, 0.2, 0.3 at least
  EXPECT_EQ(lines[0], "time,rev.q\n");
  EXPECT_EQ(lines[1].rfind("0,", 0), 0u);
  double t_last = std::strtod(lines.back().c_str(), nullptr);
  EXPECT_LE(t_last, 0.5 + 1e-12);
}

}  // namespace
}  // namespace kanesim::sim
