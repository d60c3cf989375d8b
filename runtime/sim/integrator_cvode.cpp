// CVODE on y' = f(t, y): Adams-Moulton with fixed-point iteration (non-stiff, no
// Jacobian), or BDF with Newton iteration on M = I - gamma df/dy, where df/dy is formed
// by difference quotients column by column (Jacobian below: CVODE's own rule for the
// increments, the system's discrete choices held across the columns, GuardedRhs::
// JacobianHold) and M is factored by the dense LU.
#include <cvode/cvode.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

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
  ~CvodeStepper() override {
    if (ewt_) N_VDestroy(ewt_);
  }

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
      if (CVodeSetJacFn(mem_, &CvodeStepper::Jacobian) != CV_SUCCESS)
        return Fail(error, WithDetail("CVodeSetJacFn failed", messages_.last));
      ewt_ = N_VNew_Serial(n, s_.ctx);
      if (!ewt_) return Fail(error, "out of memory");
      y1_.assign(static_cast<size_t>(n), 0.0);
      f1_.assign(static_cast<size_t>(n), 0.0);
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

  IntegratorStats Stats() const override {
    IntegratorStats st = SundialsStepper::Stats();
    st.rhs_evals_jac += jac_rhs_evals_;  // our own difference quotients (FormJacobian)
    return st;
  }

 private:
  static int Jacobian(double t, N_Vector y, N_Vector fy, SUNMatrix J, void* user_data, N_Vector, N_Vector,
                      N_Vector) {
    auto* self = static_cast<CvodeStepper*>(static_cast<SundialsStepper*>(user_data));
    return self->FormJacobian(t, N_VGetArrayPointer(y), fy, J);
  }

  // df/dy by forward differences, one column per evaluation of f, with CVODE's increments
  // (CVODE user guide, "Dense difference-quotient Jacobian"; h is the step being attempted,
  // which CVodeGetCurrentStep returns during the step):
  //   inc_j = max(sqrt(unit round-off) |y_j|, min_inc / w_j),
  //   min_inc = 1000 |h| unit round-off n ||f||_WRMS   (1 when f = 0),
  // with w the error weights. The last evaluation was at y (f(t, y) = fy, the Newton
  // iterate's): its discrete choices are held for the perturbed ones.
  int FormJacobian(double t, const double* y, N_Vector fy, SUNMatrix J) {
    const int n = rhs_.Size();
    constexpr double kUround = 2.220446049250313e-16;
    double h = 0.0;
    CVodeGetCurrentStep(mem_, &h);
    CVodeGetErrWeights(mem_, ewt_);
    const double* w = N_VGetArrayPointer(ewt_);
    const double* f0 = N_VGetArrayPointer(fy);
    const double fnorm = N_VWrmsNorm(fy, ewt_);
    const double min_inc = fnorm != 0.0 ? 1000.0 * std::fabs(h) * kUround * n * fnorm : 1.0;
    const double srur = std::sqrt(kUround);
    for (int i = 0; i < n; ++i) y1_[static_cast<size_t>(i)] = y[i];
    GuardedRhs::JacobianHold hold(rhs_);
    for (int j = 0; j < n; ++j) {
      const auto uj = static_cast<size_t>(j);
      const double inc = std::max(srur * std::fabs(y[j]), min_inc / w[j]);
      y1_[uj] = y[j] + inc;
      ++jac_rhs_evals_;
      const int status = rhs_(t, y1_.data(), f1_.data());
      y1_[uj] = y[j];
      if (status != 0) return status;  // > 0: CVODE retries with a smaller step
      // As CVODE's own (N_VLinearSum(1/inc, f1, -1/inc, f0) is (1/inc) (f1 - f0)): outside the
      // zones where a partition is re-chosen, the Jacobian is CVODE's to the bit.
      const double scale = 1.0 / inc;
      double* col = SUNDenseMatrix_Column(J, j);
      for (int i = 0; i < n; ++i) col[i] = scale * (f1_[static_cast<size_t>(i)] - f0[i]);
    }
    return 0;
  }

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

  N_Vector ewt_ = nullptr;
  std::vector<double> y1_, f1_;
  long jac_rhs_evals_ = 0;
};

}  // namespace

std::unique_ptr<Stepper> MakeCvodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                          const IntegratorOptions& options, std::string* error) {
  return MakeSundialsStepper<CvodeStepper>(rhs, t0, y0, stop, options, error);
}

}  // namespace kanesim::sim::detail
