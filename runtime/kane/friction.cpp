// Coulomb friction in prismatic and revolute joints whose magnitude follows the joint's
// normal force (the seed's dry-friction case, Lesser §3c: a force law that depends on a
// constraint force couples the tangent and the complement projections).
//
// For tree joint j with unit axis a (world), reaction force F_j on its child
// (runtime/constraints/reactions.cpp eq. 5) and speed u_j:
//   N_j = | F_j - (F_j . a) a |                       (normal force across the axis)   (1)
//   Q_f,j = -(mu_j r_j N_j + C_j) tanh(u_j / v_j)      (r_j = pin radius; 1 if prismatic) (2)
// with C_j the joint's constant friction (stdlib friction_torque / friction_force),
// regularized over the speed scale v_j (a bare sign() chatters where u_j crosses 0).
// N depends on the accelerations and the accelerations on Q_f, so both projections are
// solved together by the fixed-point iteration
//   Q_f^(k+1) = Q_f( N( udot( Q_f^(k) ) ) )                                               (3)
// warm-started from the last converged Q_f, until the change is below kTol (1 + |Q_f|);
// the accelerations are then solved once more with the converged Q_f. It converges when
// mu times the sensitivity of N to the joint's own force is below 1 (every case but
// self-locking wedges and Painleve-type states), linearly with that gain as its rate: a
// chain with mu r = 0.2 m on 0.5 m links contracts by 0.65 per iteration (~75 iterations
// from a cold start), so the iteration runs until the change stops shrinking, not for a
// fixed count. Where the gain is below -1 (the same chain a little later: Q_f flips
// between two values, N 67 <-> 46) the fixed point still exists and is unique (Q - Q_f(Q)
// is monotone) and the relaxed step
//   Q_f^(k+1) = Q_f^(k) + w (Q_f(N(udot(Q_f^(k)))) - Q_f^(k))                              (3')
// converges for w (1 - gain) in (0, 2): while the residual flips sign (a 2-cycle), w is
// halved when the change over two iterations did not shrink (kStagnant) kDiverging times in
// a row, down to kMinRelax; while it keeps its sign (a positive rate 1 + w (gain - 1)), a
// residual growing kDiverging times in a row, or a 2-cycle not shrinking at kMinRelax, is a
// gain >= 1, where no unique friction force exists (reported with the gain; recoverable: the
// integrator retries).
// When every friction joint has mu = 0, Q_f does not depend on N: one solve, no reactions.
#include <cmath>
#include <cstdio>

#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/constraints/reactions.h"

namespace kanesim::rt {

namespace {
constexpr double kTol = 1e-12;
// A bound only against a rate within round-off of 1 (a gain of 0.9 needs ~300 iterations).
constexpr int kMaxIterations = 2000;
// Two-iteration changes in a row not shrinking that halve w of (3') (at kMinRelax: diverging).
constexpr int kDiverging = 4;
// A two-iteration change ratio above this is not shrinking (a 2-cycle's hovers at 1 by
// round-off, either side; a contraction of 0.975 per iteration or slower is near gain 1).
constexpr double kStagnant = 0.95;
constexpr double kMinRelax = 1.0 / 64;  // w of (3'): a gain down to -127
}  // namespace

namespace {
// Eq. (2) for friction joint i (or exact stick-slip's law, sim/stick_slip.cpp: sliding by a
// sign, or stuck: the force that holds it) with normal force N.
double FrictionForce(const TreeJoint& j, const Workspace& ws, size_t i, double N) {
  const double r = j.type == flat::JointType::Revolute ? j.mu_radius : 1.0;
  const double slide = j.mu * r * N + j.friction_c;
  const int mode = ws.friction_mode[i];
  return mode == 0 ? -slide * std::tanh(ws.u[j.u0] / j.mu_v) : mode == 2 ? ws.friction_fixed[i] : -slide * mode;
}
}  // namespace

bool FrictionReadsNormalForce(const Program& p) {
  for (int b : p.friction_joints)
    if (p.joints[static_cast<size_t>(b)].mu != 0.0) return true;
  return false;
}

int SolveWithFriction(const Program& p, Workspace& ws, int (*path)(const Program&, Workspace&)) {
  const size_t nf = p.friction_joints.size();
  const bool reads_N = FrictionReadsNormalForce(p);
  for (size_t i = 0; i < nf; ++i) {
    const TreeJoint& j = p.joints[static_cast<size_t>(p.friction_joints[i])];
    ws.friction_Q0[i] = ws.Q[j.u0];
    ws.Q[j.u0] = ws.friction_Q0[i] + ws.friction_tau[i];
  }
  if (!reads_N) {  // constant friction only: Q_f known without the accelerations
    for (size_t i = 0; i < nf; ++i) {
      const TreeJoint& j = p.joints[static_cast<size_t>(p.friction_joints[i])];
      ws.friction_N[i] = 0.0;
      ws.friction_tau[i] = FrictionForce(j, ws, i, 0.0);
      ws.Q[j.u0] = ws.friction_Q0[i] + ws.friction_tau[i];
    }
    return path(p, ws);
  }
  double change_1 = 0.0, change_2 = 0.0, ratio = 0.0, w = 1.0;  // the last two changes; w of (3')
  int growths = 0, stalls = 0, slow = 0;  // counts in a row: residual growing; 2-cycle not shrinking; slow
  // For the report: the residual Q_f(...) - Q_f^(k) of (3')'s largest entry (its joint and
  // sign) in the last two iterations, and whether that joint's residual kept its sign.
  double res = 0.0, res_1 = 0.0, res_2 = 0.0, lead_r = 0.0;
  size_t lead = 0;
  bool same_sign = true;
  for (int it = 0; it < kMaxIterations; ++it) {
    if (int st = path(p, ws); st != 0) return st;
    ++ws.friction_iterations;
    BiasAccelerations(p, ws, /*include_free=*/true);
    LoopMultipliers(p, ws);
    JointReactions(p, ws);
    double change = 0.0, next_lead_r = 0.0;
    size_t next_lead = 0;
    res = 0.0;
    for (size_t i = 0; i < nf; ++i) {
      const auto L = static_cast<size_t>(p.friction_joints[i]);
      const TreeJoint& j = p.joints[L];
      const Vec3 a = ws.R_WB[L] * j.axis;  // the axis is fixed in both joint frames
      const Vec3 F = ws.reaction_W[L].head<3>();
      const double N = (F - F.dot(a) * a).norm();  // (1)
      const double tau = FrictionForce(j, ws, i, N);  // (2)
      ws.friction_N[i] = N;
      const double r = tau - ws.friction_tau[i];
      change = std::max(change, std::fabs(r) / (1.0 + std::fabs(tau)));
      if (i == lead) same_sign = r * lead_r >= 0.0;
      if (std::fabs(r) > res) {
        res = std::fabs(r);
        next_lead = i;
        next_lead_r = r;
      }
      ws.friction_tau[i] += w * (tau - ws.friction_tau[i]);  // (3')
      ws.Q[j.u0] = ws.friction_Q0[i] + ws.friction_tau[i];
    }
    BiasAccelerations(p, ws);  // back to free udot = 0 for the next solve
    if (change <= kTol) return path(p, ws);  // (3) converged: udot with the final Q_f
    if (!std::isfinite(change)) {
      ws.error = "Coulomb friction: the normal-force iteration met a non-finite friction force or normal force";
      return 1;
    }
    lead = next_lead;
    lead_r = next_lead_r;
    // Over two iterations (a 2-cycle's change repeats; a contraction's may rise once).
    if (it > 1) ratio = change / change_2;
    change_2 = change_1;
    change_1 = change;
    res_2 = res_1;
    res_1 = res;
    if (it <= 1) continue;
    if (same_sign) {
      // The leading residual keeps its sign: its rate 1 + w (g - 1) is positive, and a
      // smaller w only slows it (a gain of 0.954 converged in 520 iterations at w = 1; halved
      // on a transient, it was refused: sweep seed 53 trial 0). Not shrinking (the residual,
      // kDiverging times in a row) is g >= 1 whatever w; slow under a w an earlier 2-cycle
      // left: w doubled back.
      stalls = 0;
      const double rate = res_2 > 0.0 ? res_1 / res_2 : 0.0;
      growths = rate >= 1.0 ? growths + 1 : 0;
      if (growths >= kDiverging) break;
      slow = w < 1.0 && rate * rate >= kStagnant ? slow + 1 : 0;
      if (slow >= kDiverging) {
        w = std::min(1.0, 2.0 * w);
        slow = 0;
      }
      continue;
    }
    // A 2-cycle (the leading residual flips sign): relaxed, w halved while the change over
    // two iterations does not shrink.
    growths = slow = 0;
    stalls = ratio >= kStagnant ? stalls + 1 : 0;
    if (stalls < kDiverging) continue;
    if (w <= kMinRelax) break;
    w *= 0.5;
    stalls = 0;
  }
  // The map's gain g from the relaxed iteration: near a linear map its residual is
  // multiplied by rho = 1 + w (g - 1) per iteration, with rho < 0 where the leading joint's
  // residual flips sign every iteration.
  const double rho = res_2 > 0.0 ? res_1 / res_2 : 1.0;
  const double map_gain = same_sign ? 1.0 + (rho - 1.0) / w : 1.0 - (1.0 + rho) / w;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "Coulomb friction: no consistent friction force: the friction forces' feedback through the joints' "
                "normal forces has a gain of about %.3g (the normal-force iteration does not converge under "
                "relaxation %.3g; a gain of 1 or more: mu r too large for this state, a self-locking joint or a "
                "Painleve-type inconsistency)",
                map_gain, w);
  ws.error = buf;
  return 1;
}

}  // namespace kanesim::rt
