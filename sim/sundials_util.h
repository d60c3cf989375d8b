// Internal to sim: ownership of the SUNDIALS objects every solver needs.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sim/release_bound.h"
#include "sim/stepper.h"

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

// The functions every SUNDIALS integrator module has, each under its own prefix
// (CVodeSet..., ERKStepSet..., IDASet...), with the same signatures. The counters of an
// implicit method (Newton or fixed-point iteration, linear solver) are null for ERKStep.
struct ModuleFunctions {
  const char* module;  // "CVODE", "ARKODE", "IDA": named in setup failures
  // Optional inputs.
  int (*err_handler)(void* mem, void (*handler)(int, const char*, const char*, char*, void*), void* data);
  int (*tolerances)(void* mem, double rtol, double atol);
  int (*user_data)(void* mem, void* data);
  int (*stop_time)(void* mem, double t);
  int (*max_num_steps)(void* mem, long steps);
  int (*max_step)(void* mem, double h);
  int (*init_step)(void* mem, double h);
  // The solution and the module's memory.
  int (*current_time)(void* mem, double* t);
  int (*dky)(void* mem, double t, int k, N_Vector dky);  // k-th derivative of the interpolant at t
  void (*free)(void** mem);
  char* (*flag_name)(long int flag);  // malloc'd, freed by the caller
  // Counters (IntegratorStats).
  int (*num_steps)(void* mem, long* n);
  int (*num_rhs_evals)(void* mem, long* n);  // of f, or of the residual (IDA)
  int (*num_err_test_fails)(void* mem, long* n);
  int (*last_step)(void* mem, double* h);
  int (*num_lin_setups)(void* mem, long* n);
  int (*num_nonlin_iters)(void* mem, long* n);
  int (*num_nonlin_conv_fails)(void* mem, long* n);
  int (*last_order)(void* mem, int* order);
  int (*num_jac_evals)(void* mem, long* n);
  int (*num_lin_rhs_evals)(void* mem, long* n);  // of f for difference-quotient Jacobians
  int (*current_step)(void* mem, double* h);     // the step size to try next
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

// The drift of a solver's accepted steps from the constraints, in the error test's weights
// |y*_i - y_i| / (rtol |y_i| + atol), y* the step's projection computed aside (ARKODE on the
// reduced form, CVODE on the multiplier form; docs/constraints.md "A drifted state"). Past
// kLimit weights and grown over kGrowth steps in a row the relaxation lost hold (about x2
// per step at rtol 1e-4); near a change point the measured drift jumps about from step to
// step (the projection there ill-conditioned), and resetting there cost accuracy: not reset.
struct DriftWatch {
  static constexpr double kLimit = 10.0;
  static constexpr int kGrowth = 4;
  // After an accepted step at t with state ys (n), projected aside by project(t, y) (0: done).
  template <typename Project>
  void Measure(double t, const double* ys, size_t n, double rtol, double atol, Project&& project) {
    stepped_y.assign(ys, ys + n);
    projected = stepped_y;
    if (project(t, projected.data()) != 0) return;  // a projection that fails leaves y as it is
    double drift = 0.0;
    for (size_t i = 0; i < n; ++i) drift = std::max(drift, std::fabs(projected[i] - ys[i]) / (rtol * std::fabs(ys[i]) + atol));
    growth = drift > last_drift ? growth + 1 : 0;
    last_drift = drift;
    drifted = drift > kLimit && growth >= kGrowth;
    t_drifted = t;
  }
  void Clear() {
    drifted = false;
    growth = 0;
    last_drift = 0.0;
  }
  bool drifted = false;          // the last step drifted: the solver goes on from its projection
  double t_drifted = 0.0;        // its time
  double last_drift = 0.0;       // the drift of the step before
  int growth = 0;                // steps in a row whose drift grew
  std::vector<double> stepped_y;  // y of the last step  (n)
  std::vector<double> projected;  // its projection  (n)
};

// One SUNDIALS solver behind the Stepper interface: the context and vectors, the captured
// messages, the guarded right-hand side, and the steps they all take alike.
class SundialsStepper : public Stepper {
 public:
  SundialsStepper(GuardedRhs& rhs, const ModuleFunctions& module) : rhs_(rhs), module_(module) {}
  ~SundialsStepper() override {
    if (mem_) module_.free(&mem_);
  }

  double CurrentTime() const override;
  void SetStopTime(double t) override {
    module_.stop_time(mem_, t);
    stop_given_ = t;
    StopMoved(t);
  }
  double NextStep() const override {
    double h = 0.0;
    module_.current_step(mem_, &h);
    return h;
  }
  // The counters every module has, and an implicit method's when it has them.
  IntegratorStats Stats() const override;
  StepFailure Explain(int flag) const override;

 protected:
  // s_.y (and s_.yp when with_yp) of the right-hand side's size, y = y0. False, with *error.
  bool MakeState(const double* y0, bool with_yp, std::string* error);
  // SUNDIALS' messages go to messages_ (the module's return flag).
  int CaptureMessages() { return module_.err_handler(mem_, CaptureSundialsMessage, &messages_); }
  // Sets the user data (this), tolerances, stop time and step limits of `options` on mem_.
  // Call after the module's own Init. False, with *error.
  bool SetCommonOptions(double stop, const IntegratorOptions& options, std::string* error);
  // y := s_.y when flag >= 0 (a successful return of the module's solve); returns flag.
  int CopyOut(int flag, double* y) const;
  // Events (OdeSystem::NumEvents): the module's root finding on every event function, each
  // crossing downwards only. init(n) is its RootInit, direction(dirs) its SetRootDirection;
  // nothing when the system has none. False, with *error.
  template <class Init, class Direction>
  bool InitRoots(Init init, Direction direction, std::string* error) {
    const int n = rhs_.NumEvents();
    if (n == 0) return true;
    std::vector<int> down(static_cast<size_t>(n), -1);
    guards_.clear();
    for (int i = 0; i < n; ++i)
      if (rhs_.Paired(i) >= 0) guards_.push_back(i);
    if (init(n) != 0 || direction(down.data()) != 0)
      return Fail(error, WithDetail(std::string(module_.module) + ": root finding setup failed", messages_.last));
    return true;
  }
  // After the module's root return at tret: y, event_time and event_index (the first function
  // that crossed, from info(found), its GetRootInfo); kEventReached.
  template <class Info>
  int EventReached(double tret, double* y, Info info) {
    std::vector<int> found(static_cast<size_t>(rhs_.NumEvents()), 0);
    info(found.data());
    event_index = static_cast<int>(std::find_if(found.begin(), found.end(), [](int f) { return f != 0; }) - found.begin());
    event_time = tret;
    CopyOut(0, y);
    // A root return that names no function (CVODE's root finding filters each crossing by
    // its direction only after it has stopped at one: robot sweep 26 trial 0, Solo12 in
    // CVODE-BDF at t = 0.1211) is no event: the module goes on. (Before, event index
    // NumEvents() was taken for a when clause's and the run crashed.)
    if (event_index == rhs_.NumEvents()) return kNoEvent;
    if (const int p = rhs_.Paired(event_index); p >= 0) return Graze(p, tret, y);
    return kEventReached;
  }
  // A graze guard crossed at tret (y there; OdeSystem::Paired): kNoEvent when function p is
  // positive there (the module goes on), else kEventReached at p's crossing before tret,
  // located on the last step's interpolant.
  int Graze(int p, double tret, double* y);
  static constexpr int kNoEvent = kEventReached + 1;
  std::vector<int> guards_;  // the graze guards among the event functions (OdeSystem::Paired)
  // The event functions for CVODE and ARKODE (user data: this), and for IDA.
  static int Roots(double t, N_Vector y, double* g, void* user_data);
  static int RootsIda(double t, N_Vector y, N_Vector yp, double* g, void* user_data);
  // One step at a time, each checked (OdeSystem::StepAccepted), then the output instant
  // from the module's interpolant, as in its NORMAL mode. one_step(&tret) takes one step
  // toward tout into s_.y (the module's ONE_STEP mode) and returns its flag; StepChecked
  // sees each step that passed the check.
  // info(found) reads the module's root info after a root return (flag kRootReturn): an
  // event past tout waits for the call whose tout reaches it (the step's interpolant gives
  // the rows before it).
  template <class OneStep, class Info>
  int AdvanceCheckedSteps(double tout, double* y, OneStep one_step, Info info) {
    double tret = 0.0;
    double reached = -HUGE_VAL;  // the last stop time returned at (the module's t may lie a rounding short of it)
    long steps = 0;  // as the module's own limit in its NORMAL mode, which ONE_STEP calls skip
    for (;;) {
      if (pending_event_ && event_time <= tout) {
        pending_event_ = false;
        std::copy(pending_y_.begin(), pending_y_.end(), y);
        return kEventReached;
      }
      if (stepped_ && std::max(CurrentTime(), reached) >= tout && tout <= roots_checked_to_) {
        const int flag = CopyOut(module_.dky(mem_, tout, 0, s_.y), y);
        return flag >= 0 && check_rows_ ? CheckRow(tout, y, flag) : flag;
      }
      if (!stepped_ && check_rows_) MarkStep(CurrentTime(), N_VGetArrayPointer(s_.y));
      if (release_.Active()) BoundHeldStep();
      if (++steps > options_.max_steps) return kTooMuchWork;  // (a step bound that creeps)
      const int flag = one_step(&tret);
      if (flag < 0) return flag;
      stepped_ = true;
      if (flag == kTstopReturn) reached = tret;
      if (flag == kRootReturn) {  // s_.y at the root inside the step; the step's end is checked next call
        // The rest of the step, (tret, its end], has not been searched for roots: rows past
        // tret come from the next call, which searches it (a graze guard's root, no event,
        // before a contact's crossing later in the same step: the crossing was missed and
        // the row below the plane stopped the run).
        roots_checked_to_ = tret;
        if (const int r = EventReached(tret, y, info); r != kNoEvent) {
          if (event_time <= tout) return r;
          pending_event_ = true;
          pending_y_.assign(y, y + rhs_.Size());
        }
        continue;
      }
      roots_checked_to_ = INFINITY;  // (the step's end: searched to it)
      const double* ys = N_VGetArrayPointer(s_.y);
      if (rhs_.ChecksSteps() && rhs_.StepAccepted(tret, ys) != 0) return kStepCheckFailed;
      if (check_rows_) MarkStep(tret, ys);
      if (release_.Active()) {
        double h = 0.0;
        module_.last_step(mem_, &h);
        held_bound_ = release_.Next(tret, ys, std::abs(h));
      }
      StepChecked(tret, ys);
    }
  }
  // The end of an accepted step (t, y), the start of the next (RowEnergy).
  void MarkStep(double t, const double* y);
  // Held rows (ReleaseBound): one step at a time (AdvanceCheckedSteps, also where no step is
  // checked), each ending by the bound: the module's stop time moved to it (a maximum step
  // set after a step would act one step late: the next step's size is chosen at the end of
  // the last).
  bool StepsOneByOne() const { return rhs_.ChecksSteps() || release_.Active(); }
  void BoundHeldStep() {
    const double t = CurrentTime();
    if (!bound_known_) {  // the first step: from the start
      held_bound_ = release_.Next(t, N_VGetArrayPointer(s_.y), 0.0);
      bound_known_ = true;
    }
    module_.stop_time(mem_, std::min({stop_given_, t + held_bound_, row_stop_}));
  }
  // The output instant y(tout) from the interpolant, checked against the energies of the
  // last step's ends (RowEnergy); where off, integrated again from the step's start to tout
  // by DOP853 (no interpolation); still off: kRowEnergyFailed. Else flag.
  int CheckRow(double tout, double* y, int flag);
  virtual void StepChecked(double /*t*/, const double* /*y*/) {}
  virtual void StopMoved(double /*t*/) {}  // SetStopTime: a module that restarts keeps it
  // The module's return flag as one of the shared kinds (kOther for the rest).
  virtual FailureKind Kind(int flag) const = 0;
  static bool Fail(std::string* error, const std::string& what) {
    *error = what;
    return false;
  }
  // f(t, y) for CVODE and ARKODE (user data: this).
  static int Rhs(double t, N_Vector y, N_Vector ydot, void* user_data);

  GuardedRhs& rhs_;
  const ModuleFunctions& module_;
  SundialsObjects s_;
  SundialsMessages messages_;
  void* mem_ = nullptr;  // the module's memory, freed by module_.free
  bool stepped_ = false;  // one step taken in one-step mode (checked steps): an interpolant exists
  double stop_given_ = 0.0;        // the stop time (SetCommonOptions, SetStopTime): never past it
  ReleaseBound release_;           // held rows' release functions (none: no bound, no cost)
  double held_bound_ = HUGE_VAL;   // ... the next step's bound from them
  double row_stop_ = HUGE_VAL;     // the next output instant where a module's steps end there (ARKODE)
  bool bound_known_ = false;       // ... computed once from the start
  // CV_ROOT_RETURN, ARK_ROOT_RETURN, IDA_ROOT_RETURN (all 2); CV_, ARK_, IDA_TSTOP_RETURN (all 1).
  static constexpr int kRootReturn = 2;
  static constexpr int kTstopReturn = 1;
  // CV_TOO_MUCH_WORK, ARK_TOO_MUCH_WORK, IDA_TOO_MUCH_WORK (all -1).
  static constexpr int kTooMuchWork = -1;
  bool pending_event_ = false;  // a root found past tout: y there (event_time, event_index set)
  double roots_checked_to_ = INFINITY;  // after a root inside the step: the step searched to here
  std::vector<double> pending_y_;
  // Rows checked against the energy (CheckRow).
  struct StepEnd {
    double t = 0.0;
    std::vector<double> y;  // (n)
    bool known = false;     // T, V evaluated
    double T = 0.0, V = 0.0;
  };
  bool check_rows_ = false;       // options.row_energy_check and the system has an energy
  IntegratorOptions options_;     // as given (for the DOP853 that recomputes a row)
  StepEnd step_start_, step_end_; // the last accepted step's ends
  RowEnergy row_energy_;          // Eq. (5)'s motion
  std::string row_failure_;       // Explain's text for kRowEnergyFailed
  long rows_recomputed_ = 0;      // output instants integrated again (CheckRow)
  long reintegration_rhs_ = 0;    // their right-hand sides (capped: CheckRow)
};

// A stepper of type S (constructed from rhs), initialized by its Init; null, with *error,
// when that fails.
template <class S>
std::unique_ptr<Stepper> MakeSundialsStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                             const IntegratorOptions& options, std::string* error) {
  auto stepper = std::make_unique<S>(rhs);
  if (!stepper->Init(t0, y0, stop, options, error)) return nullptr;
  return stepper;
}

}  // namespace kanesim::sim::detail
