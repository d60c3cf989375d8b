// The bridge over a change point of a closed loop (docs/constraints.md "Singular
// configurations"; issue 20). A solver approaching a change point at a tight tolerance
// shrinks its steps where the loop equations' conditioning degrades and stalls short of the
// crossing; the motion itself is smooth there, so the bridge integrates toward it by
// itself (classical Runge-Kutta with small fixed steps), extrapolates over it (Hermite) and
// a fresh solver starts past it. It also checks, against the same approach, a change point
// a solver passed by itself. What it reads of the loops (rho, the projections, the monitor's
// turn check) is the runtime's, through runtime/runtime.h.
//
// One per run, for a program with closed loops (rt::BranchMonitorActive). Internal to sim/:
// Simulate drives it through OdeSystem (StepAccepted, Bridge, BridgeState, InZone); tests
// include this header directly.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"

namespace kanesim::sim {

// Parts of the bridge that tests switch off to show what they do (sim/test_hooks.h).
struct BridgeSwitches {
  // The approach also over zones where several loops are near singular at once (a chain of
  // equal-link parallelograms). Off: such zones are refused.
  bool several_loops = true;
  // The early bridge over such a zone tried after 10 accepted steps in it instead of the 50th.
  bool several_at_once = true;
  // ... and on the multiplier form too (off: the trajectory on which DOP853's dense output
  // was seen off the branch, docs/constraints.md "Several loops").
  bool several_at_once_multiplier = false;
  // There, on the multiplier form, an error estimate above the bridge's limit taken again
  // between the extrapolations projected onto the constraints. Off: refused.
  bool projected_estimate = true;
};

struct ChangePointBridge {
  std::unique_ptr<rt::BranchMonitor, void (*)(rt::BranchMonitor*)> monitor{nullptr, [](rt::BranchMonitor*) {}};
  rt::Workspace* ws = nullptr;  // the monitor's (rt::MonitorWorkspace)
  bool sparse = false;          // the multiplier form (rt::SolverPath::Sparse)
  BridgeSwitches switches;
  // The zone (rho < 1e-2) of the latest accepted step, as the monitor measured it.
  bool in_zone = false;
  int zone_loop = -1, zone_near = 0;  // its loop; loops near singular at its latest step
  double zone_t = 0.0, zone_rho = 1.0;
  long zone_steps = 0;  // accepted steps in it since it began or was bridged
  std::string error;    // why the last StepAccepted failed, when the bridge's (else the monitor's)
  bool own_error = false;
  double projected_est = -1.0;  // the last approach's projected estimate (-1: not taken)
  // The accepted steps of the current zone, the last few before it first; the last kPreZone
  // accepted steps outside a zone (to start a zone's trace with).
  std::vector<double> trace_t, trace_rho;
  std::vector<std::vector<double>> trace_y;
  std::vector<double> pre_t, pre_rho;
  std::vector<std::vector<double>> pre_y;
  bool bridged = false;  // this zone was bridged once: a second stall in it stops
  // The Hermite fit of the last bridge (three accepted steps: t, y, y'), for the output
  // rows in its gap (BridgedState).
  double h_t[3] = {0.0, 0.0, 0.0};
  std::vector<double> h_y[3], h_f[3];
  int h_first = 0;                          // 0: the quintic through the three; 1: the cubic through the last two
  std::vector<double> nt, nrho;             // the bridge's own approach (Runge-Kutta nodes: t, y, y')
  std::vector<std::vector<double>> ny, nf;
  std::string bridge_refused;  // why the last bridge was refused
  // The early bridge (EnableEarlyBridge): its tolerances (0: off), whether it was tried in
  // this zone, and a bridge computed after an accepted step for the integrator's next Bridge.
  double early_rtol = 0.0, early_atol = 0.0;
  bool early_tried = false, pending = false;
  double pend_from = 0.0, pend_tb = 0.0;
  std::vector<double> pend_y;
  double bridge_estimate = 0.0;  // the last bridge's error estimate, in units of the tolerance
  double bridge_h = 0.0;         // the last approach's Runge-Kutta step
  // A passage the solver made by itself (CheckPassage): checked once per zone; the end of
  // the last bridge (a zone starting there was bridged).
  bool passage_checked = false;
  double last_tb = -INFINITY;
  long passages_checked = 0, passages_unchecked = 0;
};

// Null for a program without closed loops.
std::unique_ptr<ChangePointBridge> MakeChangePointBridge(const rt::Program& program);

// After each accepted step: the monitor's turn check (rt::CheckBranch), then the zone's
// bookkeeping. -1 (fatal; BridgeError says why) when the motion turned onto another branch,
// when the solver stalled in a zone (1000 accepted steps), or when an early bridge is ready
// (the step fails so that the integrator's next BridgeChangePoint returns it); else 0.
int CheckStep(const rt::Program& program, ChangePointBridge& bridge, double t, const double* y);
const std::string& BridgeError(const ChangePointBridge& bridge);

// After a solver failed inside a near-singular zone (stalled before a change point): a state
// y_b (StateSize entries) at time t_b just past the crossing, extrapolated from the zone's
// accepted steps and projected onto the constraints, from which a fresh solver goes on; the
// bridged motion is BridgedState on [t_from, t_b]. 0, or 1 when no bridge can be trusted
// (bridge_refused says why; the failure stands). Once per zone.
int BridgeChangePoint(const rt::Program& program, ChangePointBridge& bridge, double rtol, double atol, double* t_from,
                      double* t_b, double* y_b);
void BridgedState(const ChangePointBridge& bridge, double t, double* y);

// With these tolerances, CheckStep tries the bridge itself after 50 accepted steps inside
// one near-singular zone (a stall; a passage takes a few) and checks the change points the
// solver passes by itself against the bridge's approach.
void EnableEarlyBridge(ChangePointBridge& bridge, double rtol, double atol);

// The two fits (change_point_bridge.cpp) and the passage check, for CheckStep.
int BridgeByApproach(const rt::Program& p, ChangePointBridge& m, double rtol, double atol, double* t_from, double* t_b,
                     double* y_b);
int BridgeByZoneFit(const rt::Program& p, ChangePointBridge& m, double rtol, double atol, double* t_from, double* t_b,
                    double* y_b);
// Checks a change point the solver passed by itself against the bridge's approach over it
// (0: it stands, -1: the step fails and the bridge replaces it).
int CheckPassage(const rt::Program& p, ChangePointBridge& m, double t, const double* y, bool near);

}  // namespace kanesim::sim
