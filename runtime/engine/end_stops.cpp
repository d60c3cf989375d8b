// End stops (runtime/runtime.h EndStops, InverseMassColumn): what the integrators' event
// handling (sim/end_stops.cpp) reads of the program: where each stop joint sits in the state,
// and the mass matrix's response to an impulse.
#include <algorithm>
#include <cmath>

#include "runtime/kane/kane.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

std::vector<EndStop> EndStops(const Program& p) {
  std::vector<EndStop> out;
  for (int b : p.stop_joints) {
    const TreeJoint& j = p.joints[static_cast<size_t>(b)];
    EndStop s;
    s.joint = j.name;
    s.q = static_cast<int>(std::find(p.q_free.begin(), p.q_free.end(), j.q0) - p.q_free.begin());
    s.u = p.u_free_of[static_cast<size_t>(j.u0)];
    s.q_min = j.q_min;
    s.q_max = j.q_max;
    s.restitution = j.restitution;
    out.push_back(s);
  }
  return out;
}

// Kane's equations are affine in the applied generalized forces: udot(Q + s e_k) - udot(Q)
// = s M^-1 e_k exactly. The second pass takes s so large that the difference is not lost
// in the rounding of udot(Q) (relative error ~ 1e-3 eps).
int InverseMassColumn(const Program& p, Workspace& ws, double t, const double* y, int k, double* x) {
  if (!p.rows.empty() || !p.friction_joints.empty()) {
    ws.error = p.rows.empty() ? "an impulse in a mechanism with Coulomb friction is not supported yet"
                              : "an impulse in a mechanism with closed loops or contacts is not supported yet";
    return -1;
  }
  std::vector<double> ydot(static_cast<size_t>(p.nq + p.nu));
  if (int s = Derivative(p, ws, t, y, ydot.data()); s != 0) return s;
  const double* a0 = ydot.data() + p.nq;
  double a_max = 0.0;
  for (int i = 0; i < p.nu; ++i) a_max = std::max(a_max, std::abs(a0[i]));
  const int full = p.u_free[static_cast<size_t>(k)];
  double scale = 1.0;
  for (int pass = 0; pass < 2; ++pass) {
    if (int s = AppliedForces(p, ws); s != 0) return s;
    ws.Q[full] += scale;
    if (int s = SolveAccelerations(p, ws); s != 0) return s;
    for (int i = 0; i < p.nu; ++i) x[i] = (ws.udot[p.u_free[static_cast<size_t>(i)]] - a0[i]) / scale;
    if (!(x[k] > 0.0)) {  // M is positive definite: (M^-1)_kk > 0
      ws.error = "the mass matrix is singular for an impulse on speed " + std::to_string(k);
      return -1;
    }
    scale = std::max(1.0, 1e3 * a_max / x[k]);
  }
  return 0;
}

}  // namespace kanesim::rt
