// Golden comparison: interpolation, tolerances, first exceedance; invariants; specs.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "batch/golden.h"

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

// [run] energy_check: read as given; the default leaves the settings text of the specs
// recorded before the key existed unchanged (their stored `settings` hashes stay valid),
// any other value changes it (a golden recorded unguarded is not compared to a guarded run).
TEST(ReadGoldenSpec, EnergyCheckKey) {
  const std::string dir = ::testing::TempDir();
  auto read = [&](const std::string& name, const std::string& run_extra, GoldenSpec* s) {
    {
      std::ofstream f(dir + "/" + name + ".toml");
      f << "model = \"m.mech\"\n[run]\nrtol = 1e-9\n" << run_extra;
    }
    std::string err;
    EXPECT_TRUE(ReadGoldenSpec(dir + "/" + name + ".toml", s, &err)) << err;
  };
  GoldenSpec plain, on, off, report;
  read("ec", "", &plain);
  read("ec", "energy_check = \"on\"\n", &on);
  read("ec", "energy_check = \"off\"\n", &off);
  read("ec", "energy_check = \"report\"\n", &report);
  EXPECT_EQ(plain.energy_check, "on");
  EXPECT_EQ(off.energy_check, "off");
  EXPECT_EQ(SettingsText(plain), SettingsText(on));
  EXPECT_NE(SettingsText(plain), SettingsText(off));
  EXPECT_NE(SettingsText(off), SettingsText(report));
  {
    std::ofstream f(dir + "/ec2.toml");
    f << "model = \"m.mech\"\n[run]\nenergy_check = 1\n";
  }
  GoldenSpec s;
  std::string err;
  EXPECT_FALSE(ReadGoldenSpec(dir + "/ec2.toml", &s, &err));
  EXPECT_NE(err.find("energy_check must be a string"), std::string::npos) << err;
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


// Wrong if a stored output that cannot guard anything reads as a valid golden: cut off,
// no rows, a non-finite value (inf <= abs + rel * inf passes everything), times out of
// order, or rows unlike the count and checksum recorded with them.
TEST(TrajectoryCsv, CorruptFilesAreRefused) {
  Trajectory t = Line(0.5, 0.1, 6);
  const std::string good = FormatTrajectoryCsv(t);
  const std::string path = ::testing::TempDir() + "/corrupt.csv";
  Trajectory back;
  std::string err;
  std::ofstream(path) << good;
  ASSERT_TRUE(ReadTrajectoryCsv(path, &back, &err)) << err;
  EXPECT_EQ(back.provenance["rows"], "6");
  const size_t header_end = good.find("time,x\n") + 7;
  const std::vector<std::pair<std::string, std::string>> bad = {
      {good.substr(0, good.size() - 3), "cut off"},
      {good.substr(0, header_end), "no rows"},
      {good.substr(0, good.rfind('\n', good.size() - 2) + 1), "recorded with 6"},
      {good.substr(0, good.rfind(',') + 1) + "inf\n", "not a finite number"},
      {good.substr(0, good.rfind(',') + 1) + "nan\n", "not a finite number"},
      {good.substr(0, good.rfind(',') + 1) + "0x1\n", "not a finite number"},
      {good.substr(0, good.rfind('\n', good.size() - 2) + 1) + "0.1,0.05\n", "do not increase"},
  };
  for (const auto& [text, why] : bad) {
    std::ofstream(path) << text;
    EXPECT_FALSE(ReadTrajectoryCsv(path, &back, &err)) << why;
    EXPECT_NE(err.find(why), std::string::npos) << err;
  }
  std::string edited = good;
  edited[edited.size() - 2] = edited[edited.size() - 2] == '5' ? '6' : '5';
  std::ofstream(path) << edited;
  EXPECT_FALSE(ReadTrajectoryCsv(path, &back, &err));
  EXPECT_NE(err.find("checksum"), std::string::npos) << err;
}

// Wrong if a golden over other instants than the run (fewer rows, an earlier end)
// compares as equal.
TEST(Compare, GridsMustMatch) {
  Trajectory golden = Line(1.0, 0.1, 11), run = golden;
  EXPECT_EQ(CompareGrids(golden, run), "");
  Trajectory one = Line(1.0, 0.1, 1);
  EXPECT_NE(CompareGrids(one, run).find("the golden holds 1 instant over [0, 0], the run 11 instants"),
            std::string::npos)
      << CompareGrids(one, run);
  EXPECT_NE(CompareGrids(Line(1.0, 0.1, 10), run), "");
  EXPECT_NE(CompareGrids(Line(1.0, 0.2, 11), run), "");
}

// Wrong if an invariant whose window holds no instant passes (it checked nothing).
TEST(Invariant, EmptyWindowFails) {
  Trajectory run;
  run.names = {"kinetic_energy", "potential_energy"};
  for (int k = 0; k <= 10; ++k) {
    run.t.push_back(k);
    run.rows.push_back({1.0, 0.0});
  }
  InvariantResult r = CheckInvariant({"energy_balance", 1e-3, 20.0, 30.0}, run, run.names);
  EXPECT_EQ(r.status, InvariantResult::Status::kFail) << r.text;
  EXPECT_NE(r.text.find("no output instant"), std::string::npos) << r.text;
}

// Wrong if a spec value that makes the test pass anything (an infinite or NaN
// tolerance) or run nothing (a non-finite or non-positive time setting), or a value of
// the wrong type, is accepted.
TEST(ReadGoldenSpec, ValuesThatCannotGuardAreRefused) {
  const std::string dir = ::testing::TempDir();
  const std::vector<std::string> bad = {
      "[tolerance]\ndefault = { abs = inf }",  "[tolerance]\ndefault = { rel = nan }",
      "[tolerance]\nx = { abs = -1 }",         "[tolerance]\nx = { abs = \"1\" }",
      "[run]\nstop_time = inf",                "[run]\nstop_time = nan",
      "[run]\ninterval = 0",                   "[run]\nrtol = -1e-6",
      "[run]\nstart_time = 2\nstop_time = 1", "[[invariant]]\nkind = \"energy_balance\"\ntol = inf",
      "[[invariant]]\nkind = \"energy_balance\"\ntol = 1\nfrom = 2\nto = 1",
      "[[invariant]]\nkind = \"energy_balance\"\ntol = 1\nform = 2",
      "set = { k = [1, 2] }",                     "model_name = 3",
      "golden = 1",                               "run = 3",
      "tolerance = 1",                            "invariant = 1",
  };
  for (const std::string& body : bad) {
    std::ofstream(dir + "/bad.toml") << "model = \"m.mech\"\n" << body << "\n";
    GoldenSpec s;
    std::string err;
    EXPECT_FALSE(ReadGoldenSpec(dir + "/bad.toml", &s, &err)) << body;
    EXPECT_NE(err.find("bad.toml"), std::string::npos) << body << ": " << err;
  }
}

}  // namespace
}  // namespace kanesim::batch
