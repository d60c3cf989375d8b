// ARKODE's ERKStep on y' = f(t, y): an explicit embedded Runge-Kutta pair with
// adaptive steps; output instants from its Hermite interpolant (degree 5).
#include <arkode/arkode_erkstep.h>

#include <memory>
#include <string>

#include "runtime/sim/stepper.h"
#include "runtime/sim/sundials_util.h"

namespace kanesim::sim::detail {
namespace {

constexpr ModuleSetters kArkode{"ARKODE",           ERKStepSStolerances,   ERKStepSetUserData, ERKStepSetStopTime,
                                ERKStepSetMaxNumSteps, ERKStepSetMaxStep,     ERKStepSetInitStep};

class ArkodeStepper final : public SundialsStepper {
 public:
  explicit ArkodeStepper(GuardedRhs& rhs) : SundialsStepper(rhs) {}
  ~ArkodeStepper() override {
    if (mem_) ERKStepFree(&mem_);
  }

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    if (!MakeState(y0, /*with_yp=*/false, error)) return false;
    mem_ = ERKStepCreate(&ArkodeStepper::Rhs, t0, s_.y, s_.ctx);
    if (!mem_) return Fail(error, "ERKStepCreate failed");
    ARKODE_ERKTableID table =
        options.erk_table == ErkTable::Fehlberg87 ? ARKODE_FEHLBERG_13_7_8 : ARKODE_VERNER_8_5_6;
    if (ERKStepSetErrHandlerFn(mem_, CaptureSundialsMessage, &messages_) != ARK_SUCCESS ||
        ERKStepSetTableNum(mem_, table) != ARK_SUCCESS ||
        ERKStepSetInterpolantDegree(mem_, ARK_INTERP_MAX_DEGREE) != ARK_SUCCESS)
      return Fail(error, WithDetail("ARKODE setup failed", messages_.last));
    return SetCommonOptions(kArkode, stop, options, error);
  }

  int Advance(double tout, double* y) override {
    double tret = 0.0;
    return CopyOut(ERKStepEvolve(mem_, tout, s_.y, &tret, ARK_NORMAL), y);
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
    FailureKind kind = FailureKind::kOther;
    switch (flag) {
      case ARK_RHSFUNC_FAIL:
      case ARK_FIRST_RHSFUNC_ERR:
      case ARK_REPTD_RHSFUNC_ERR:
      case ARK_UNREC_RHSFUNC_ERR: kind = FailureKind::kRhs; break;
      case ARK_TOO_MUCH_WORK: kind = FailureKind::kTooMuchWork; break;
      case ARK_TOO_MUCH_ACC: kind = FailureKind::kTooMuchAccuracy; break;
      case ARK_ERR_FAILURE: kind = FailureKind::kErrorTest; break;
      default: break;
    }
    return Describe(kind, "ARKODE", ERKStepGetReturnFlagName, flag);
  }

 private:
  static int Rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<ArkodeStepper*>(user_data);
    return self->rhs_(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  }
};

}  // namespace

std::unique_ptr<Stepper> MakeArkodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                           const IntegratorOptions& options, std::string* error) {
  auto stepper = std::make_unique<ArkodeStepper>(rhs);
  if (!stepper->Init(t0, y0, stop, options, error)) return nullptr;
  return stepper;
}

}  // namespace kanesim::sim::detail
