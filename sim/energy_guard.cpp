#include "sim/energy_guard.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "runtime/runtime.h"

namespace kanesim::sim {

namespace {

// The bound on the relative energy error: max(kEnergyC * rtol, kEnergyFloor), above the
// largest error of correct runs (docs/integrators.md "The energy guard" has the table).
constexpr double kEnergyC = 3e4;
constexpr double kEnergyFloor = 1e-4;
// T and V are sums of terms as large as |T| + |V|; their roundoff is below this share of it.
constexpr double kRoundoff = 1e-11;

}  // namespace

// The error test accepts a local error of rtol |y_i| + atol per state, so an atol above
// rtol (states of order one) loosens what the run was asked for; measured:
// examples/double_pendulum.mech, DOP853, rtol 1e-8, 20 s: atol 1e-8 0.11e-6 of the motion's
// energy, atol 1e-3 3.2e-4, atol 1e-1 4.2e-4 (an rtol-only bound, 3e-4, stopped the last
// two, runs as accurate as they were asked to be).
double EnergyTolerance(double rtol, double atol) { return std::max(kEnergyC * std::max(rtol, atol), kEnergyFloor); }

EnergyGuard::EnergyGuard(const rt::Program& program, EnergyCheck mode, double rtol, double atol) {
  tol_ = EnergyTolerance(rtol, atol);
  if (mode == EnergyCheck::kOff) {
    description_ = "off";
    return;
  }
  if (std::string why = rt::NonConservativeCause(program); !why.empty()) {
    description_ = "not applied (" + why + " does work)";
    return;
  }
  active_ = true;
  stop_ = mode == EnergyCheck::kOn;
  description_ = stop_ ? "on" : "report";
}

int EnergyGuard::Row(double t, double T, double V, std::string* cause) {
  if (!active_ || !std::isfinite(T) || !std::isfinite(V)) return 0;
  const double E = T + V;
  if (!started_) {
    started_ = true;
    e0_ = E;
    v0_ = V;
  }
  motion_ = std::max(motion_, T + std::abs(V - v0_));
  size_ = std::max(size_, std::abs(T) + std::abs(V));
  const double dE = std::abs(E - e0_);
  const double floor = kRoundoff * size_;
  if (dE <= floor) return 0;
  const double rel = motion_ > 0.0 ? dE / motion_ : HUGE_VAL;
  worst_ = std::max(worst_, rel);
  const double bound = tol_ * motion_ + floor;
  if (!stop_ || dE <= bound) return 0;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "the total energy of a conservative model changed by %.6g J (E0 = %.10g J, E = %.10g J), more than "
                "the tolerance allows (%.3g J: %.3g of the motion's energy %.6g J): the solution cannot be trusted "
                "(docs/integrators.md \"The energy guard\"; --energy-check off runs on regardless)",
                E - e0_, e0_, E, bound, tol_, motion_);
  *cause = buf;
  return 1;
}

}  // namespace kanesim::sim
