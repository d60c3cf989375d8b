// What an output row reads of a hybrid run's mode (docs/events.md "Outputs"): the exact
// friction laws, and the held contacts' reactions and stuck joints' forces solved at the row's
// own (t, y) (rt::SetHeldLoads), so that the accelerations, body accelerations, joint
// reactions and contact forces are the held motion's (a joint resting on its stop reads
// a = 0, its reaction the static one), not the free motion's. It solves on its own copies of
// the stops and friction events: a row never moves the integrator's state or its Newton data.
#pragma once

#include <vector>

#include "runtime/runtime.h"
#include "sim/end_stops.h"
#include "sim/stick_slip.h"

namespace kanesim::sim {

class HeldOutputs {
 public:
  HeldOutputs(const rt::Program& program, double rtol, double atol);
  HeldOutputs(const HeldOutputs&) = delete;
  HeldOutputs& operator=(const HeldOutputs&) = delete;
  // Before rt::EvalSignals on ws at (t, y) (y with the resting joints snapped onto their
  // stops): the modes of `stops` and `stick` (null or inactive: none), their held rows solved
  // at (t, y) into ws. 0, or Derivative's codes (then Error(), or rt::ErrorMessage(ws)).
  int Prepare(const EndStopEvents* stops, const StickSlipEvents* stick, rt::Workspace& ws, double t, const double* y);
  const std::string& Error() const;

 private:
  const rt::Program& program_;
  EndStopEvents stops_;
  StickSlipEvents stick_;
  std::vector<double> ydot_;
};

}  // namespace kanesim::sim
