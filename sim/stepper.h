// Internal to sim: one solver (SUNDIALS' or our DOP853) behind a small interface, and the guard
// around the user's right-hand side that the solvers call. Not part of the public API.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sim/integrator.h"

namespace kanesim::sim::detail {

// Calls the user's f, remembers where and why it last failed, and turns a non-finite
// derivative into a recoverable failure (the solver retries with a smaller step; if the
// NaN persists the run fails with this cause).
class GuardedRhs {
 public:
  explicit GuardedRhs(OdeSystem& system) : system_(system) {}
  int operator()(double t, const double* y, double* ydot);
  int Size() const { return system_.Size(); }
  // The system's projection (OdeSystem::Project), failures recorded as operator()'s.
  bool CanProject() const { return system_.CanProject(); }
  void EnableStepProjection() { system_.EnableStepProjection(); }
  int Project(double t, double* y);
  // The system's ProjectAside: a measurement, its failures not recorded.
  int ProjectAside(double t, double* y) { return system_.ProjectAside(t, y); }
  int ProjectAsideMultiplierForm(double t, double* y) { return system_.ProjectAsideMultiplierForm(t, y); }
  // The system's check of an accepted step (OdeSystem::StepAccepted), failures recorded
  // as operator()'s; a failed check is always fatal for the SUNDIALS solvers
  // (kStepCheckFailed).
  bool ChecksSteps() const { return system_.ChecksSteps(); }
  int StepAccepted(double t, const double* y);
  // The system's energy of a state (OdeSystem::HasEnergy, Energy), for checking rows.
  int NumEvents() const { return system_.NumEvents(); }
  // The system itself, for evaluations aside that are no solver's (ReleaseBound): their
  // failures are not recorded.
  OdeSystem& System() { return system_; }
  int EventFunctions(double t, const double* y, double* g) {
    ++event_evals;
    return system_.EventFunctions(t, y, g);
  }
  int Paired(int i) const { return system_.Paired(i); }
  bool HasEnergy() const { return system_.HasEnergy(); }
  int Energy(double t, const double* y, double* T, double* V) { return system_.Energy(t, y, T, V); }
  // The system's ProjectedStates (OdeSystem::ProjectedStates), inside a JacobianHold.
  bool ProjectedStates(std::vector<int>* states, double* diag) { return system_.ProjectedStates(states, diag); }
  int NewtonRank() const { return system_.NewtonRank(); }
  // The system's HoldForJacobian, on for the life of a JacobianHold.
  class JacobianHold {
   public:
    explicit JacobianHold(GuardedRhs& rhs) : system_(rhs.system_) { system_.HoldForJacobian(true); }
    ~JacobianHold() { system_.HoldForJacobian(false); }
    JacobianHold(const JacobianHold&) = delete;
    JacobianHold& operator=(const JacobianHold&) = delete;

   private:
    OdeSystem& system_;
  };

  long event_evals = 0;    // EventFunctions calls over the run (IntegratorStats::event_evals)
  bool failed = false;     // an evaluation failed since the last ClearFailure()
  bool fatal = false;      // an evaluation returned < 0: latched, every later call fails
                           // without calling f, so no solver can creep up to it again
  double fail_time = 0.0;  // t of the last failed evaluation (of the fatal one once latched)
  std::string cause;       // why it failed
  void ClearFailure() {
    failed = false;
    recoverable_ = 0;
  }
  // Everything cleared, the fatal latch too: for a fresh solver after a bridge.
  void Reset() {
    ClearFailure();
    fatal = false;
    fail_time = 0.0;
    cause.clear();
  }

  // Recoverable failures between two output instants (since ClearFailure) after which
  // the next one is fatal: a solver without a minimum step (CVODE, IDA) would otherwise
  // creep toward a lasting failure (a NaN from t = 0.35 on) in ever smaller steps until
  // its step limit, 1e5 steps later; a transient failure of a stage off the trajectory
  // costs a handful.
  static constexpr int kMaxRecoverableFailures = 200;

 private:
  int Failed(double t, int status);  // records a failure of f or of the projection; returns status
  int Recoverable();                 // counts one; 1, or -1 (latched fatal) past the limit
  int recoverable_ = 0;
  OdeSystem& system_;
};

// A SUNDIALS stepper's Advance flag when the system's check of an accepted step failed.
inline constexpr int kStepCheckFailed = -100000;
// ... and when an output instant's energy was off and integrating to it again did not help.
inline constexpr int kRowEnergyFailed = -100001;

// An output instant checked against the energies of the accepted steps around it, in a
// system that conserves T + V (OdeSystem::HasEnergy; docs/constraints.md "Rows checked
// against the energy"). Over one step from t0 to t1 with energies E0 and E1, the energy of
// the state interpolated at theta = (t - t0) / (t1 - t0) is off by
//   d = |E(t) - (E0 + theta (E1 - E0))| / (|E1 - E0| + rtol S + 1e-11 (|T| + |V|))      (5)
// where S is the motion's energy so far (the largest T + |V - V(first)|, as the energy
// guard's). The steps' own drift is in E0 and E1; an interpolant that is right stays near
// the line between them.
struct RowEnergy {
  // Past this d the interpolated state is not trusted. Measured over the chains of 2 and 10
  // equal-link parallelograms (both forms, the five integrators, rtol 1e-4 ... 1e-12, 20 s):
  // the rows of main that were WRONG 8.7e4 (DOP853, chain of 10, 1e-12) and 1.3e6 (chain of
  // 2, 1e-10); below the limit at most 934 (DOP853, chain of 10, 1e-10: a row 5.7e-7 of E
  // off, left) and 548 (ARKODE, chain of 10, 1e-8: 8.3e-6); typically below 50.
  static constexpr double kLimit = 1e3;
  void Motion(double T, double V) {
    if (!started) {
      started = true;
      v_first = V;
    }
    motion = std::max(motion, T + std::abs(V - v_first));
  }
  // Eq. (5) for the instant's energy Er at theta between E0 and E1 (T1, V1: the end's).
  double Deviation(double e0, double e1, double theta, double er, double rtol, double T1, double V1) const {
    const double scale = std::abs(e1 - e0) + rtol * motion + 1e-11 * (std::abs(T1) + std::abs(V1));
    const double off = std::abs(er - (e0 + theta * (e1 - e0)));
    // A mechanism with no energy at all (massless parts held still: T = V = 0 throughout)
    // has scale 0; its rows are exactly on the line, not 0/0 = NaN (issue 38).
    return off == 0.0 ? 0.0 : off / scale;
  }
  bool started = false;
  double v_first = 0.0, motion = 0.0;
};

// What went wrong in one Advance, in words for the user.
struct StepFailure {
  bool from_rhs = false;  // the right-hand side failed (use GuardedRhs's time and cause)
  std::string cause;      // the solver's reason otherwise
};

// Advance's flag when an event function crossed zero before tout (OdeSystem::NumEvents): y
// is the state at Stepper::event_time, where function event_index crossed.
inline constexpr int kEventReached = 1000;
// ... and when DOP853 found the problem stiff (IntegratorOptions::switch_when_stiff): y is
// the state of its last accepted step, at Stepper::event_time (before tout).
inline constexpr int kStiffReached = 1001;

class Stepper {
 public:
  virtual ~Stepper() = default;
  // Integrates to tout (NORMAL mode, interpolated) and writes y(tout) into y. Returns
  // the solver's flag: >= 0 success, < 0 failure (then Explain(flag)); kEventReached.
  virtual int Advance(double tout, double* y) = 0;
  double event_time = 0.0;  // kEventReached: where, and which event function
  int event_index = -1;
  virtual double CurrentTime() const = 0;
  // The stepping core (sim/simulator.h): integrate no further than t from now on (the solver's
  // stop time), the step size it would try next, and the inputs changed at CurrentTime() (a
  // solver that keeps f(t, y) from the last step evaluates it again).
  virtual void SetStopTime(double t) = 0;
  virtual double NextStep() const = 0;
  virtual int InputsChanged() { return 0; }
  virtual IntegratorStats Stats() const = 0;
  virtual StepFailure Explain(int flag) const = 0;
};

// Each returns null and sets *error when the solver cannot be set up (or, for IDA, when
// f fails at t0: then rhs.failed is set).
std::unique_ptr<Stepper> MakeIdaStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                        const IntegratorOptions& options, std::string* error);
std::unique_ptr<Stepper> MakeCvodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                          const IntegratorOptions& options, std::string* error);
std::unique_ptr<Stepper> MakeArkodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                           const IntegratorOptions& options, std::string* error);
// Our own DOP853 (sim/integrator_dop853.cpp): null when f fails at t0.
std::unique_ptr<Stepper> MakeDop853Stepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                           const IntegratorOptions& options, std::string* error);

// The stepper of options.method (Auto: IDA).
std::unique_ptr<Stepper> MakeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                     const IntegratorOptions& options, std::string* error);

// The counters of a solver that ended (at a bridge, an event, a hand-over) added to *to,
// those of the solvers before it; the per-solver fields (last step, order, linear solver)
// are left to the caller's choice of solver.
void AddStats(IntegratorStats* to, const IntegratorStats& s);

// DOP853 found the problem stiff (its Advance returned kStiffReached; y holds its state at
// stepper->event_time): its counters go into *done, marked switched, *options become
// CVODE-BDF's (for every later restart) and a CVODE-BDF stepper goes on from there
// (docs/integrators.md "The automatic choice"). Integrate and the stepping core both hand
// over through this. Null with *error as MakeStepper.
std::unique_ptr<Stepper> HandOverStiff(GuardedRhs& rhs, const Stepper& stiff, const double* y, double stop,
                                       IntegratorOptions* options, IntegratorStats* done, std::string* error);

// SUNDIALS error handler target: keeps the last message instead of printing it.
struct SundialsMessages {
  std::string last;  // "<function>: <message>"
};
void CaptureSundialsMessage(int error_code, const char* module, const char* function, char* msg,
                            void* user_data);

}  // namespace kanesim::sim::detail
