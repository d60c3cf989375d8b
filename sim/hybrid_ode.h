// The model's equations of motion with its events, for an integrator outside kanesim (an
// FMU's Model Exchange master, docs/fmi.md "Events") and for the stepping core
// (sim/simulator.h, through System()). The same right-hand side, event functions and event
// handling a run uses (sim/engine_ode.h over sim/end_stops.h, sim/stick_slip.h,
// sim/lift_off.h, sim/when_events.h), with the integrator left out: the master integrates
// y' = Derivatives(t, y), watches Indicators(t, y) (an event is one of them crossing zero
// downwards, as in a run) and calls Event at the crossing.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/integrator.h"
#include "sim/simulate.h"

namespace kanesim::sim {

class HybridOde {
 public:
  // rtol, atol: the tolerances the end stops' rest and accumulation tests scale with.
  HybridOde(std::shared_ptr<const rt::Program> program, double rtol, double atol);
  ~HybridOde();
  HybridOde(const HybridOde&) = delete;
  HybridOde& operator=(const HybridOde&) = delete;

  // The event functions' number and, per function, what it watches ("joint 'hinge' at
  // q_min", "condition of when (m.mech:9)", last "graze guard of joint 'hinge' at q_min":
  // minus the gap's rate, crossing at the gap's minimum; Event there is the gap's impact
  // where the gap is not positive, else nothing).
  int NumIndicators() const;
  std::vector<std::string> IndicatorNames() const;

  // The model's inputs (rt::NumInputs values), held until set again.
  void SetInputs(const std::vector<double>& values);

  // The start at (t0, y0), as a run starts: "" or why it cannot (a joint past its stop, a
  // rolling contact pulling); a start on a contact is its first event (y0 may jump), exact
  // friction decides sliding or stuck.
  std::string Start(double t0, double* y0);
  // y' at (t, y) in the current mode (resting contacts held, stuck joints held, sliding
  // ones' friction by their direction). 0, or rt::Derivative's codes (then FailureCause).
  int Derivatives(double t, const double* y, double* ydot);
  // The NumIndicators event functions at (t, y). 0, or the codes above.
  int Indicators(double t, const double* y, double* z);
  // Indicator i crossed zero downwards at (t, y): the run's handling of it (an impact, a
  // rest or a lift from a stop, a reinit, a stick or a slip); y jumps in place. 0, or nonzero
  // (FailureCause: a rolling contact that would pull, a failed impulse).
  int Event(double t, double* y, int i);
  // A terminate(...) fired: its message.
  bool Terminated(std::string* why) const;
  std::string FailureCause() const;

  // The mode (which contacts rest, accumulated bounces, stuck joints and their forces, a
  // terminate), as numbers to save and restore.
  std::vector<double> Modes() const;
  bool SetModes(const std::vector<double>& modes);

  // For kanesim's own solvers (sim::Simulator): the system with every event function (the
  // indicators, then the graze guards, OdeSystem::Paired) and the handling above.
  OdeSystem& System();
  // The events handled: the start's, then every Event's, in time order, with their jumps.
  std::vector<EventRecord> StartEvents() const;
  const std::vector<EventRecord>& Events() const;
  // What an output row sees at (t, y), as the run's rows: the joints resting on their stops
  // exactly there (with `snap`; y may move by the interpolant's round-off), the mode's friction
  // laws and the held rows' motion in ws (sim/held_outputs.h). "", or why the held rows have
  // no solution.
  std::string ForOutputs(rt::Workspace& ws, double t, double* y, bool snap = true);

 private:
  std::string StartModes(double t0, double* y0);  // Start without its log
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kanesim::sim
