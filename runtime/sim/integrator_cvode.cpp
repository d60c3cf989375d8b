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

class CvodeStepper final : public Stepper {
 public:
  explicit CvodeStepper(GuardedRhs& rhs) : rhs_(rhs) {}
  ~CvodeStepper() override {
    if (mem_) CVodeFree(&mem_);
  }

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    int n = rhs_.Size();
    bool bdf = options.method == Method::CvodeBdf;
    if (!s_.ok()) return Fail(error, "SUNContext_Create failed");
    s_.y = N_VNew_Serial(n, s_.ctx);
    if (!s_.y) return Fail(error, "out of memory");
    double* y = N_VGetArrayPointer(s_.y);
    for (int i = 0; i < n; ++i) y[i] = y0[i];
    mem_ = CVodeCreate(bdf ? CV_BDF : CV_ADAMS, s_.ctx);
    if (!mem_) return Fail(error, "CVodeCreate failed");
    if (CVodeSetErrHandlerFn(mem_, CaptureSundialsMessage, &messages_) != CV_SUCCESS ||
        CVodeInit(mem_, &CvodeStepper::Rhs, t0, s_.y) != CV_SUCCESS ||
        CVodeSStolerances(mem_, options.rtol, options.atol) != CV_SUCCESS ||
        CVodeSetUserData(mem_, this) != CV_SUCCESS || CVodeSetStopTime(mem_, stop) != CV_SUCCESS ||
        CVodeSetMaxNumSteps(mem_, options.max_steps) != CV_SUCCESS)
      return Fail(error, WithDetail("CVODE setup failed", messages_.last));
    if (options.max_step > 0.0 && CVodeSetMaxStep(mem_, options.max_step) != CV_SUCCESS)
      return Fail(error, WithDetail("CVodeSetMaxStep failed", messages_.last));
    if (options.initial_step > 0.0 && CVodeSetInitStep(mem_, options.initial_step) != CV_SUCCESS)
      return Fail(error, WithDetail("CVodeSetInitStep failed", messages_.last));
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
    int flag = CVode(mem_, tout, s_.y, &tret, CV_NORMAL);
    if (flag >= 0) {
      const double* ys = N_VGetArrayPointer(s_.y);
      for (int i = 0, n = rhs_.Size(); i < n; ++i) y[i] = ys[i];
    }
    return flag;
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
    const std::string& d = messages_.last;
    switch (flag) {
      case CV_RHSFUNC_FAIL:
      case CV_FIRST_RHSFUNC_ERR:
      case CV_REPTD_RHSFUNC_ERR:
      case CV_UNREC_RHSFUNC_ERR: return {true, WithDetail("the right-hand side failed", d)};
      case CV_TOO_MUCH_WORK: return {false, WithDetail("too much work (step limit reached between output instants)", d)};
      case CV_TOO_MUCH_ACC: return {false, WithDetail("too much accuracy requested", d)};
      case CV_ERR_FAILURE: return {false, WithDetail("step size underflow: the error test failed repeatedly", d)};
      case CV_CONV_FAILURE: return {false, WithDetail("the corrector iteration failed to converge repeatedly", d)};
      case CV_LSETUP_FAIL:
      case CV_LSOLVE_FAIL: return {false, WithDetail("the linear solver failed (singular Newton matrix)", d)};
      default: return {false, WithDetail(std::string("CVODE failed: ") + CVodeGetReturnFlagName(flag), d)};
    }
  }

 private:
  static int Rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<CvodeStepper*>(user_data);
    return self->rhs_(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  }

  static bool Fail(std::string* error, const std::string& what) {
    *error = what;
    return false;
  }

  GuardedRhs& rhs_;
  SundialsObjects s_;
  SundialsMessages messages_;
  void* mem_ = nullptr;
};

}  // namespace

std::unique_ptr<Stepper> MakeCvodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                          const IntegratorOptions& options, std::string* error) {
  auto stepper = std::make_unique<CvodeStepper>(rhs);
  if (!stepper->Init(t0, y0, stop, options, error)) return nullptr;
  return stepper;
}

}  // namespace kanesim::sim::detail
