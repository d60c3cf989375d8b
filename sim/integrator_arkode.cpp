// ARKODE's ERKStep on y' = f(t, y): an explicit embedded Runge-Kutta pair with
// adaptive steps (its table made first-same-as-last: SetFsalTable).
//
// Output instants end steps (ERKStep's stop time at each, Stop()): its Hermite interpolant
// has degree 5 at most, too low for the steps of an 8th-order pair. Measured on the forced
// damped oscillator (examples/spring_mass.mech, 10 s every 0.01 s) once the first stage was
// right: rows off the closed form by 2.7e-5, 6.6e-7, 5.1e-8 at rtol 1e-6, 1e-8, 1e-10 with
// the steps' ends at 1.4e-8, 7.9e-11, 1.2e-12. At least one step per output interval.
//
// A recoverable failure of f (> 0, e.g. a NaN from a stage past the onset of a NaN) ends
// ERKStepEvolve with ARK_UNREC_RHSFUNC_ERR: ERKStep (SUNDIALS 6.4) retries only steps
// that failed the error test. So that such a stage shrinks the step as in the other
// solvers instead of ending the run at the start of the step (and losing the output
// instants inside it), the stepper restarts ERKStep with a quarter of its last step:
// the first time from the last output instant, later from the last accepted step, which
// a post-step hook records from then on (only then: with the hook installed ERKStep's
// dense output loses about a digit). GuardedRhs bounds the retries.
//
// Closed loops on the reduced form (steps checked one at a time): the drift of each
// accepted step from the constraints is measured aside (MeasureDrift), and when it is past
// DriftWatch::kLimit error weights and still growing ERKStep is reset to the projected state
// before its next step (ResetProjected).
#include <arkode/arkode_erkstep.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sim/stepper.h"
#include "sim/sundials_util.h"

namespace kanesim::sim::detail {
namespace {

constexpr ModuleFunctions kArkode{
    .module = "ARKODE",
    .err_handler = ERKStepSetErrHandlerFn,
    .tolerances = ERKStepSStolerances,
    .user_data = ERKStepSetUserData,
    .stop_time = ERKStepSetStopTime,
    .max_num_steps = ERKStepSetMaxNumSteps,
    .max_step = ERKStepSetMaxStep,
    .init_step = ERKStepSetInitStep,
    .current_time = ERKStepGetCurrentTime,
    .dky = ERKStepGetDky,
    .free = ERKStepFree,
    .flag_name = ERKStepGetReturnFlagName,
    .num_steps = ERKStepGetNumSteps,
    .num_rhs_evals = ERKStepGetNumRhsEvals,
    .num_err_test_fails = ERKStepGetNumErrTestFails,
    .last_step = ERKStepGetLastStep,
    .num_lin_setups = nullptr,  // an explicit method: no iteration, no linear solver
    .num_nonlin_iters = nullptr,
    .num_nonlin_conv_fails = nullptr,
    .last_order = nullptr,
    .num_jac_evals = nullptr,
    .num_lin_rhs_evals = nullptr,
    .current_step = ERKStepGetCurrentStep
};

class ArkodeStepper final : public SundialsStepper {
 public:
  explicit ArkodeStepper(GuardedRhs& rhs) : SundialsStepper(rhs, kArkode) {}

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    if (!MakeState(y0, /*with_yp=*/false, error)) return false;
    mem_ = ERKStepCreate(&ArkodeStepper::Rhs, t0, s_.y, s_.ctx);
    if (!mem_) return Fail(error, "ERKStepCreate failed");
    const ARKODE_ERKTableID table =
        options.erk_table == ErkTable::Fehlberg87 ? ARKODE_FEHLBERG_13_7_8 : ARKODE_VERNER_8_5_6;
    if (CaptureMessages() != ARK_SUCCESS || !SetFsalTable(table) ||
        ERKStepSetInterpolantDegree(mem_, ARK_INTERP_MAX_DEGREE) != ARK_SUCCESS)
      return Fail(error, WithDetail("ARKODE setup failed", messages_.last));
    if (!SetCommonOptions(stop, options, error)) return false;
    if (!InitRoots([&](int count) { return ERKStepRootInit(mem_, count, &SundialsStepper::Roots); },
                   [&](int* d) { return ERKStepSetRootDirection(mem_, d) | ERKStepSetNoInactiveRootWarn(mem_); }, error))
      return false;
    stop_ = stop;
    rtol_ = options.rtol;
    atol_ = options.atol;
    t_accepted_ = t0;
    y_accepted_.assign(y0, y0 + rhs_.Size());
    return true;
  }

  int Advance(double tout, double* y) override {
    double tret = 0.0;
    row_stop_ = tout;  // (rows are step ends: the head of this file)
    if (ERKStepSetStopTime(mem_, Stop()) != ARK_SUCCESS) return ARK_ILL_INPUT;
    if (StepsOneByOne()) return AdvanceChecked(tout, y);
    for (;;) {  // (a graze guard that found no dip: on)
      int flag = ERKStepEvolve(mem_, tout, s_.y, &tret, ARK_NORMAL);
      while (flag == ARK_UNREC_RHSFUNC_ERR && rhs_.failed && !rhs_.fatal) flag = Restart(tout, &tret);
      if (flag >= 0 && !hooked_) {  // the restart point until the hook keeps accepted steps
        const double* ys = N_VGetArrayPointer(s_.y);
        t_accepted_ = tret;
        std::copy(ys, ys + y_accepted_.size(), y_accepted_.begin());
      }
      if (flag != ARK_ROOT_RETURN) return CopyOut(flag, y);
      if (int r = EventReached(tret, y, [&](int* f) { ERKStepGetRootInfo(mem_, f); }); r != kNoEvent) return r;
    }
  }

  // ERKStepReset keeps the step size and evaluates f(t, y) again with the new inputs (the
  // next step's first stage would otherwise be the last step's f).
  // At the last step's end: its stop time, where s_.y is (the caller sets the next stop).
  int InputsChanged() override {
    const double t = stop_;
    if (ERKStepReset(mem_, t, s_.y) != ARK_SUCCESS) return -1;
    t_accepted_ = t;
    const double* ys = N_VGetArrayPointer(s_.y);
    std::copy(ys, ys + y_accepted_.size(), y_accepted_.begin());
    return 0;
  }

  IntegratorStats Stats() const override {
    IntegratorStats st = SundialsStepper::Stats();
    st.steps += before_restarts_.steps;
    st.rhs_evals += before_restarts_.rhs_evals;
    st.err_test_fails += before_restarts_.err_test_fails;
    return st;
  }

 private:
  // ERKStep (SUNDIALS 6.4) takes the last stage's f as the next step's first whenever that
  // stage is at c_s = 1 (erkStep_FullRHS, ARK_FULLRHS_END), without checking that its row
  // a_s,j is the solution's b_j; fixed upstream in 6.7.0 (LLNL/sundials #324). Both tables
  // used here end with a stage at c_s = 1 whose state Y_s is not y_n+1, so every step began
  // with k_1 = f(t_n, Y_s) instead of f(t_n, y_n): an error J (Y_s - y_n) of the last step's
  // size that no shorter retry removes. Where J is large (the light damped tip of the chain of
  // EndStopEvents.ChainWithManyStopsRestsAndStrikesTogether: |Y_s - y_n| ~ 1e-4 in its speed,
  // 0.2 in its k_1), the error test then failed seven times in a row down to h ~ 5e-7. The
  // table is loaded with one stage more, row b_j at c = 1 with weights b = d = 0: its state is
  // y_n+1 (the same sums), so the reuse is exact (a first-same-as-last pair, as Dormand-Prince's
  // 5(4)); it costs the one evaluation per step that 6.7's recomputation costs.
  bool SetFsalTable(ARKODE_ERKTableID id) {
    ARKodeButcherTable given = ARKodeButcherTable_LoadERK(id);
    if (!given) return false;
    const int s = given->stages;
    ARKodeButcherTable fsal = ARKodeButcherTable_Alloc(s + 1, given->d != nullptr);
    bool ok = fsal != nullptr;
    if (ok) {
      fsal->q = given->q;
      fsal->p = given->p;
      for (int i = 0; i < s; ++i) {
        std::copy(given->A[i], given->A[i] + s, fsal->A[i]);
        fsal->A[s][i] = given->b[i];
        fsal->b[i] = given->b[i];
        fsal->c[i] = given->c[i];
        if (given->d) fsal->d[i] = given->d[i];
      }
      fsal->c[s] = 1.0;
      ok = ERKStepSetTable(mem_, fsal) == ARK_SUCCESS;
    }
    ARKodeButcherTable_Free(fsal);
    ARKodeButcherTable_Free(given);
    return ok;
  }

  // After each accepted step: where a restart begins.
  static int Accepted(double t, N_Vector y, void* user_data) {
    static_cast<ArkodeStepper*>(static_cast<SundialsStepper*>(user_data))->StepChecked(t, N_VGetArrayPointer(y));
    return 0;
  }

  // Advance one step at a time, each checked (OdeSystem::StepAccepted) and kept as the
  // restart point (StepChecked), then the output instant from ERKStep's interpolant.
  int AdvanceChecked(double tout, double* y) {
    return AdvanceCheckedSteps(tout, y, [&](double* tret) {
      if (watch_.drifted && !ResetProjected()) return ARK_ILL_INPUT;
      int flag = ERKStepEvolve(mem_, tout, s_.y, tret, ARK_ONE_STEP);
      while (flag == ARK_UNREC_RHSFUNC_ERR && rhs_.failed && !rhs_.fatal) flag = Restart(tout, tret, ARK_ONE_STEP);
      if (flag == ARK_ERR_FAILURE && rhs_.ChecksSteps() && ResetAfterErrorTest()) flag = ERKStepEvolve(mem_, tout, s_.y, tret, ARK_ONE_STEP);
      if (flag >= 0 && flag != ARK_ROOT_RETURN) MeasureDrift(*tret);
      return flag;
    }, [&](int* f) { ERKStepGetRootInfo(mem_, f); });
  }

  // The accepted step's drift: how far its y is from y*, its projection onto the
  // constraints (the state f is evaluated at), in the error test's weights
  // |y*_i - y_i| / (rtol |y_i| + atol). Past DriftWatch::kLimit, ERKStep goes on from y* after
  // the output instants of this step (ResetProjected). Without it the components the
  // projection overrides drifted at loose tolerances (the relaxation in f pulls them back
  // at k_drift = 10 1/s, about one step there), up to 0.5 rad/s on the chains of
  // parallelograms at rtol 1e-4, and an output row or a stage whose partition of the
  // speeds differs took a drifted one as independent (docs/constraints.md, "A drifted
  // state"). A projection that fails (at a singular configuration) leaves y as it is.
  void MeasureDrift(double t) {
    watch_.Measure(t, N_VGetArrayPointer(s_.y), static_cast<size_t>(rhs_.Size()), rtol_, atol_,
                   [&](double tt, double* y) { return rhs_.ProjectAside(tt, y); });
  }

  // ERKStep reset (ERKStepReset) to the projected state of the last step, once that
  // step's output instants are written (they come from its interpolant).
  bool ResetProjected() {
    watch_.Clear();
    // y* as f projects it (f's partition of the speeds: the components it keeps are the
    // ones ERKStep integrated without override).
    double* ys = N_VGetArrayPointer(s_.y);
    std::copy(watch_.stepped_y.begin(), watch_.stepped_y.end(), ys);
    if (rhs_.Project(watch_.t_drifted, ys) != 0) return true;  // no reset where f cannot project
    std::copy(ys, ys + watch_.stepped_y.size(), watch_.projected.begin());
    if (ERKStepReset(mem_, watch_.t_drifted, s_.y) != ARK_SUCCESS || ERKStepSetStopTime(mem_, Stop()) != ARK_SUCCESS)
      return false;
    StepChecked(watch_.t_drifted, watch_.projected.data());
    return true;
  }

  // The error test failed repeatedly (ARK_ERR_FAILURE) on a step of closed loops: ERKStep
  // again from the projection y* of the last accepted step (ERKStepReset), once per
  // accepted step; false (the failure stands) when it was tried there already or f cannot
  // project. Near a limit position the off-constraint components' error estimate does not
  // shrink with the step; projecting every step instead costs accuracy (measurements: docs/constraints/2026-11-28_tuning_measurements.md).
  bool ResetAfterErrorTest() {
    if (reset_at_ == t_accepted_) return false;
    reset_at_ = t_accepted_;
    double* ys = N_VGetArrayPointer(s_.y);
    std::copy(y_accepted_.begin(), y_accepted_.end(), ys);
    if (rhs_.Project(t_accepted_, ys) != 0) return false;
    watch_.Clear();
    return ERKStepReset(mem_, t_accepted_, s_.y) == ARK_SUCCESS && ERKStepSetStopTime(mem_, Stop()) == ARK_SUCCESS;
  }

  void StepChecked(double t, const double* y) override {
    t_accepted_ = t;
    std::copy(y, y + y_accepted_.size(), y_accepted_.begin());
  }

  FailureKind Kind(int flag) const override {
    switch (flag) {
      case ARK_RHSFUNC_FAIL:
      case ARK_FIRST_RHSFUNC_ERR:
      case ARK_REPTD_RHSFUNC_ERR:
      case ARK_UNREC_RHSFUNC_ERR: return FailureKind::kRhs;
      case ARK_TOO_MUCH_WORK: return FailureKind::kTooMuchWork;
      case ARK_TOO_MUCH_ACC: return FailureKind::kTooMuchAccuracy;
      case ARK_ERR_FAILURE: return FailureKind::kErrorTest;
      default: return FailureKind::kOther;
    }
  }

  // ERKStep again from the restart point, with a quarter of the last accepted step (of
  // the step it was about to try when none was accepted yet), toward tout.
  int Restart(double tout, double* tret, int mode = ARK_NORMAL) {
    double h = 0.0;
    ERKStepGetLastStep(mem_, &h);
    if (h == 0.0) ERKStepGetCurrentStep(mem_, &h);
    const IntegratorStats st = Stats();
    before_restarts_.steps = st.steps;
    before_restarts_.rhs_evals = st.rhs_evals;
    before_restarts_.err_test_fails = st.err_test_fails;
    double* ys = N_VGetArrayPointer(s_.y);
    std::copy(y_accepted_.begin(), y_accepted_.end(), ys);
    if (mode == ARK_NORMAL && !hooked_ && ERKStepSetPostprocessStepFn(mem_, &ArkodeStepper::Accepted) != ARK_SUCCESS)
      return ARK_UNREC_RHSFUNC_ERR;
    hooked_ = hooked_ || mode == ARK_NORMAL;
    if (ERKStepReInit(mem_, &ArkodeStepper::Rhs, t_accepted_, s_.y) != ARK_SUCCESS ||
        ERKStepSetInitStep(mem_, kRhsShrink * h) != ARK_SUCCESS || ERKStepSetStopTime(mem_, Stop()) != ARK_SUCCESS)
      return ARK_UNREC_RHSFUNC_ERR;
    return ERKStepEvolve(mem_, tout, s_.y, tret, mode);
  }

  static constexpr double kRhsShrink = 0.25;  // as DOP853 after a failure of f

  double stop_ = 0.0;
  void StopMoved(double t) override { stop_ = t; }
  // ERKStep's stop time: the caller's, or the next output instant before it.
  double Stop() const { return std::min(stop_, row_stop_); }
  double rtol_ = 0.0, atol_ = 0.0;   // the error test's tolerances (MeasureDrift)
  DriftWatch watch_;                 // MeasureDrift (sundials_util.h)
  bool hooked_ = false;              // Accepted() is installed (after the first restart)
  double reset_at_ = -INFINITY;      // t_accepted_ of the last ResetAfterErrorTest
  double t_accepted_ = 0.0;          // restart point: the last output instant, or once
  std::vector<double> y_accepted_;   // hooked the last accepted step; its state  (n)
  IntegratorStats before_restarts_;  // counters of the ERKStep runs before the last restart
};

}  // namespace

std::unique_ptr<Stepper> MakeArkodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                           const IntegratorOptions& options, std::string* error) {
  return MakeSundialsStepper<ArkodeStepper>(rhs, t0, y0, stop, options, error);
}

}  // namespace kanesim::sim::detail
