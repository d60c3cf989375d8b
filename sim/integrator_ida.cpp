// IDA on the residual F(t, y, y') = y' - f(t, y) (an ODE written as an implicit system
// so that the same solver serves the DAE formulations later).
//
// Newton matrix (IDA user guide, "IDALS"):   J = dF/dy + cj dF/dy' = cj I - df/dy,
// where cj = alpha_0 / h is IDA's BDF coefficient. df/dy comes from grouped difference
// quotients (sim/dq_jacobian.h, shared with CVODE-BDF: the block structure of
// options.coupling, IDA's increment rule, the partition held and the known columns of the
// states f does not read on closed loops on the reduced form). J is factored by dense LU
// or by KLU on the fixed block pattern (symbolic analysis once, numeric refactorization
// afterwards).
#include <ida/ida.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sim/dq_jacobian.h"
#include "sim/newton_krylov.h"
#include "sim/stepper.h"
#include "sim/sundials_util.h"

namespace kanesim::sim::detail {
namespace {

constexpr ModuleFunctions kIda{
    .module = "IDA",
    .err_handler = IDASetErrHandlerFn,
    .tolerances = IDASStolerances,
    .user_data = IDASetUserData,
    .stop_time = IDASetStopTime,
    .max_num_steps = IDASetMaxNumSteps,
    .max_step = IDASetMaxStep,
    .init_step = IDASetInitStep,
    .current_time = IDAGetCurrentTime,
    .dky = IDAGetDky,
    .free = IDAFree,
    .flag_name = IDAGetReturnFlagName,
    .num_steps = IDAGetNumSteps,
    .num_rhs_evals = IDAGetNumResEvals,
    .num_err_test_fails = IDAGetNumErrTestFails,
    .last_step = IDAGetLastStep,
    .num_lin_setups = IDAGetNumLinSolvSetups,
    .num_nonlin_iters = IDAGetNumNonlinSolvIters,
    .num_nonlin_conv_fails = IDAGetNumNonlinSolvConvFails,
    .last_order = IDAGetLastOrder,
    .num_jac_evals = IDAGetNumJacEvals,
    .num_lin_rhs_evals = IDAGetNumLinResEvals,
    .current_step = IDAGetCurrentStep
};

class IdaStepper final : public SundialsStepper {
 public:
  explicit IdaStepper(GuardedRhs& rhs) : SundialsStepper(rhs, kIda) {}
  ~IdaStepper() override {
    if (ewt_) N_VDestroy(ewt_);
  }

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    const int n = rhs_.Size();
    if (!MakeState(y0, /*with_yp=*/true, error)) return false;
    const double* y = N_VGetArrayPointer(s_.y);
    // Consistent y'(t0) = f(t0, y0): no IDACalcIC needed for an ODE.
    if (rhs_(t0, y, N_VGetArrayPointer(s_.yp)) != 0) return Fail(error, rhs_.cause);
    mem_ = IDACreate(s_.ctx);
    if (!mem_) return Fail(error, "IDACreate failed");
    if (CaptureMessages() != IDA_SUCCESS || IDAInit(mem_, &IdaStepper::Residual, t0, s_.y, s_.yp) != IDA_SUCCESS)
      return Fail(error, WithDetail("IDA setup failed", messages_.last));
    if (!SetCommonOptions(stop, options, error)) return false;
    if (!InitRoots([&](int count) { return IDARootInit(mem_, count, &SundialsStepper::RootsIda); },
                   [&](int* d) { return IDASetRootDirection(mem_, d) | IDASetNoInactiveRootWarn(mem_); }, error))
      return false;
    dq_.Build(n, options.coupling, DqJacobian::Increment::kIda);
    nnz_ = dq_.Nonzeros();
    f0_.assign(static_cast<size_t>(n), 0.0);
    int maxl = 0;
    krylov_ = UseKrylov(options, rhs_, &maxl);  // matrix-free: sim/newton_krylov.h
    if (krylov_) {
      s_.ls = MakeKrylovSolver(s_.y, maxl, s_.ctx);
      if (!s_.ls || IDASetLinearSolver(mem_, s_.ls, nullptr) != IDA_SUCCESS)
        return Fail(error, WithDetail("IDA Krylov linear solver setup failed", messages_.last));
    } else {
      const double fill = static_cast<double>(nnz_) / (static_cast<double>(n) * n);
      klu_ = options.ida_linear_solver == IdaLinearSolver::Klu ||
             (options.ida_linear_solver == IdaLinearSolver::Auto && n >= kKluMinStates && fill <= kKluMaxFill);
      dq_.SetLayout(klu_);
      if (klu_) {
        s_.A = SUNSparseMatrix(n, n, nnz_, CSC_MAT, s_.ctx);
        s_.ls = s_.A ? SUNLinSol_KLU(s_.y, s_.A, s_.ctx) : nullptr;
      } else {
        s_.A = SUNDenseMatrix(n, n, s_.ctx);
        s_.ls = s_.A ? SUNLinSol_Dense(s_.y, s_.A, s_.ctx) : nullptr;
      }
      if (!s_.ls || IDASetLinearSolver(mem_, s_.ls, s_.A) != IDA_SUCCESS)
        return Fail(error, WithDetail(klu_ ? "IDA KLU linear solver setup failed" : "IDA dense linear solver setup failed",
                                      messages_.last));
      if (IDASetJacFn(mem_, &IdaStepper::Jacobian) != IDA_SUCCESS)
        return Fail(error, WithDetail("IDASetJacFn failed", messages_.last));
    }
    ewt_ = N_VNew_Serial(n, s_.ctx);
    if (!ewt_) return Fail(error, "out of memory");
    // Closed loops on the reduced form (the states the projection sets: f's evaluation at y0
    // above chose the partition).
    bool reduced_loops = false;
    if (rhs_.ChecksSteps()) {
      GuardedRhs::JacobianHold hold(rhs_);
      double pdiag = 0.0;
      reduced_loops = rhs_.ProjectedStates(&projected_, &pdiag);
    }
    if (reduced_loops && IDASetNonlinConvCoef(mem_, kLoopConvCoef) != IDA_SUCCESS)
      return Fail(error, WithDetail("IDASetNonlinConvCoef failed", messages_.last));
    return true;
  }

  int Advance(double tout, double* y) override {
    double tret = 0.0;
    if (!StepsOneByOne()) {
      for (;;) {  // (a graze guard that found no dip: on)
        const int flag = IDASolve(mem_, tout, &tret, s_.y, s_.yp, IDA_NORMAL);
        if (flag != IDA_ROOT_RETURN) return CopyOut(flag, y);
        if (int r = EventReached(tret, y, [&](int* f) { IDAGetRootInfo(mem_, f); }); r != kNoEvent) return r;
      }
    }
    return AdvanceCheckedSteps(
        tout, y, [&](double* t) { return IDASolve(mem_, tout, t, s_.y, s_.yp, IDA_ONE_STEP); },
        [&](int* f) { IDAGetRootInfo(mem_, f); });
  }

  IntegratorStats Stats() const override {
    IntegratorStats st = SundialsStepper::Stats();
    st.rhs_evals_jac += dq_.Evaluations();  // our own difference quotients (FormJacobian)
    st.linear_solver = klu_ ? "KLU" : "dense LU";
    st.jac_nonzeros = nnz_;
    if (krylov_) {
      st.linear_solver = kKrylovName;
      st.jac_nonzeros = 0;
      IDAGetNumLinIters(mem_, &st.lin_iters);
      IDAGetNumLinConvFails(mem_, &st.lin_conv_fails);
    }
    return st;
  }

 private:
  FailureKind Kind(int flag) const override {
    switch (flag) {
      case IDA_RES_FAIL:
      case IDA_REP_RES_ERR:
      case IDA_FIRST_RES_FAIL: return FailureKind::kRhs;
      case IDA_TOO_MUCH_WORK: return FailureKind::kTooMuchWork;
      case IDA_TOO_MUCH_ACC: return FailureKind::kTooMuchAccuracy;
      case IDA_ERR_FAIL: return FailureKind::kErrorTest;
      case IDA_CONV_FAIL: return FailureKind::kConvergence;
      case IDA_LSETUP_FAIL:
      case IDA_LSOLVE_FAIL: return FailureKind::kLinearSolver;
      default: return FailureKind::kOther;
    }
  }

  static int Residual(double t, N_Vector yy, N_Vector yp, N_Vector rr, void* user_data) {
    auto* self = static_cast<IdaStepper*>(static_cast<SundialsStepper*>(user_data));
    double* r = N_VGetArrayPointer(rr);
    int status = self->rhs_(t, N_VGetArrayPointer(yy), r);  // r = f(t, y)
    if (status != 0) return status;
    const double* ypd = N_VGetArrayPointer(yp);
    for (int i = 0, n = self->rhs_.Size(); i < n; ++i) r[i] = ypd[i] - r[i];  // F = y' - f
    return 0;
  }

  // J = cj I - df/dy by grouped difference quotients; f(t, y) = y' - F(t, y, y').
  static int Jacobian(double t, double cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J, void* user_data,
                      N_Vector, N_Vector, N_Vector) {
    auto* self = static_cast<IdaStepper*>(static_cast<SundialsStepper*>(user_data));
    return self->FormJacobian(t, cj, N_VGetArrayPointer(yy), N_VGetArrayPointer(yp), N_VGetArrayPointer(rr), J);
  }

  int FormJacobian(double t, double cj, const double* y, const double* yp, const double* r, SUNMatrix J) {
    const int n = rhs_.Size();
    long nst = 0, ncf = 0, netf = 0;
    IDAGetNumSteps(mem_, &nst);
    IDAGetNumNonlinSolvConvFails(mem_, &ncf);
    IDAGetNumErrTestFails(mem_, &netf);
    // IDA forms J at every linear setup (a new cj after a step-size change, a Newton
    // failure); CVODE keeps df/dy across them. Where df/dy costs many evaluations, do so:
    // the last df/dy with the new cj, unless a step failed since or it is kMaxReuseSteps
    // old. Unlike CVODE (a fresh one after Newton failures only), also after error-test
    // failures: without, the chain of 40 at rtol 1e-12 (multiplier form) crept in a zone
    // and stopped at t = 3.17 (docs/constraints.md).
    if (reuse_ok_ && ncf == jac_ncf_ && netf == jac_netf_ && nst - jac_nst_ < kMaxReuseSteps) {
      ++jac_reused_;
      dq_.WriteNewton(cj, J);
      return 0;
    }
    jac_nst_ = nst;
    jac_ncf_ = ncf;
    jac_netf_ = netf;
    const long evals_before = dq_.Evaluations();
    double h = 0.0;
    IDAGetCurrentStep(mem_, &h);
    IDAGetErrWeights(mem_, ewt_);
    for (int i = 0; i < n; ++i) f0_[static_cast<size_t>(i)] = yp[i] - r[i];
    const int status = dq_.Form(rhs_, t, y, yp, f0_.data(), h, N_VGetArrayPointer(ewt_));
    if (status != 0) return status;  // > 0: IDA retries with a smaller step
    dq_.WriteNewton(cj, J);
    reuse_ok_ = dq_.Evaluations() - evals_before >= kReuseMinEvals;
    return 0;
  }

  // The Newton iteration's convergence coefficient (IDA's epsNewt, default 0.33) on closed
  // loops on the reduced form: near a change point f has a noise floor that the default rate
  // test mistakes for divergence, cutting the step again and again (measurements: docs/constraints/2026-11-28_tuning_measurements.md).
  // Set before the first step: IDA copies it at its initial setup only.
  static constexpr double kLoopConvCoef = 1.0;
  // df/dy reused only where it costs at least kReuseMinEvals evaluations (not on the
  // reduced form's closed loops, 2 per Jacobian), for fewer than kMaxReuseSteps steps.
  static constexpr long kReuseMinEvals = 16;
  static constexpr long kMaxReuseSteps = 20;
  DqJacobian dq_;
  bool reuse_ok_ = false;
  long jac_nst_ = 0, jac_ncf_ = 0, jac_netf_ = 0, jac_reused_ = 0;
  std::vector<int> projected_;
  N_Vector ewt_ = nullptr;
  bool klu_ = false;
  bool krylov_ = false;  // matrix-free GMRES (UseKrylov)
  sunindextype nnz_ = 0;
  std::vector<double> f0_;  // f(t, y) = y' - F
};

}  // namespace

std::unique_ptr<Stepper> MakeIdaStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                        const IntegratorOptions& options, std::string* error) {
  return MakeSundialsStepper<IdaStepper>(rhs, t0, y0, stop, options, error);
}

}  // namespace kanesim::sim::detail
