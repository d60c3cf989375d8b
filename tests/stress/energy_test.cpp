// Long horizon: examples/chain.mech with N = 5 (no damping, no forcing: conservative) for
// 1000 s. What must hold: the run completes, and the total energy E = T + V drifts by at
// most kDriftFactor * rtol * max(T) over the whole run (drift grows with the horizon; at
// rtol = 1e-6 CVODE-Adams measured 0.011 J on E0 = 8.5 J, max T = 64 J, so the bound
// 1e3 * 1e-6 * 64 = 0.064 J has a margin of ~6). Runs ~1.2 s (Release). Under sanitizers
// (KANESIM_STRESS_SHORT) the horizon is 20 s and the bound 1e2 * rtol * max T (measured 16x).
// If it failed: the integrator or the right-hand side leaks energy (a sign or a missing
// gyroscopic term shows up as drift long before it shows up in a short trajectory).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

constexpr double kRtol = 1e-6;
#ifdef KANESIM_STRESS_SHORT
constexpr int kHorizon = 20;          // sanitizer build (tests/stress/CMakeLists.txt)
constexpr double kDriftFactor = 1e2;  // measured 16 x rtol x max T at 20 s
#else
constexpr int kHorizon = 1000;
constexpr double kDriftFactor = 1e3;  // drift allowed per (rtol * max kinetic energy)
#endif

TEST(StressLongHorizon, Chain5EnergyDriftBounded) {
  RunResult r = RunKanesim("examples/chain.mech",
                           {"--set", "N=5", "--stop-time", std::to_string(kHorizon), "--interval",
                            std::to_string(kHorizon / 100.0), "--rtol", "1e-6",
                            "--integrator", "cvode", "--output", "kinetic_energy", "--output", "potential_energy"});
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  ASSERT_EQ(r.rows.size(), 101u);
  EXPECT_EQ(r.rows.back()[0], static_cast<double>(kHorizon));
  const std::vector<double> T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
  ASSERT_EQ(T.size(), V.size());
  const double E0 = T[0] + V[0];
  double drift = 0.0, t_max = 0.0;
  for (size_t k = 0; k < T.size(); ++k) {
    drift = std::max(drift, std::fabs(T[k] + V[k] - E0));
    t_max = std::max(t_max, T[k]);
  }
  const double bound = kDriftFactor * kRtol * t_max;
  RecordProperty("energy_drift_J", std::to_string(drift));
  RecordProperty("drift_over_rtol_maxT", std::to_string(drift / (kRtol * t_max)));
  std::printf("chain N=5, %d s, CVODE rtol 1e-6: E0 = %.6g J, max T = %.4g J, max |E - E0| = %.3g J "
              "= %.0f x rtol x max T (bound %.0f), wall %.1f s\n",
              kHorizon, E0, t_max, drift, drift / (kRtol * t_max), kDriftFactor, r.wall_seconds);
  EXPECT_LE(drift, bound) << "energy drift " << drift << " J over " << kHorizon << " s exceeds " << bound << " J";
}

}  // namespace
}  // namespace kanesim::stress
