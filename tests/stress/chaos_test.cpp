// Chaotic motion: examples/double_pendulum.mech up to t = 5 s, inside its predictability
// horizon (tests/data/double_pendulum_ref.md: the worst-case amplification of an initial
// error is 2.4e4 at 5 s, so a double-precision run can match ~11.6 digits there; at 10 s
// only ~1e-4, see docs/benchmarks.md). What must hold: the error at t = 5 s against the
// 40-digit reference shrinks at every tightening of rtol (1e-4, 1e-6, 1e-8, 1e-10) until
// it is below kFinalTol, stays below it from there, shrinks by kMinTotalGain overall, and
// ends below kFinalTol: a local error of 1e-10 may be amplified by up to 2.4e4 by t = 5 s
// (~2.4e-6). Measured at rtol 1e-8 / 1e-10: IDA 4.6e-6 / 5.0e-6 (the planar recursion;
// 1.7e-5 / 5.1e-6 on the spatial one, the same equations to rounding: IDA's error there
// is its floor, not its tolerance), CVODE 7.7e-4 / 3.1e-6, ARKODE 3.0e-7 / 9.3e-9.
// If it failed: the integrator does not
// converge on a chaotic trajectory (tolerance not honoured, error control on the wrong
// states), or the equations are wrong in a way a short run hides.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

constexpr double kMinTotalGain = 1e3;  // error(1e-4) / error(1e-10)
constexpr double kFinalTol = 2e-5;     // at rtol = 1e-10: ~10x the amplified local error

class StressChaos : public ::testing::TestWithParam<const char*> {};

TEST_P(StressChaos, DoublePendulumConvergesUpToTheHorizon) {
  const RunResult ref = ReadCsv("tests/data/double_pendulum_ref.csv");
  const std::vector<double>& want = ref.RowAt(5.0);
  double prev = 0.0, first = 0.0;
  for (const char* rtol : {"1e-4", "1e-6", "1e-8", "1e-10"}) {
    RunResult r = RunKanesim("examples/double_pendulum.mech",
                             {"--integrator", GetParam(), "--rtol", rtol, "--stop-time", "5", "--interval", "5"});
    ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
    double err = 0.0;
    for (const char* q : {"shoulder.q", "elbow.q"})
      err = std::max(err, std::fabs(r.rows.back()[static_cast<size_t>(r.Index(q))] -
                                    want[static_cast<size_t>(ref.Index(q))]));
    std::printf("double pendulum t = 5 s, %s rtol %s: error %.2g\n", GetParam(), rtol, err);
    if (prev > kFinalTol) {
      EXPECT_LT(err, prev) << "no convergence from the previous tolerance at rtol " << rtol;
    } else if (prev > 0.0) {
      EXPECT_LE(err, kFinalTol) << "the error left the floor it had reached, at rtol " << rtol;
    }
    if (first == 0.0) first = err;
    prev = err;
  }
  EXPECT_GE(first / prev, kMinTotalGain);
  EXPECT_LE(prev, kFinalTol);
}

INSTANTIATE_TEST_SUITE_P(Integrators, StressChaos, ::testing::Values("ida", "cvode", "arkode"));

}  // namespace
}  // namespace kanesim::stress
