// ARKODE's ERKStep on y' = f(t, y): an explicit embedded Runge-Kutta pair with
// adaptive steps; output instants from its Hermite interpolant (degree 5).
#include <arkode/arkode_erkstep.h>

#include <memory>
#include <string>

#include "runtime/sim/stepper.h"
#include "runtime/sim/sundials_util.h"

namespace kanesim::sim::detail {
namespace {

class ArkodeStepper final : public Stepper {
 public:
  explicit ArkodeStepper(GuardedRhs& rhs) : rhs_(rhs) {}
  ~ArkodeStepper() override {
    if (mem_) ERKStepFree(&mem_);
  }

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    int n = rhs_.Size();
    if (!s_.ok()) return Fail(error, "SUNContext_Create failed");
    s_.y = N_VNew_Serial(n, s_.ctx);
    if (!s_.y) return Fail(error, "out of memory");
    double* y = N_VGetArrayPointer(s_.y);
    for (int i = 0; i < n; ++i) y[i] = y0[i];
    mem_ = ERKStepCreate(&ArkodeStepper::Rhs, t0, s_.y, s_.ctx);
    if (!mem_) return Fail(error, "ERKStepCreate failed");
    ARKODE_ERKTableID table =
        options.erk_table == ErkTable::Fehlberg87 ? ARKODE_FEHLBERG_13_7_8 : ARKODE_VERNER_8_5_6;
    if (ERKStepSetErrHandlerFn(mem_, CaptureSundialsMessage, &messages_) != ARK_SUCCESS ||
        ERKStepSStolerances(mem_, options.rtol, options.atol) != ARK_SUCCESS ||
        ERKStepSetUserData(mem_, this) != ARK_SUCCESS || ERKStepSetTableNum(mem_, table) != ARK_SUCCESS ||
        ERKStepSetInterpolantDegree(mem_, ARK_INTERP_MAX_DEGREE) != ARK_SUCCESS ||
        ERKStepSetStopTime(mem_, stop) != ARK_SUCCESS ||
        ERKStepSetMaxNumSteps(mem_, options.max_steps) != ARK_SUCCESS)
      return Fail(error, WithDetail("ARKODE setup failed", messages_.last));
    if (options.max_step > 0.0 && ERKStepSetMaxStep(mem_, options.max_step) != ARK_SUCCESS)
      return Fail(error, WithDetail("ERKStepSetMaxStep failed", messages_.last));
    if (options.initial_step > 0.0 && ERKStepSetInitStep(mem_, options.initial_step) != ARK_SUCCESS)
      return Fail(error, WithDetail("ERKStepSetInitStep failed", messages_.last));
    return true;
  }

  int Advance(double tout, double* y) override {
    double tret = 0.0;
    int flag = ERKStepEvolve(mem_, tout, s_.y, &tret, ARK_NORMAL);
    if (flag >= 0) {
      const double* ys = N_VGetArrayPointer(s_.y);
      for (int i = 0, n = rhs_.Size(); i < n; ++i) y[i] = ys[i];
    }
    return flag;
  }

  double CurrentTime() const override {
    double t = 0.0;
    ERKStepGetCurrentTime(mem_, &t);
    return t;
  }

  IntegratorStats Stats() const override {
    IntegratorStats st;
    ERKStepGetNumSteps(mem_, &st.steps);
    ERKStepGetNumRhsEvals(mem_, &st.rhs_evals);
    ERKStepGetNumErrTestFails(mem_, &st.err_test_fails);
    ERKStepGetLastStep(mem_, &st.last_step);
    return st;
  }

  StepFailure Explain(int flag) const override {
    const std::string& d = messages_.last;
    switch (flag) {
      case ARK_RHSFUNC_FAIL:
      case ARK_FIRST_RHSFUNC_ERR:
      case ARK_REPTD_RHSFUNC_ERR:
      case ARK_UNREC_RHSFUNC_ERR: return {true, WithDetail("the right-hand side failed", d)};
      case ARK_TOO_MUCH_WORK: return {false, WithDetail("too much work (step limit reached between output instants)", d)};
      case ARK_TOO_MUCH_ACC: return {false, WithDetail("too much accuracy requested", d)};
      case ARK_ERR_FAILURE: return {false, WithDetail("step size underflow: the error test failed repeatedly", d)};
      default: return {false, WithDetail(std::string("ARKODE failed: ") + ERKStepGetReturnFlagName(flag), d)};
    }
  }

 private:
  static int Rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<ArkodeStepper*>(user_data);
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

std::unique_ptr<Stepper> MakeArkodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                           const IntegratorOptions& options, std::string* error) {
  auto stepper = std::make_unique<ArkodeStepper>(rhs);
  if (!stepper->Init(t0, y0, stop, options, error)) return nullptr;
  return stepper;
}

}  // namespace kanesim::sim::detail
