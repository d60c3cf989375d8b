// The output rows' held rows (sim/held_outputs.h).
#include "sim/held_outputs.h"

namespace kanesim::sim {

HeldOutputs::HeldOutputs(const rt::Program& program, double rtol, double atol)
    : program_(program), stops_(program, rtol, atol), stick_(program) {
  if (stops_.Active()) stick_.SetStops(&stops_);  // as the run's (sim/simulate.cpp)
  ydot_.resize(static_cast<size_t>(rt::StateSize(program)));
}

const std::string& HeldOutputs::Error() const { return stops_.Error().empty() ? stick_.Error() : stops_.Error(); }

int HeldOutputs::Prepare(const EndStopEvents* stops, const StickSlipEvents* stick, rt::Workspace& ws, double t,
                         const double* y) {
  const bool friction = stick && stick->Active() && stick_.Active();
  const bool held = (stops && stops->AnyHeld()) || (friction && stick->AnyStuck());
  if (friction) stick_.SetModes(stick->Modes());
  if (!held) {
    if (friction) stick->Sync(ws);  // the sliding joints' directions
    rt::ClearHeldLoads(ws);
    return 0;
  }
  if (stops && stops_.Active()) stops_.SetResting(stops->Resting());
  int s = 0;
  if (friction) {  // the stuck joints' forces and the stops' reactions as one system, into ws
    s = stick_.Rhs(ws, t, y, ydot_.data());
  } else {
    s = rt::Derivative(program_, ws, t, y, ydot_.data());
    if (s == 0) s = stops_.Hold(ws, t, y, ydot_.data());
  }
  if (s != 0) return s;
  stops_.LoadSignals(ws, friction ? stick_.StuckSpeeds() : std::vector<int>{});
  return 0;
}

}  // namespace kanesim::sim
