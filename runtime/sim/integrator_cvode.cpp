// CVODE on y' = f(t, y): Adams-Moulton with fixed-point iteration (non-stiff, no
// Jacobian), or BDF with Newton iteration on M = I - gamma df/dy, where df/dy is formed
// by CVODE's difference quotients and M is factored by the dense LU.
#include <cvode/cvode.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <memory>
#include <string>

#include "runtime/sim/stepper.h"
#include "runtime/sim/sundials_util.h"

namespace kanesim::sim::detail {
namespace {

constexpr ModuleFunctions kCvode{
    .module = "CVODE",
    .err_handler = CVodeSetErrHandlerFn,
    .tolerances = CVodeSStolerances,
    .user_data = CVodeSetUserData,
    .stop_time = CVodeSetStopTime,
    .max_num_steps = CVodeSetMaxNumSteps,
    .max_step = CVodeSetMaxStep,
    .init_step = CVodeSetInitStep,
    .current_time = CVodeGetCurrentTime,
    .dky = CVodeGetDky,
    .free = CVodeFree,
    .flag_name = CVodeGetReturnFlagName,
    .num_steps = CVodeGetNumSteps,
    .num_rhs_evals = CVodeGetNumRhsEvals,
    .num_err_test_fails = CVodeGetNumErrTestFails,
    .last_step = CVodeGetLastStep,
    .num_lin_setups = CVodeGetNumLinSolvSetups,
    .num_nonlin_iters = CVodeGetNumNonlinSolvIters,
    .num_nonlin_conv_fails = CVodeGetNumNonlinSolvConvFails,
    .last_order = CVodeGetLastOrder,
    .num_jac_evals = CVodeGetNumJacEvals,
    .num_lin_rhs_evals = CVodeGetNumLinRhsEvals
};

class CvodeStepper final : public SundialsStepper {
 public:
  explicit CvodeStepper(GuardedRhs& rhs) : SundialsStepper(rhs, kCvode) {}

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    const int n = rhs_.Size();
    const bool bdf = options.method == Method::CvodeBdf;
    if (!MakeState(y0, /*with_yp=*/false, error)) return false;
    mem_ = CVodeCreate(bdf ? CV_BDF : CV_ADAMS, s_.ctx);
    if (!mem_) return Fail(error, "CVodeCreate failed");
    if (CaptureMessages() != CV_SUCCESS || CVodeInit(mem_, &CvodeStepper::Rhs, t0, s_.y) != CV_SUCCESS)
      return Fail(error, WithDetail("CVODE setup failed", messages_.last));
    if (!SetCommonOptions(stop, options, error)) return false;
    if (bdf) {
      s_.A = SUNDenseMatrix(n, n, s_.ctx);
      s_.ls = s_.A ? SUNLinSol_Dense(s_.y, s_.A, s_.ctx) : nullptr;
      if (!s_.ls || CVodeSetLinearSolver(mem_, s_.ls, s_.A) != CV_SUCCESS)
        return Fail(error, WithDetail("CVODE dense linear solver setup failed", messages_.last));
    } else {
      s_.nls = SUNNonlinSol_FixedPoint(s_.y, 0, s_.ctx);
      if (!s_.nls || CVodeSetNonlinearSolver(mem_, s_.nls) != CV_SUCCESS)
        return Fail(error, WithDetail("CVODE fixed-point solver setup failed", messages_.last));
    }
    return true;
  }

  int Advance(double tout, double* y) override {
    double tret = 0.0;
    if (!rhs_.ChecksSteps()) return CopyOut(CVode(mem_, tout, s_.y, &tret, CV_NORMAL), y);
    return AdvanceCheckedSteps(tout, y, [&](double* t) { return CVode(mem_, tout, s_.y, t, CV_ONE_STEP); });
  }

 private:
  FailureKind Kind(int flag) const override {
    switch (flag) {
      case CV_RHSFUNC_FAIL:
      case CV_FIRST_RHSFUNC_ERR:
      case CV_REPTD_RHSFUNC_ERR:
      case CV_UNREC_RHSFUNC_ERR: return FailureKind::kRhs;
      case CV_TOO_MUCH_WORK: return FailureKind::kTooMuchWork;
      case CV_TOO_MUCH_ACC: return FailureKind::kTooMuchAccuracy;
      case CV_ERR_FAILURE: return FailureKind::kErrorTest;
      case CV_CONV_FAILURE: return FailureKind::kConvergence;
      case CV_LSETUP_FAIL:
      case CV_LSOLVE_FAIL: return FailureKind::kLinearSolver;
      default: return FailureKind::kOther;
    }
  }
};

}  // namespace

std::unique_ptr<Stepper> MakeCvodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                          const IntegratorOptions& options, std::string* error) {
  return MakeSundialsStepper<CvodeStepper>(rhs, t0, y0, stop, options, error);
}

}  // namespace kanesim::sim::detail
