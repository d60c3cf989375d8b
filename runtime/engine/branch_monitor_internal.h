// The branch monitor's state, shared by its two files (runtime/runtime.h declares the interface):
// branch_monitor.cpp checks each accepted step against a turn onto another branch;
// change_point_measures.cpp measures and projects states for the bridge over a change point
// (sim/change_point_bridge.h; docs/constraints.md "Singular configurations").
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
// angular velocities: <V, V> = 2T); the branch monitor's turn and ProjectSpeedsInKineticMetric.
inline double Metric(const Program& p, const Workspace& ws, const std::vector<Vec3>& va, const std::vector<Vec3>& wa,
                     const std::vector<Vec3>& vb, const std::vector<Vec3>& wb) {
  double s = 0.0;
  for (size_t L = 0; L < p.bodies.size(); ++L) s += p.bodies[L].mass * va[L].dot(vb[L]) + wa[L].dot(ws.I_W[L] * wb[L]);
  return s;
}

// The tangent space's kinetic metric at y (closed loops, rolling contacts): beta (nu x nind,
// Derivative's, with its partition), Mr = beta^T M beta, and r = beta^T M (u_raw - u_y) when
// raw is given (else 0). Nonzero when y is not valid. In change_point_measures.cpp.
int TangentMetric(const Program& p, Workspace& ws, double t, const double* y, const double* raw, Eigen::MatrixXd* beta,
                  Eigen::MatrixXd* Mr, Eigen::VectorXd* r);

// x = W F, the speeds' jump for the impulse F with the rows' reactions (W = beta Mr^-1
// beta^T, the constrained inverse mass); -1 naming `what` where the rows fix F's motion.
// In end_stops.cpp.
int ConstrainedInverseMassTimes(const Program& p, Workspace& ws, double t, const double* y, const double* F,
                                const std::string& what, double* x);

// The plane contacts' normal forces lambda (one per contact, pushing: > 0) on their bodies at
// their points, among the applied forces (after AppliedForces): the joint reactions between a
// contact's body and the ground, and the constraint rows' where there are rows, carry them.
// In plane_contacts.cpp.
void AddPlaneForces(const Program& p, Workspace& ws, const double* lambda);

struct BranchMonitor {
  std::unique_ptr<Workspace, void (*)(Workspace*)> ws{nullptr, [](Workspace*) {}};
  bool have_ref = false, in_zone = false;
  double ref_t = 0.0, zone_t = 0.0, zone_rho = 1.0;
  int zone_loop = -1;
  std::vector<double> loop_length;  // per loop: its translation rows' scale, LoopLeverArm at the first check (m)
  Eigen::VectorXd ref_u, cur_u;     // all joint speeds
  std::vector<Vec3> cur_v, cur_w;  // the current step's mass-centre and angular velocities
  std::string error;
};

// rho = sigma_min/sigma_max of the nearest-singular loop's rows at the configuration in
// m.ws (ConstraintJacobian done), and the count of loops near singular (rho < 1e-2) when
// near_loops is given; returns that loop (-1: none). In branch_monitor.cpp.
int NearestSingularLoop(const Program& p, BranchMonitor& m, double* rho_out, int* near_loops = nullptr);

}  // namespace kanesim::rt
