// Golden comparison: interpolation, tolerances, first exceedance; invariants; specs.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "runtime/batch/golden.h"

namespace kanesim::batch {
namespace {

Trajectory Line(double slope, double dt, int n, double bump_at = -1, double bump = 0) {
  Trajectory t;
  t.names = {"x"};
  for (int k = 0; k < n; ++k) {
    double time = k * dt;
    t.t.push_back(time);
    t.rows.push_back({slope * time + (std::abs(time - bump_at) < 1e-12 ? bump : 0.0)});
  }
  return t;
}

// Wrong if linear interpolation between different grids is not exact on a line.
TEST(Interpolate, ExactOnLinearSignals) {
  Trajectory fine = Line(2.0, 0.001, 1001);
  EXPECT_NEAR(Interpolate(fine, 0, 0.5005), 1.001, 1e-14);
  EXPECT_EQ(Interpolate(fine, 0, -1.0), 0.0);  // clamped
  GoldenSpec spec;
  spec.default_tol = {"*", 1e-12, 0};
  CompareResult c = Compare(spec, Line(2.0, 0.01, 101), fine);  // different grids
  EXPECT_TRUE(c.pass);
}

// Wrong if the report names the wrong time or size of the largest deviation, or the
// wrong first time beyond tolerance (abs + rel * |golden|).
TEST(Compare, LargestDeviationAndFirstExceedance) {
  GoldenSpec spec;
  spec.default_tol = {"*", 1e-6, 0};
  Trajectory golden = Line(1.0, 0.1, 11);
  Trajectory run = golden;
  run.rows[3][0] += 2e-6;  // t = 0.3, 2x tolerance
  run.rows[7][0] -= 5e-6;  // t = 0.7, 5x
  CompareResult c = Compare(spec, golden, run);
  ASSERT_FALSE(c.pass);
  ASSERT_EQ(c.signals.size(), 1u);
  EXPECT_NEAR(c.signals[0].max_dev, 5e-6, 1e-15);
  EXPECT_NEAR(c.signals[0].t_max, 0.7, 1e-15);
  EXPECT_NEAR(c.signals[0].first_exceed, 0.3, 1e-15);
  EXPECT_NEAR(c.signals[0].worst_ratio, 5.0, 1e-6);
  // A per-signal relative tolerance of 1e-5 (|x| = 0.7 -> 7e-6) covers both.
  spec.tolerances = {{"x", 1e-6, 1e-5}};
  EXPECT_TRUE(Compare(spec, golden, run).pass);
}

// Wrong if a shorter run or a missing signal slips through as a pass.
TEST(Compare, ShortRunAndMissingSignal) {
  GoldenSpec spec;
  Trajectory golden = Line(1.0, 0.1, 11);
  Trajectory shorter = Line(1.0, 0.1, 6);
  EXPECT_FALSE(Compare(spec, golden, shorter).pass);
  Trajectory renamed = golden;
  renamed.names = {"y"};
  EXPECT_FALSE(Compare(spec, golden, renamed).pass);
}

// Wrong if energy drift is not measured against the energy that moves, or if a
// constraint invariant fails a model that has no constraint signals (it must skip).
TEST(Invariant, EnergyBalanceAndSkips) {
  Trajectory run;
  run.names = {"kinetic_energy", "potential_energy"};
  for (int k = 0; k <= 10; ++k) {
    double ke = 5.0 * k / 10;
    run.t.push_back(k);
    run.rows.push_back({ke, -ke + (k == 4 ? 1e-3 : 0.0)});  // drift 1e-3 at t = 4
  }
  std::vector<std::string> avail = {"kinetic_energy", "potential_energy", "x"};
  InvariantResult r = CheckInvariant({"energy_balance", 1e-3, kUnset, kUnset}, run, avail);
  EXPECT_EQ(r.status, InvariantResult::Status::kPass) << r.text;  // 1e-3 / 5 = 2e-4
  r = CheckInvariant({"energy_balance", 1e-4, kUnset, kUnset}, run, avail);
  EXPECT_EQ(r.status, InvariantResult::Status::kFail) << r.text;
  r = CheckInvariant({"energy_balance", 1e-4, 5.0, kUnset}, run, avail);  // window after the drift
  EXPECT_EQ(r.status, InvariantResult::Status::kPass) << r.text;
  r = CheckInvariant({"constraint_residual", 1e-8, kUnset, kUnset}, run, avail);
  EXPECT_EQ(r.status, InvariantResult::Status::kSkipped);
  r = CheckInvariant({"constraint_work", 1e-8, kUnset, kUnset}, run, avail);
  EXPECT_EQ(r.status, InvariantResult::Status::kSkipped);
}

// Wrong if a residual signal, once the runtime provides one, is not checked.
TEST(Invariant, ConstraintResidualChecksWhenAvailable) {
  Trajectory run;
  run.names = {"loop.constraint_residual[1]"};
  run.t = {0, 1};
  run.rows = {{0.0}, {3e-8}};
  InvariantResult r = CheckInvariant({"constraint_residual", 1e-8, kUnset, kUnset}, run, run.names);
  EXPECT_EQ(r.status, InvariantResult::Status::kFail) << r.text;
}

// Wrong if a spec's fields are dropped or a typo in a key passes silently.
TEST(ReadGoldenSpec, FieldsAndUnknownKeys) {
  std::string dir = ::testing::TempDir();
  {
    std::ofstream f(dir + "/g1.toml");
    f << "model = \"m.mech\"\nset = { k = 3 }\n[run]\nstop_time = 2\nrtol = 1e-9\n"
         "[tolerance]\ndefault = { abs = 1e-9 }\n\"j.q\" = { rel = 1e-4 }\n"
         "[[invariant]]\nkind = \"energy_balance\"\ntol = 1e-6\n";
  }
  GoldenSpec s;
  std::string err;
  ASSERT_TRUE(ReadGoldenSpec(dir + "/g1.toml", &s, &err)) << err;
  EXPECT_EQ(s.name, "g1");
  EXPECT_EQ(s.stop_time, 2.0);
  EXPECT_EQ(s.rtol, 1e-9);
  EXPECT_EQ(s.sets, (std::vector<std::string>{"k=3"}));
  EXPECT_EQ(s.default_tol.abs, 1e-9);
  ASSERT_EQ(s.tolerances.size(), 1u);
  EXPECT_EQ(s.tolerances[0].rel, 1e-4);
  ASSERT_EQ(s.invariants.size(), 1u);
  EXPECT_NE(s.golden_path.find("g1.csv"), std::string::npos);
  {
    std::ofstream f(dir + "/g2.toml");
    f << "model = \"m.mech\"\n[run]\nstoptime = 2\n";
  }
  EXPECT_FALSE(ReadGoldenSpec(dir + "/g2.toml", &s, &err));
  EXPECT_NE(err.find("stoptime"), std::string::npos);
}

// Wrong if the stored format does not read back exactly (17 digits, provenance).
TEST(TrajectoryCsv, RoundTrip) {
  Trajectory t = Line(1.0 / 3.0, 0.1, 5);
  t.names = {"a,b"};
  t.provenance["model"] = "m.mech fnv1a64:0123";
  std::string path = ::testing::TempDir() + "/traj.csv";
  std::ofstream(path) << FormatTrajectoryCsv(t);
  Trajectory back;
  std::string err;
  ASSERT_TRUE(ReadTrajectoryCsv(path, &back, &err)) << err;
  EXPECT_EQ(back.names, t.names);
  EXPECT_EQ(back.t, t.t);
  EXPECT_EQ(back.rows, t.rows);
  EXPECT_EQ(back.provenance["model"], "m.mech fnv1a64:0123");
}

}  // namespace
}  // namespace kanesim::batch
