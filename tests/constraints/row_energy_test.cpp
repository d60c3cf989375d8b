// Output rows checked against the energy (docs/constraints.md "Rows checked against the
// energy"; sim/stepper.h RowEnergy): in a conservative model an interpolated output
// instant whose T + V is far off the energies of the accepted steps around it is not
// written from the interpolant (DOP853: the step is taken again to end on it; CVODE, IDA,
// ARKODE: the instant is integrated again from the step's start). Checked against the
// lumped crank's energy (1/2) J w^2 + G sin(theta) of the equal-link parallelograms
// (tests/support/lumped_crank.h), which does not depend on the check: every row within 1e-6
// of E. With the check off (TestHooks::row_energy_check) the same runs write the rows the
// check exists for, so these cases fail if it stops working.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/simulate.h"
#include "sim/test_hooks.h"
#include "tests/support/load_util.h"
#include "tests/support/lumped_crank.h"
#include "tests/support/sanitizer_cases.h"

namespace kanesim::test {
namespace {

struct Rows {
  sim::SimResult result;
  double energy = 0.0;  // max over the rows of |E_lumped - E_lumped(first row)| / |E_lumped(first row)|
  double last_t = 0.0;
};

// Runs `model` to `stop` with rows every 0.01 s, `integrator` at rtol = atol = `rtol` on the
// reduced form (`solver`), the signals q and u of `crank` first; the lumped energy of crank
// `c` in every row.
Rows RunRows(const std::string& model, std::vector<lang::ParamOverride> sets, const std::string& crank,
         const lumped_crank::Crank& c, rt::Integrator integrator, double rtol, double stop, bool check,
         rt::SolverPath solver = rt::SolverPath::Dense) {
  rt::CompileOptions co;
  co.solver = solver;
  auto l = LoadModel(kRoot + model, std::move(sets), co);
  Rows r;
  if (!l || !l->prog) {
    ADD_FAILURE() << "the model did not compile";
    return r;
  }
  sim::SimOptions so;
  so.rtol = so.atol = rtol;
  so.integrator = integrator;
  so.stop_time = stop;
  so.interval = 0.01;
  so.signals = {crank + ".q", crank + ".u"};
  sim::TestHooks hooks;
  hooks.row_energy_check = check;
  // The energy guard's bound (1e-4 of E) is far above these rows' errors; off, so that a
  // run without the check writes them all.
  so.energy_check = sim::EnergyCheck::kOff;
  sim::MemorySink sink;
  r.result = sim::Simulate(*l->prog, so, sink, hooks);
  if (sink.rows.empty()) return r;
  auto energy = [&c](const std::vector<double>& row) { return 0.5 * c.J * row[1] * row[1] + c.G * std::sin(row[0]); };
  const double e0 = energy(sink.rows.front());
  for (const auto& row : sink.rows) r.energy = std::max(r.energy, std::fabs(energy(row) - e0) / std::fabs(e0));
  r.last_t = sink.times.back();
  return r;
}

// Chain of ten equal-link parallelograms, DOP853, rtol 1e-12, reduced form: the step
// [0.6045, 0.6253] crosses a change point by itself (no bridge, so the dense-output stage
// check of integrator_dop853.cpp kDenseLimit saw 0.278 < 1); its ends are 1e-10 of E off,
// the rows at t = 0.61 and 0.62 interpolated in it 6.0e-6 and 1.3e-5 (exit 0). Their energy
// is 8.7e4 units of Eq. (5) off the line between the ends' (the other rows of the 20 s
// run: at most 260).
TEST(RowEnergy, Dop853RowsAcrossAChangePointOfTheChainOfTen) {
  const lumped_crank::Crank c = lumped_crank::ParallelogramChain(10);
  const std::string model = "/tests/stress/models/parallelogram_chain.mech";
  const Rows on = RunRows(model, {{"N", "10"}}, "rj0", c, rt::Integrator::Dop853, 1e-12, 0.7, true);
  EXPECT_EQ(on.result.status, sim::SimResult::Status::kOk) << on.result.message;
  EXPECT_NEAR(on.last_t, 0.7, 1e-12);
  EXPECT_LT(on.energy, 1e-6);
  EXPECT_GE(on.result.stats.integrator.energy_rejects, 1);
  const Rows off = RunRows(model, {{"N", "10"}}, "rj0", c, rt::Integrator::Dop853, 1e-12, 0.7, false);
  EXPECT_EQ(off.result.stats.integrator.energy_rejects, 0);
  EXPECT_GT(off.energy, 1e-6);  // the rows the check exists for
}

// The single parallelogram with unequal links (a = 0.5, b = 0.6), DOP853, rtol 1e-10,
// reduced form: the step [6.4614, 6.4950] crosses a change point, its ends 7.5e-10 of E off,
// the rows at t = 6.47, 6.48, 6.49 4.2e-5, 2.5e-5, 1.8e-5 (exit 0; the dense-output check
// saw 0.219).
TEST(RowEnergy, Dop853RowsAcrossAChangePointOfTheParallelogram) {
  const double a = 0.5, m1 = 0.5, m2 = 0.8, m3 = 1.0, g = 9.81;
  const lumped_crank::Crank c{(m1 + m2) * a * a / 3.0 + m3 * a * a, g * a * ((m1 + m2) / 2.0 + m3)};
  const std::string model = "/tests/stress/models/parallelogram.mech";
  const Rows on = RunRows(model, {{"a", "0.5"}}, "crank_pivot", c, rt::Integrator::Dop853, 1e-10, 6.6, true);
  EXPECT_EQ(on.result.status, sim::SimResult::Status::kOk) << on.result.message;
  EXPECT_LT(on.energy, 1e-6);
  EXPECT_GE(on.result.stats.integrator.energy_rejects, 1);
  const Rows off = RunRows(model, {{"a", "0.5"}}, "crank_pivot", c, rt::Integrator::Dop853, 1e-10, 6.6, false);
  EXPECT_GT(off.energy, 1e-5);
}

}  // namespace
}  // namespace kanesim::test

namespace kanesim::test {
namespace {

// ARKODE on the chain of ten, rtol 1e-10, reduced form. Its rows used to come from ERKStep's
// interpolant: one output instant 1541 units of Eq. (5) off the steps around it (the others at
// most 57), 6.1e-7 of E off the lumped crank (the rest of the run 1.3e-7), integrated again by
// DOP853. Rows now end ERKStep's steps (sim/integrator_arkode.cpp): nothing is interpolated,
// the check finds no row to integrate again, and the run stays as close to the lumped crank
// with the check as without it (measured 1.03e-7 both).
TEST(RowEnergy, ArkodeRowsEndStepsAndNeedNoSecondIntegration) {
  const lumped_crank::Crank c = lumped_crank::ParallelogramChain(10);
  const std::string model = "/tests/stress/models/parallelogram_chain.mech";
  const Rows on = RunRows(model, {{"N", "10"}}, "rj0", c, rt::Integrator::ArkodeErk, 1e-10, 20.0, true);
  // Under the sanitizers the run with the check only (the one without it is the same code
  // minus the check): the same assertions on it, to t = 20.
  const Rows off = kUnderSanitizers ? on : RunRows(model, {{"N", "10"}}, "rj0", c, rt::Integrator::ArkodeErk, 1e-10, 20.0, false);
  std::printf("[ rows ] ARKODE chain of ten 1e-10: check on %.3g (%ld integrated again, %ld steps), off %.3g (%ld steps)\n",
              on.energy, on.result.stats.integrator.energy_rejects, on.result.stats.integrator.steps, off.energy,
              off.result.stats.integrator.steps);
  EXPECT_EQ(on.result.status, sim::SimResult::Status::kOk) << on.result.message;
  EXPECT_EQ(on.result.stats.integrator.energy_rejects, 0);
  EXPECT_LT(on.energy, 2.5e-7);
  EXPECT_LT(off.energy, 2.5e-7);
}

}  // namespace
}  // namespace kanesim::test
