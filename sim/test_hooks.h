// Switches and hooks for tests only: parts of a run that a test turns off to show what they
// do, and a fault put into the right-hand side on purpose. Kept out of SimOptions (what users
// set) and out of sim/sim.h: no front end (the CLI, the Python module, sweeps) includes this
// header. Every default is what Simulate(program, options, sink) does.
#pragma once

#include <functional>

#include "sim/change_point_bridge.h"
#include "sim/simulate.h"

namespace kanesim::sim {

struct TestHooks {
  // Step over singular configurations of closed loops (docs/constraints.md "Singular
  // configurations"). Off: the solver's failure at a change point stands.
  bool bridge = true;
  BridgeSwitches bridge_switches;  // parts of the bridge (sim/change_point_bridge.h)
  bool dense_check = true;  // DOP853: steps whose dense-output stages are not smooth are retaken
  // Interpolated output rows of a conservative model with closed loops checked against the
  // energies of the solver's steps around them and recomputed where off (docs/constraints.md
  // "Rows checked against the energy").
  bool row_energy_check = true;
  // Output rows near a change point whose projection moved the integrator's speeds too far
  // are projected in the kinetic metric instead (docs/constraints.md "Rows near a change point").
  bool zone_rows = true;
  // Output rows of steps inside a near-singular zone held until the zone is passed or bridged,
  // and recomputed from the bridge when bridged (docs/constraints.md "Rows held through a zone").
  bool hold_zone_rows = true;
  // Called after every right-hand side with its t, y and ydot (e.g. a push the model does
  // not have, for the energy guard's tests).
  std::function<void(double t, const double* y, double* ydot)> rhs_fault;
};

SimResult Simulate(const rt::Program& program, const SimOptions& options, SignalSink& sink, const TestHooks& hooks);

}  // namespace kanesim::sim
