// IDA on the residual F(t, y, y') = y' - f(t, y) (an ODE written as an implicit system
// so that the same solver serves the DAE formulations later).
//
// Newton matrix (IDA user guide, "IDALS"):   J = dF/dy + cj dF/dy' = cj I - df/dy,
// where cj = alpha_0 / h is IDA's BDF coefficient. df/dy is formed by IDA's difference
// quotients (n extra evaluations of f per Jacobian) and factored by the dense LU; see
// integrator.h for why not KLU.
#include <ida/ida.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <memory>
#include <string>

#include "runtime/sim/stepper.h"
#include "runtime/sim/sundials_util.h"

namespace kanesim::sim::detail {
namespace {

class IdaStepper final : public Stepper {
 public:
  explicit IdaStepper(GuardedRhs& rhs) : rhs_(rhs) {}
  ~IdaStepper() override {
    if (mem_) IDAFree(&mem_);
  }

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    int n = rhs_.Size();
    if (!s_.ok()) return Fail(error, "SUNContext_Create failed");
    s_.y = N_VNew_Serial(n, s_.ctx);
    s_.yp = N_VNew_Serial(n, s_.ctx);
    if (!s_.y || !s_.yp) return Fail(error, "out of memory");
    double* y = N_VGetArrayPointer(s_.y);
    for (int i = 0; i < n; ++i) y[i] = y0[i];
    // Consistent y'(t0) = f(t0, y0): no IDACalcIC needed for an ODE.
    if (rhs_(t0, y, N_VGetArrayPointer(s_.yp)) != 0) return Fail(error, rhs_.cause);
    mem_ = IDACreate(s_.ctx);
    if (!mem_) return Fail(error, "IDACreate failed");
    if (IDASetErrHandlerFn(mem_, CaptureSundialsMessage, &messages_) != IDA_SUCCESS ||
        IDAInit(mem_, &IdaStepper::Residual, t0, s_.y, s_.yp) != IDA_SUCCESS ||
        IDASStolerances(mem_, options.rtol, options.atol) != IDA_SUCCESS ||
        IDASetUserData(mem_, this) != IDA_SUCCESS || IDASetStopTime(mem_, stop) != IDA_SUCCESS ||
        IDASetMaxNumSteps(mem_, options.max_steps) != IDA_SUCCESS)
      return Fail(error, WithDetail("IDA setup failed", messages_.last));
    if (options.max_step > 0.0 && IDASetMaxStep(mem_, options.max_step) != IDA_SUCCESS)
      return Fail(error, WithDetail("IDASetMaxStep failed", messages_.last));
    if (options.initial_step > 0.0 && IDASetInitStep(mem_, options.initial_step) != IDA_SUCCESS)
      return Fail(error, WithDetail("IDASetInitStep failed", messages_.last));
    s_.A = SUNDenseMatrix(n, n, s_.ctx);
    s_.ls = s_.A ? SUNLinSol_Dense(s_.y, s_.A, s_.ctx) : nullptr;
    if (!s_.ls || IDASetLinearSolver(mem_, s_.ls, s_.A) != IDA_SUCCESS)
      return Fail(error, WithDetail("IDA dense linear solver setup failed", messages_.last));
    return true;
  }

  int Advance(double tout, double* y) override {
    double tret = 0.0;
    int flag = IDASolve(mem_, tout, &tret, s_.y, s_.yp, IDA_NORMAL);
    if (flag >= 0) {
      const double* ys = N_VGetArrayPointer(s_.y);
      for (int i = 0, n = rhs_.Size(); i < n; ++i) y[i] = ys[i];
    }
    return flag;
  }

  double CurrentTime() const override {
    double t = 0.0;
    IDAGetCurrentTime(mem_, &t);
    return t;
  }

  IntegratorStats Stats() const override {
    IntegratorStats st;
    long nje = 0, nreLS = 0;
    IDAGetNumSteps(mem_, &st.steps);
    IDAGetNumResEvals(mem_, &st.rhs_evals);
    IDAGetNumLinSolvSetups(mem_, &st.lin_setups);
    IDAGetNumErrTestFails(mem_, &st.err_test_fails);
    IDAGetNumNonlinSolvIters(mem_, &st.nonlin_iters);
    IDAGetNumNonlinSolvConvFails(mem_, &st.nonlin_conv_fails);
    IDAGetNumJacEvals(mem_, &nje);
    IDAGetNumLinResEvals(mem_, &nreLS);
    IDAGetLastStep(mem_, &st.last_step);
    IDAGetLastOrder(mem_, &st.last_order);
    st.jac_evals = nje;
    st.rhs_evals_jac = nreLS;
    return st;
  }

  StepFailure Explain(int flag) const override {
    const std::string& d = messages_.last;
    switch (flag) {
      case IDA_RES_FAIL:
      case IDA_REP_RES_ERR:
      case IDA_FIRST_RES_FAIL: return {true, WithDetail("the right-hand side failed", d)};
      case IDA_TOO_MUCH_WORK: return {false, WithDetail("too much work (step limit reached between output instants)", d)};
      case IDA_TOO_MUCH_ACC: return {false, WithDetail("too much accuracy requested", d)};
      case IDA_ERR_FAIL: return {false, WithDetail("step size underflow: the error test failed repeatedly", d)};
      case IDA_CONV_FAIL: return {false, WithDetail("the Newton iteration failed to converge repeatedly", d)};
      case IDA_LSETUP_FAIL:
      case IDA_LSOLVE_FAIL: return {false, WithDetail("the linear solver failed (singular Newton matrix)", d)};
      default: return {false, WithDetail(std::string("IDA failed: ") + IDAGetReturnFlagName(flag), d)};
    }
  }

 private:
  static int Residual(double t, N_Vector yy, N_Vector yp, N_Vector rr, void* user_data) {
    auto* self = static_cast<IdaStepper*>(user_data);
    double* r = N_VGetArrayPointer(rr);
    int status = self->rhs_(t, N_VGetArrayPointer(yy), r);  // r = f(t, y)
    if (status != 0) return status;
    const double* ypd = N_VGetArrayPointer(yp);
    for (int i = 0, n = self->rhs_.Size(); i < n; ++i) r[i] = ypd[i] - r[i];  // F = y' - f
    return 0;
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

std::unique_ptr<Stepper> MakeIdaStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                        const IntegratorOptions& options, std::string* error) {
  auto stepper = std::make_unique<IdaStepper>(rhs);
  if (!stepper->Init(t0, y0, stop, options, error)) return nullptr;
  return stepper;
}

}  // namespace kanesim::sim::detail
