// Internal to runtime/sim: ownership of the SUNDIALS objects every solver needs.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>

#include <string>

#include "runtime/sim/stepper.h"

namespace kanesim::sim::detail {

// A SUNContext plus the vectors, matrix and solvers made in it, freed in reverse order.
class SundialsObjects {
 public:
  SundialsObjects() { ok_ = SUNContext_Create(nullptr, &ctx) == 0; }
  ~SundialsObjects() {
    if (nls) SUNNonlinSolFree(nls);
    if (ls) SUNLinSolFree(ls);
    if (A) SUNMatDestroy(A);
    if (yp) N_VDestroy(yp);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }
  SundialsObjects(const SundialsObjects&) = delete;
  SundialsObjects& operator=(const SundialsObjects&) = delete;
  bool ok() const { return ok_; }

  SUNContext ctx = nullptr;
  N_Vector y = nullptr;   // state (and the solver's output)
  N_Vector yp = nullptr;  // IDA only: y'
  SUNMatrix A = nullptr;
  SUNLinearSolver ls = nullptr;
  SUNNonlinearSolver nls = nullptr;

 private:
  bool ok_ = false;
};

// "<what> [<SUNDIALS' own message>]" when SUNDIALS said something.
inline std::string WithDetail(const std::string& what, const std::string& detail) {
  return detail.empty() ? what : what + " [" + detail + "]";
}

// The optional inputs every SUNDIALS integrator module has, each under its own prefix
// (CVodeSet..., ERKStepSet..., IDASet...), with the same signatures.
struct ModuleSetters {
  const char* module;  // "CVODE", "ARKODE", "IDA": named in setup failures
  int (*tolerances)(void* mem, double rtol, double atol);
  int (*user_data)(void* mem, void* data);
  int (*stop_time)(void* mem, double t);
  int (*max_num_steps)(void* mem, long steps);
  int (*max_step)(void* mem, double h);
  int (*init_step)(void* mem, double h);
};

// Why an integrator module gave up, in the terms shared by CVODE, ARKODE and IDA; each
// stepper maps its own return flags onto these.
enum class FailureKind {
  kRhs,              // the right-hand side (or residual) failed: GuardedRhs has the time and cause
  kTooMuchWork,      // the step limit between output instants
  kTooMuchAccuracy,
  kErrorTest,        // repeated error-test failures: the step size underflowed
  kConvergence,      // repeated failures of the nonlinear (corrector or Newton) iteration
  kLinearSolver,     // the Newton matrix could not be set up or solved
  kOther,            // anything else: named by the module's own flag name
};

// One SUNDIALS solver behind the Stepper interface: the context and vectors, the captured
// messages, the guarded right-hand side, and the steps they all take alike.
class SundialsStepper : public Stepper {
 public:
  explicit SundialsStepper(GuardedRhs& rhs) : rhs_(rhs) {}

 protected:
  // s_.y (and s_.yp when with_yp) of the right-hand side's size, y = y0. False, with *error.
  bool MakeState(const double* y0, bool with_yp, std::string* error);
  // Sets the user data (this), tolerances, stop time and step limits of `options` on mem_.
  // Call after the module's own Init. False, with *error.
  bool SetCommonOptions(const ModuleSetters& m, double stop, const IntegratorOptions& options, std::string* error);
  // y := s_.y when flag >= 0 (a successful return of the module's solve); returns flag.
  int CopyOut(int flag, double* y) const;
  // The user's message for a failure of this kind; `flag_name` names kOther.
  // `flag_name` is the module's *GetReturnFlagName, whose string the caller frees; it is
  // called only for a flag outside the kinds above.
  StepFailure Describe(FailureKind kind, const char* module, char* (*flag_name)(long int), int flag) const;
  static bool Fail(std::string* error, const std::string& what) {
    *error = what;
    return false;
  }

  GuardedRhs& rhs_;
  SundialsObjects s_;
  SundialsMessages messages_;
  void* mem_ = nullptr;  // the module's memory, freed by the derived class's destructor
  bool stepped_ = false;  // one step taken in one-step mode (checked steps): an interpolant exists
};

}  // namespace kanesim::sim::detail
