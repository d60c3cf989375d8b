// The branch monitor's state, shared by its two files (runtime/runtime.h declares the interface):
// branch_monitor.cpp checks each accepted step against a turn onto another branch;
// change_point_bridge.cpp bridges a near-singular zone and checks a passage the solver
// made by itself (docs/constraints.md "Singular configurations").
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "runtime/program/program.h"

namespace kanesim::rt {

// <a, b> in the kinetic metric at the workspace's configuration (bodies' mass-centre and
// angular velocities: <V, V> = 2T); the branch monitor's turn and the bridge's speeds.
inline double Metric(const Program& p, const Workspace& ws, const std::vector<Vec3>& va, const std::vector<Vec3>& wa,
                     const std::vector<Vec3>& vb, const std::vector<Vec3>& wb) {
  double s = 0.0;
  for (size_t L = 0; L < p.bodies.size(); ++L) s += p.bodies[L].mass * va[L].dot(vb[L]) + wa[L].dot(ws.I_W[L] * wb[L]);
  return s;
}

struct BranchMonitor {
  std::unique_ptr<Workspace, void (*)(Workspace*)> ws{nullptr, [](Workspace*) {}};
  bool have_ref = false, in_zone = false;
  double ref_t = 0.0, zone_t = 0.0, zone_rho = 1.0;
  int zone_loop = -1;
  long zone_steps = 0;
  int zone_near = 0;  // loops near singular (rho < kZone) at the zone's latest accepted step
  bool projected_estimate = true;  // ... the multiplier form's estimate there taken after the projection (SetBridgeProjectedEstimate)
  double projected_est = -1.0;     // the last approach's projected estimate (-1: not taken)
  bool several_at_once = true;  // ... tried after 10 accepted steps there, not 50 (SetBridgeSeveralAtOnce)
  bool several_at_once_multiplier = false;  // ... also on the multiplier form (tests only)
  bool several_loops = true;  // the bridge's approach over zones with several loops near singular (SetBridgeSeveralLoops)
  std::vector<double> loop_length;  // per loop: its translation rows' scale, LoopLeverArm at the first check (m)
  Eigen::VectorXd ref_u, cur_u;     // all joint speeds
  std::vector<Vec3> cur_v, cur_w;  // the current step's mass-centre and angular velocities
  std::string error;
  // The bridge (BridgeChangePoint): the accepted steps of the current zone, the last one
  // before it first; the last accepted step (to start a zone's trace with).
  std::vector<double> trace_t, trace_rho;
  std::vector<std::vector<double>> trace_y;
  std::vector<double> pre_t, pre_rho;  // the last kPreZone accepted steps (outside a zone)
  std::vector<std::vector<double>> pre_y;
  bool bridged = false;  // this zone was bridged once: a second stall in it stops
  // The Hermite fit of the last bridge (three accepted steps: t, y, y'), for the output
  // rows in its gap (BridgeState).
  double h_t[3] = {0.0, 0.0, 0.0};
  std::vector<double> h_y[3], h_f[3];
  int h_first = 0;
  std::vector<double> nt, nrho;  // the bridge's own approach (Runge-Kutta nodes: t, y, y')
  std::vector<std::vector<double>> ny, nf;  // 0: the quintic through the three; 1: the cubic through the last two
  std::string bridge_refused;  // why the last bridge was refused
  // The early bridge (SetEarlyBridge): its tolerances (0: off), whether it was tried in this
  // zone, and a bridge computed by CheckBranch for the integrator's next Bridge call.
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
  long passages_checked = 0, passages_unchecked = 0;  // PassageCounts
};

// rho = sigma_min/sigma_max of the nearest-singular loop's rows at the configuration in
// m.ws (ConstraintJacobian done), and the count of loops near singular (rho < 1e-2) when
// near_loops is given; returns that loop (-1: none). In branch_monitor.cpp.
int NearestSingularLoop(const Program& p, BranchMonitor& m, double* rho_out, int* near_loops = nullptr);

// Checks a change point the solver passed by itself against the bridge's approach over it
// (0: it stands, 1: the step fails and the bridge replaces it, -1: fatal). In
// change_point_bridge.cpp.
int CheckPassage(const Program& p, BranchMonitor& m, double t, const double* y, bool near);

}  // namespace kanesim::rt
