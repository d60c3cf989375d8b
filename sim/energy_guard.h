// The energy guard (docs/integrators.md "The energy guard"): in a model whose forces conserve
// T + V (rt::NonConservativeCause), a run whose total energy moves from its start value
// by more than the tolerance can explain stops with exit 2 instead of ending with a wrong
// motion. A net under every cause of a wrong solution (a branch switch the other checks
// missed, an integrator that accepted bad steps), evaluated at the output rows.
#pragma once

#include <string>
#include <vector>

#include "runtime/runtime.h"

namespace kanesim::sim {

enum class EnergyCheck {
  kOn,      // stop with exit 2 when the energy leaves the bound (the default)
  kOff,     // no check, no cost
  kReport,  // measure the largest error for --stats, never stop
};

// The relative energy error of a row: |E - E0| / S, S = the motion's energy so far, the
// largest T + |V - V0| over the rows up to this one (so that E0 = 0, or a large V0 from
// where the origin sits, does not matter). The run stops where it exceeds
// EnergyTolerance(rtol, atol) (plus a roundoff floor on the sizes of T and V themselves):
// max(3e4 max(rtol, atol), 1e-4); atol only where it is the larger (the states are of order one).
double EnergyTolerance(double rtol, double atol = 0.0);

class EnergyGuard {
 public:
  EnergyGuard(const rt::Program& program, EnergyCheck mode, double rtol, double atol);
  EnergyGuard(const EnergyGuard&) = delete;
  EnergyGuard& operator=(const EnergyGuard&) = delete;

  bool Active() const { return active_; }  // a conservative model and the check not off
  // The signals Row needs, evaluated with the row's own (after the requested ones, in
  // the same workspace: no second projection, and the written values are unchanged).
  static std::vector<std::string> Signals() { return {"kinetic_energy", "potential_energy"}; }
  // At an output row, its kinetic and potential energy (the first row sets E0): 0 to go
  // on; non-zero when the energy left the bound and the mode is kOn, the cause in words.
  int Row(double t, double T, double V, std::string* cause);
  double WorstError() const { return worst_; }  // the largest relative error seen (0 before any row)
  double Tolerance() const { return tol_; }
  // What --stats says about the guard: "on", "off", "report", or "not applied (<cause>)".
  const std::string& Description() const { return description_; }

 private:
  bool active_ = false, stop_ = false;
  double tol_ = 0.0;
  std::string description_;
  bool started_ = false;
  double e0_ = 0.0, v0_ = 0.0;
  double motion_ = 0.0;   // max over the rows of T + |V - V0|
  double size_ = 0.0;     // max over the rows of |T| + |V| (for the roundoff floor)
  double worst_ = 0.0;
};

}  // namespace kanesim::sim
