// The bridge's view of the accepted steps (sim/change_point_bridge.h CheckStep): the
// monitor's turn check, then the zone's trace of accepted steps, the early bridge over a
// stall, the stop after too many steps in one zone, and the check of a passage the solver
// made by itself (docs/constraints.md "Singular configurations").
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "sim/change_point_bridge.h"

namespace kanesim::sim {

namespace {
// Accepted steps inside one near-singular zone after which the run stops: a passage takes a
// few (at most 9 on the equal-link parallelogram, every integrator, rtol 1e-4 ... 1e-10); a
// solver creeping towards the singular configuration would otherwise run into its step
// limit per output instant, minutes later.
constexpr long kMaxZoneSteps = 1000;
// After this many accepted steps inside one zone (EnableEarlyBridge) the bridge is tried at
// once rather than after kMaxZoneSteps; refused, the solver goes on as before.
constexpr long kEarlyBridgeSteps = 50;
// ... and after this many in a zone where several loops are near singular at once (a chain
// of equal-link parallelograms; BridgeSwitches::several_at_once), reduced form only: there
// every evaluation re-chooses the partition of an ill-conditioned block and a creeping
// solver's steps are expensive, while the solvers' own passages (at most 9 steps) are left
// to them (docs/constraints.md "Several loops"; measurements in docs/benchmarks.md "Change
// points").
constexpr long kEarlyBridgeStepsSeveral = 10;
constexpr size_t kPreZone = 8;  // accepted steps before a zone kept for a bridge's fit

// "The integrator took N steps in the zone without passing the change point", then `tail`.
std::string StuckMessage(const rt::Program& p, const ChangePointBridge& m, double t, const char* tail) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "closed loop '%s' at a singular configuration at time %.9g: the integrator took %ld steps since "
                "time %.9g without passing the change point (the constraint rows within %.2g of losing rank, "
                "sigma_min/sigma_max)%s",
                rt::LoopName(p, m.zone_loop).c_str(), t, m.zone_steps, m.zone_t, m.zone_rho, tail);
  return buf;
}

// Keeps the last kPreZone accepted steps outside a zone.
void KeepBeforeZone(ChangePointBridge& m, double t, double rho, const double* y, size_t n) {
  if (m.pre_t.size() >= kPreZone) {
    std::rotate(m.pre_t.begin(), m.pre_t.begin() + 1, m.pre_t.end());
    std::rotate(m.pre_rho.begin(), m.pre_rho.begin() + 1, m.pre_rho.end());
    std::rotate(m.pre_y.begin(), m.pre_y.begin() + 1, m.pre_y.end());
    m.pre_t.back() = t;
    m.pre_rho.back() = rho;
    m.pre_y.back().assign(y, y + n);
  } else {
    m.pre_t.push_back(t);
    m.pre_rho.push_back(rho);
    m.pre_y.emplace_back(y, y + n);
  }
}
}  // namespace

std::unique_ptr<ChangePointBridge> MakeChangePointBridge(const rt::Program& p) {
  if (!rt::BranchMonitorActive(p)) return nullptr;
  auto m = std::make_unique<ChangePointBridge>();
  m->monitor = rt::MakeBranchMonitor(p);
  m->ws = &rt::MonitorWorkspace(*m->monitor);
  m->sparse = rt::Summarize(p).solver == rt::SolverPath::Sparse;
  return m;
}

const std::string& BridgeError(const ChangePointBridge& m) {
  return m.own_error ? m.error : rt::BranchMonitorError(*m.monitor);
}

void EnableEarlyBridge(ChangePointBridge& m, double rtol, double atol) {
  m.early_rtol = rtol;
  m.early_atol = atol;
}

int CheckStep(const rt::Program& p, ChangePointBridge& m, double t, const double* y) {
  m.own_error = false;
  rt::BranchStep s;
  if (rt::CheckBranch(p, *m.monitor, t, y, &s) != 0) return -1;
  if (!s.valid) return 0;
  const bool was_in_zone = m.in_zone, was_bridged = m.bridged;
  const size_t n = static_cast<size_t>(rt::StateSize(p));
  if (s.near) {
    if (!m.in_zone) {
      m.in_zone = true;
      m.zone_steps = 0;
      m.bridged = false;
      m.early_tried = false;
      m.passage_checked = t <= m.last_tb;  // the bridged state
      m.trace_t = m.pre_t;
      m.trace_rho = m.pre_rho;
      m.trace_y = m.pre_y;
    }
    m.zone_loop = s.zone_loop;
    m.zone_t = s.zone_t;
    m.zone_rho = s.zone_rho;
    if (m.trace_t.size() < static_cast<size_t>(kMaxZoneSteps) + kPreZone + 1) {
      m.trace_t.push_back(t);
      m.trace_rho.push_back(s.rho);
      m.trace_y.emplace_back(y, y + n);
    }
    m.zone_near = s.near_loops;
    ++m.zone_steps;
    const bool several = s.near_loops > 1 && m.switches.several_loops && m.switches.several_at_once &&
                         (!m.sparse || m.switches.several_at_once_multiplier);
    if (m.early_rtol > 0.0 && !m.bridged && !m.early_tried &&
        m.zone_steps >= (several ? kEarlyBridgeStepsSeveral : kEarlyBridgeSteps)) {
      // Stalling: a passage takes a few steps. Bridged now, if the bridge can be trusted;
      // the solver's failure below hands it to the integrator (Bridge returns it).
      m.early_tried = true;
      m.pend_y.assign(n, 0.0);
      if (BridgeChangePoint(p, m, m.early_rtol, m.early_atol, &m.pend_from, &m.pend_tb, m.pend_y.data()) == 0) {
        m.pending = true;
        m.error = StuckMessage(p, m, t, ", and the bridge over it could not be used here");
        m.own_error = true;
        return -1;
      }
      // Refused: the solver goes on (the stop at kMaxZoneSteps tries the bridge once more).
    }
    if (m.zone_steps > kMaxZoneSteps) {
      // The hint names the other form (the chain of 40 at rtol 1e-12 passes on the reduced form
      // with every integrator where the multiplier form stalls with CVODE).
      m.error = StuckMessage(p, m, t,
                             m.sparse ? "; near it the loop equations are too ill-conditioned for this tolerance (try a "
                                        "looser --rtol, or --solver dense)"
                                      : "; near it the loop equations are too ill-conditioned for this tolerance (try a "
                                        "looser --rtol, or --solver sparse)");
      m.own_error = true;
      return -1;
    }
  } else {
    m.in_zone = false;
    m.bridged = false;
    KeepBeforeZone(m, t, s.rho, y, n);
  }
  if ((s.near || was_in_zone) && !was_bridged && !m.passage_checked && m.early_rtol > 0.0) {
    const int c = CheckPassage(p, m, t, y, s.near);
    m.own_error = c != 0;
    return c;
  }
  return 0;
}

}  // namespace kanesim::sim
