// Mass and inertia ratios 1e-6 ... 1e6 in one chain (models/mass_ratio_chain.mech: rod
// masses 1, 1e6, 1e-6, 1e3, 1e-3 kg; the mass matrix spans twelve orders of magnitude).
// What must hold, for every integrator and both solution paths: the run completes and q
// at t = 0.5, 1, 1.5, 2 s matches tests/stress/data/mass_ratio_ref.csv (Pinocchio aba +
// DOP853 1e-13, estimated error <= 8e-12; bench/wp/make_stress_refs.py) within 1e-6 at
// rtol 1e-10 (measured: 2e-10 ARKODE, ~2e-8 IDA and CVODE), or it fails with exit code 2
// and a message. If it failed: the mass matrix factorization loses the light bodies
// (cancellation in the composite inertias, a pivot threshold, an absolute tolerance that
// ignores small entries).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

constexpr double kQTol = 1e-6;

class StressMassRatio : public ::testing::TestWithParam<std::tuple<const char*, const char*>> {};

TEST_P(StressMassRatio, MatchesReferenceOrFailsCleanly) {
  const auto [integrator, solver] = GetParam();
  RunResult r = RunKanesim("tests/stress/models/mass_ratio_chain.mech",
                           {"--integrator", integrator, "--solver", solver, "--rtol", "1e-10", "--output", "j[*].q"});
  if (r.exit_code == 2) {
    EXPECT_NE(r.stderr_text.find("numerical failure at t = "), std::string::npos) << r.stderr_text;
    GTEST_SKIP() << "refused cleanly: " << r.stderr_text;
  }
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  const RunResult ref = ReadCsv("tests/stress/data/mass_ratio_ref.csv");
  double worst = 0.0;
  for (double t : {0.5, 1.0, 1.5, 2.0}) {
    const std::vector<double>& row = r.RowAt(t);
    const std::vector<double>& want = ref.RowAt(t);
    ASSERT_NEAR(row[0], t, 1e-12);
    for (int i = 1; i <= 5; ++i) {
      const std::string name = "j[" + std::to_string(i) + "].q";
      const double got = row[static_cast<size_t>(r.Index(name))], exp = want[static_cast<size_t>(ref.Index(name))];
      worst = std::max(worst, std::fabs(got - exp));
      EXPECT_NEAR(got, exp, kQTol) << name << " at t = " << t;
    }
  }
  std::printf("mass ratio chain, %s %s, rtol 1e-10: max |q - q_ref| = %.2g\n", integrator, solver, worst);
}

INSTANTIATE_TEST_SUITE_P(AllPaths, StressMassRatio,
                         ::testing::Combine(::testing::Values("ida", "cvode", "arkode"),
                                            ::testing::Values("dense", "sparse")));

}  // namespace
}  // namespace kanesim::stress
