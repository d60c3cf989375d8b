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

constexpr ModuleSetters kCvode{"CVODE",           CVodeSStolerances,   CVodeSetUserData, CVodeSetStopTime,
                               CVodeSetMaxNumSteps, CVodeSetMaxStep,     CVodeSetInitStep};

class CvodeStepper final : public SundialsStepper {
 public:
  explicit CvodeStepper(GuardedRhs& rhs) : SundialsStepper(rhs) {}
  ~CvodeStepper() override {
    if (mem_) CVodeFree(&mem_);
  }

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    const int n = rhs_.Size();
    const bool bdf = options.method == Method::CvodeBdf;
    if (!MakeState(y0, /*with_yp=*/false, error)) return false;
    mem_ = CVodeCreate(bdf ? CV_BDF : CV_ADAMS, s_.ctx);
    if (!mem_) return Fail(error, "CVodeCreate failed");
    if (CVodeSetErrHandlerFn(mem_, CaptureSundialsMessage, &messages_) != CV_SUCCESS ||
        CVodeInit(mem_, &CvodeStepper::Rhs, t0, s_.y) != CV_SUCCESS)
      return Fail(error, WithDetail("CVODE setup failed", messages_.last));
    if (!SetCommonOptions(kCvode, stop, options, error)) return false;
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
    // One step at a time, each checked (OdeSystem::StepAccepted), then the output instant
    // from CVODE's interpolant, as in CV_NORMAL mode.
    for (;;) {
      if (stepped_ && CurrentTime() >= tout) return CopyOut(CVodeGetDky(mem_, tout, 0, s_.y), y);
      const int flag = CVode(mem_, tout, s_.y, &tret, CV_ONE_STEP);
      if (flag < 0) return flag;
      stepped_ = true;
      if (rhs_.StepAccepted(tret, N_VGetArrayPointer(s_.y)) != 0) return kStepCheckFailed;
    }
  }

  double CurrentTime() const override {
    double t = 0.0;
    CVodeGetCurrentTime(mem_, &t);
    return t;
  }

  IntegratorStats Stats() const override {
    IntegratorStats st;
    CVodeGetNumSteps(mem_, &st.steps);
    CVodeGetNumRhsEvals(mem_, &st.rhs_evals);
    CVodeGetNumLinSolvSetups(mem_, &st.lin_setups);
    CVodeGetNumErrTestFails(mem_, &st.err_test_fails);
    CVodeGetNumNonlinSolvIters(mem_, &st.nonlin_iters);
    CVodeGetNumNonlinSolvConvFails(mem_, &st.nonlin_conv_fails);
    CVodeGetLastStep(mem_, &st.last_step);
    CVodeGetLastOrder(mem_, &st.last_order);
    if (s_.ls) {
      CVodeGetNumJacEvals(mem_, &st.jac_evals);
      CVodeGetNumLinRhsEvals(mem_, &st.rhs_evals_jac);
    }
    return st;
  }

  StepFailure Explain(int flag) const override {
    FailureKind kind = FailureKind::kOther;
    switch (flag) {
      case CV_RHSFUNC_FAIL:
      case CV_FIRST_RHSFUNC_ERR:
      case CV_REPTD_RHSFUNC_ERR:
      case CV_UNREC_RHSFUNC_ERR:
      case kStepCheckFailed: kind = FailureKind::kRhs; break;
      case CV_TOO_MUCH_WORK: kind = FailureKind::kTooMuchWork; break;
      case CV_TOO_MUCH_ACC: kind = FailureKind::kTooMuchAccuracy; break;
      case CV_ERR_FAILURE: kind = FailureKind::kErrorTest; break;
      case CV_CONV_FAILURE: kind = FailureKind::kConvergence; break;
      case CV_LSETUP_FAIL:
      case CV_LSOLVE_FAIL: kind = FailureKind::kLinearSolver; break;
      default: break;
    }
    return Describe(kind, "CVODE", CVodeGetReturnFlagName, flag);
  }

 private:
  static int Rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<CvodeStepper*>(user_data);
    return self->rhs_(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  }
};

}  // namespace

std::unique_ptr<Stepper> MakeCvodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                          const IntegratorOptions& options, std::string* error) {
  auto stepper = std::make_unique<CvodeStepper>(rhs);
  if (!stepper->Init(t0, y0, stop, options, error)) return nullptr;
  return stepper;
}

}  // namespace kanesim::sim::detail
