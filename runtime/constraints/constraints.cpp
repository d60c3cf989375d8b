// Loop-closure constraints: their rows, Jacobian, bias and the dependent speeds
// (runtime/constraints/constraints.h). The reduced equations (10) are kane/kane_reduced.cpp's.
//
// Every row is one scalar position constraint between frame a (body A) and frame b
// (body B) of a cut joint, r = p_Wb - p_Wa:
//   Translation  phi = d . r,             d = R_Wa d_a                                  (1)
//   Alignment    phi = e . n - offset,    e = R_Wa e_a,  n = R_Wb n_b                    (2)
// Their exact time derivatives are linear in the speeds (Lesser eq. 48, A u + b = 0):
//   (1)  phid = d . (v_b - v_a - w_A x r)                                               (3)
//   (2)  phid = k . (w_B - w_A),   k = n x e                                            (4)
// with v_a, v_b the velocities of the frame origins; a column r of A is (3)/(4) for the
// unit pseudo-speed u = e_r (seed 000 eq. 11.16). Differentiating once more with
// udot = 0 gives the acceleration bias c (seed 000 eq. 11.17):
//   (1)  c = (w_A x d) . s + d . (a_b - a_a - alpha_A x r - w_A x (v_b - v_a)),
//        s = v_b - v_a - w_A x r                                                        (5)
//   (2)  c = ((w_B x n) x e + n x (w_A x e)) . (w_B - w_A) + k . (alpha_B - alpha_A)     (6)
//
// Reduced equations (Lesser eqs. 49-51): the free speeds are split by column-pivoted QR
// of A into dependent ones (rank of them, pivot columns) and independent ones. With
// A_dep = Q R (least squares: redundant rows drop out),
//   u_dep = -A_dep^+ (A_ind u_ind + b)                                                  (7)
//   beta  = [1 on ind;  -A_dep^+ A_ind on dep]      (constrained tangent basis, eq. 51) (8)
//   udot  = beta z + udot_p,   udot_p = [0 on ind;  -A_dep^+ c on dep]                   (9)
//   (beta^T M beta) z = beta^T (f - M udot_p)        (Kane's equations on beta)         (10)
// The partition is kept while its block stays well conditioned (min/max |R_ii| above
// kDegraded) and re-chosen by pivoting when it degrades.
//
// A joint coupling (Program::couplings) joins the coordinates of two Revolute or Prismatic
// joints, leader l and follower f, whose speeds are their coordinates' rates
// (flat/mechanism.h), with a ratio r and an offset c:
//   phi = q_f - r q_l - c                                                              (11)
//   phid = u_f - r u_l        (A: 1 at u_f, -r at u_l when free; b: the prescribed)      (12)
//   c_bias = udot_f - r udot_l over the prescribed ones (free udot = 0)                  (13)
// The rows are exact and linear in q: Newton's step (7) lands on them in one iteration.
#include "runtime/constraints/constraints.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "runtime/constraints/contacts.h"
#include "runtime/kinematics/joint_kinematics.h"
#include "runtime/kinematics/kinematics.h"

namespace kanesim::rt {

namespace {

// Conditioning (min/max |R_ii|) of the dependent block below which the partition is
// re-chosen by pivoting; and below which, after re-choosing, the configuration is
// singular (a loop at a dead point: the Jacobian lost rank).
constexpr double kDegraded = 1e-2;
constexpr double kSingular = 1e-10;
// A turning point (docs/constraints.md "Turning points"): an independent speed passes zero
// and the kept block degrades while the loop's rows stay well conditioned; its projection
// amplifies the integrator's drift by 1 / ratio. Below kTurning a block of one loop's size
// (kToRoundOffMaxRank) is re-chosen by pivoting when that gains kTurnGain.
constexpr double kTurning = 0.2;
constexpr double kTurnGain = 2.0;
// ... checked again only once the block's ratio has fallen by kTurnRecheck since a check that
// found nothing better: at a change point pivoting finds the kept block at every evaluation in
// the band, and the pivoting QR there cost the single parallelogram 10-19 % of its instructions.
constexpr double kTurnRecheck = 0.5;
// From this many dependent speeds on, the order they are factored in is chosen by the fill
// of A_dep's QR (BandedOrder): a chain of loops has a block-banded A_dep, whose QR stays
// banded in the order of the rows the speeds move but fills in the pivoting order
// (small_qr.h; docs/benchmarks.md, "Change points"). The banded order is taken when its
// symbolic cost is below kBandedGain of the pivoting order's; otherwise, and below
// kBandedMinRank (where the dense QR costs microseconds), the pivoting order stays, which
// makes min/max |R_ii| rank-revealing at the moment the partition is chosen.
constexpr int kBandedMinRank = 16;
constexpr double kBandedGain = 0.5;
// Newton on positions: iterate to round-off (kTight) so that the right-hand side is a
// smooth function of y for difference-quotient Jacobians; fail above kLoose.
constexpr double kTight = kProjectTight;
constexpr double kLoose = 1e-8;
constexpr int kMaxNewton = kProjectMaxNewton;
// Near a singular configuration (pivot ratio below kDegraded) Newton goes on below kTight
// until the residual is at round-off (kRoundOff) or stops shrinking (by kStall per step).
constexpr double kRoundOff = 1e-16;
constexpr double kStall = 0.5;
// ... below kToRoundOff, not only below kDegraded: the reduced form's accelerations are off
// by ~c/rho^3 for the residual c Newton leaves (docs/constraints.md), 3e-7 relative at rho
// 9e-3 with c = 1e-13, which the bridge's approach and a solver's own passage carry
// (measured on the equal-link parallelogram at rtol 1e-12: 0.01 -> 3 of 10 reduced-form
// cells on the branch, 0.1 -> 5, 0.3 -> 6, 0.5 -> 10; docs/benchmarks.md "Change points").
constexpr double kToRoundOff = 0.5;
// ... for dependent blocks of one loop's size at most (a chain of loops' block has a pivot
// ratio below 0.5 everywhere: Newton to round-off at every evaluation cost ARKODE on the
// chain of ten at rtol 1e-9 its accuracy, 1.4e-4 rad off the lumped crank).
constexpr int kToRoundOffMaxRank = 6;
// A rolling disk lies flat when the sine of its axis' angle to the plane normal, |m| of
// contacts.cpp eq. 2, falls below kFlatSine (0.57 degrees: a thin disk's face reaches
// the plane, and the lowest rim point P is undefined at 0). A step that passes through
// flat is caught as well: P jumps to the opposite side of the rim, and the integrator's
// speeds give the new P a normal velocity of the order of |v_C| + r |w| (kJumped of it)
// instead of the integration error. Only within kNearFlat (30 degrees) of flat: farther
// out, a large normal velocity is the integrator's own drift off the velocity
// constraint at a loose tolerance (ARKODE at rtol 1e-3 on a disk wobbling between 2 and
// 19 degrees of lean reached 10 % of it), not a jump, and the step goes on as usual.
constexpr double kFlatSine = 1e-2;
constexpr double kJumped = 0.1;
constexpr double kNearFlat = 0.5;

// A cut joint's frame: its origin in W and the rotation of the body it is fixed on (the
// identity for the world). The rows' directions are stored in that body's axes
// (ConstraintRow::d_aB, n_bB), so the frame's own rotation is never formed.
struct FrameState {
  int body = -1;
  Vec3 p = Vec3::Zero();
  const Mat3* R = nullptr;
  Vec3 rho = Vec3::Zero();  // p - p_WB of the body (computed directly: no cancellation)
  Vec3 Dir(const Vec3& v_body) const { return R ? Vec3(*R * v_body) : v_body; }
};

FrameState FrameAt(const Program& p, const Workspace& ws, int frame) {
  const FramePlace& F = p.frames[static_cast<size_t>(frame)];
  FrameState f;
  f.body = F.body;
  if (F.body < 0) {
    f.p = F.p_BF;
    return f;
  }
  const auto B = static_cast<size_t>(F.body);
  f.R = &ws.R_WB[B];
  f.rho = ws.R_WB[B] * F.p_BF;
  f.p = ws.p_WB[B] + f.rho;
  return f;
}

// Acceleration of a frame origin with free udot = 0 (after BiasAccelerations), and its
// body's angular acceleration alpha.
Vec3 FrameBiasAccel(const Workspace& ws, const FrameState& f, Vec3* alpha) {
  alpha->setZero();
  if (f.body < 0) return Vec3::Zero();
  const auto B = static_cast<size_t>(f.body);
  const Vec3& rho = f.rho;
  *alpha = ws.alpha_bias[B];
  return ws.a_bias_o[B] + ws.alpha_bias[B].cross(rho) + ws.w_WB[B].cross(ws.w_WB[B].cross(rho));
}

// Row value of (3)/(4) for the point velocities/angular velocities given.
double RowRate(const ConstraintRow& row, const Vec3& d_or_k, const Vec3& r, const Vec3& v_a, const Vec3& w_A,
               const Vec3& v_b, const Vec3& w_B) {
  if (row.kind == RowKind::Translation) return d_or_k.dot(v_b - v_a - w_A.cross(r));
  return d_or_k.dot(w_B - w_A);
}

// Direction of a row: d (translation) or k = n x e (alignment), and r = p_b - p_a.
Vec3 RowDirection(const ConstraintRow& row, const FrameState& a, const FrameState& b) {
  if (row.kind == RowKind::Translation) return a.Dir(row.d_aB);
  return b.Dir(row.n_bB).cross(a.Dir(row.d_aB));
}

// A coupled joint's full speed (== its coordinate's place in u) and its free column, -1
// when prescribed.
int CoupledSpeed(const Program& p, int joint) { return p.joints[static_cast<size_t>(joint)].u0; }
int CoupledColumn(const Program& p, int joint) { return p.u_free_of[static_cast<size_t>(CoupledSpeed(p, joint))]; }

// (11) for every coupling, into ws.phi.
void CouplingResiduals(const Program& p, Workspace& ws) {
  for (const CouplingModel& c : p.couplings) {
    const int qf = p.joints[static_cast<size_t>(c.follower)].q0, ql = p.joints[static_cast<size_t>(c.leader)].q0;
    ws.phi[c.row] = ws.q[qf] - c.ratio * ws.q[ql] - c.offset;
  }
}

// (12): the active rows' entries of ws.A (their columns are zeroed by ZeroJacobian, the
// rows' bodies being the coupled joints' own: RowBodies) and, with `rates`, ws.psi.
void CouplingJacobian(const Program& p, Workspace& ws, bool rates) {
  for (const CouplingModel& c : p.couplings) {
    if (rates) ws.psi[c.row] = ws.u[CoupledSpeed(p, c.follower)] - c.ratio * ws.u[CoupledSpeed(p, c.leader)];
    const int k = p.active_of_row[static_cast<size_t>(c.row)];
    if (k < 0) continue;
    if (const int col = CoupledColumn(p, c.follower); col >= 0) ws.A(k, col) = 1.0;
    if (const int col = CoupledColumn(p, c.leader); col >= 0) ws.A(k, col) = -c.ratio;
  }
}

}  // namespace

std::string LoopOwners(const Program& p) {
  std::string names;
  for (const LoopClosure& l : p.loops) names += (names.empty() ? "'" : ", '") + l.name + "'";
  for (const ContactModel& c : p.contacts) names += (names.empty() ? "contact '" : ", contact '") + c.name + "'";
  for (const CouplingModel& c : p.couplings) names += (names.empty() ? "coupling '" : ", coupling '") + c.name + "'";
  return names;
}

// With ws.error: -1 (fatal) when a rolling disk lies flat, 1 (recoverable) when a step went
// through flat (after the positions are projected; ws.psi of the integrator's speeds).
int CheckDisksUpright(const Program& p, Workspace& ws) {
  for (const ContactModel& c : p.contacts) {
    if (c.type != flat::ContactType::RollingDisk) continue;
    const ContactPoint cp = ContactAt(p, ws, c);
    const double sin_flat = (c.n_W - c.n_W.dot(cp.e_W) * cp.e_W).norm();
    const Vec3 v_C = cp.vPm - cp.w.cross(cp.P - cp.C);
    const double jump = std::fabs(ws.psi[c.row0]) / (v_C.norm() + c.radius * cp.w.norm() + 1e-6);
    if (sin_flat >= kFlatSine && (jump <= kJumped || sin_flat >= kNearFlat)) continue;
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.3g degrees", std::asin(std::min(1.0, sin_flat)) * 180.0 / M_PI);
    ws.error = "rolling disk '" + c.name + "' " + (sin_flat < kFlatSine ? "lies flat on its plane" : "passed through flat") +
               " at time " + std::to_string(ws.t) + " (its axis " + buf +
               " from the plane normal): the lowest rim point is undefined there and the disk's face reaches the "
               "plane; the rolling contact ends (a fall, not modelled)";
    // Flat is the end of the model (fatal: retrying creeps towards it in ever smaller
    // steps); a jump may be a rejected trial step, so the integrator retries it smaller.
    return sin_flat < kFlatSine ? -1 : 1;
  }
  return 0;
}

namespace {

// A cut joint's two frames and, when asked, their motion: computed once for all its rows.
struct LoopFrames {
  FrameState a, b;
  Vec3 v_a = Vec3::Zero(), w_A = Vec3::Zero(), v_b = Vec3::Zero(), w_B = Vec3::Zero();
};

LoopFrames FramesOf(const Program& p, const Workspace& ws, const LoopClosure& l, bool motion) {
  LoopFrames f{FrameAt(p, ws, l.frame_a), FrameAt(p, ws, l.frame_b)};
  if (motion) {
    PointMotion(ws, f.a.body, f.a.rho, &f.v_a, &f.w_A);
    PointMotion(ws, f.b.body, f.b.rho, &f.v_b, &f.w_B);
  }
  return f;
}

}  // namespace

namespace {

// (1), (2) for a cut joint's rows, into ws.phi.
void LoopResiduals(const Program& p, Workspace& ws, const LoopClosure& l, const LoopFrames& f) {
  for (int i = l.row0; i < l.row0 + l.nrows; ++i) {
    const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
    if (row.kind == RowKind::Translation)
      ws.phi[i] = f.a.Dir(row.d_aB).dot(f.b.p - f.a.p);  // (1)
    else
      ws.phi[i] = f.a.Dir(row.d_aB).dot(f.b.Dir(row.n_bB)) - row.offset;  // (2)
  }
}

// (3), (4) for a cut joint's rows: the active ones into ws.A (zeroed by the caller), all
// into ws.psi (with `rates`). Each speed's twist column is carried to the frame point once
// for all the rows: v_s = H^v_s + H^w_s x (x - o_J), and then per row
//   translation: d . v_s (frame b),  -(d . v_s + (r x d) . H^w_s) (frame a: d . (w_A x r))
//   alignment:   k . H^w_s (b),  -k . H^w_s (a).
void LoopJacobian(const Program& p, Workspace& ws, const LoopClosure& l, const LoopFrames& f, bool rates = true) {
  const Vec3 r = f.b.p - f.a.p;
  // A cut joint has at most 5 rows (compile/loops.cpp CompileLoops), so the guard on na
  // below never drops one.
  constexpr int kMaxRows = 6;
  Vec3 dk[kMaxRows], rxd[kMaxRows];
  int active[kMaxRows];
  bool translation[kMaxRows];
  int na = 0;
  for (int i = l.row0; i < l.row0 + l.nrows; ++i) {
    const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
    const Vec3 d = RowDirection(row, f.a, f.b);
    if (rates) ws.psi[i] = RowRate(row, d, r, f.v_a, f.w_A, f.v_b, f.w_B);
    const int k = p.active_of_row[static_cast<size_t>(i)];
    if (k < 0 || na == kMaxRows) continue;
    dk[na] = d;
    translation[na] = row.kind == RowKind::Translation;
    rxd[na] = r.cross(d);
    active[na++] = k;
  }
  auto side = [&](const FrameState& fr, double sign, bool is_a) {
    if (fr.body < 0) return;
    for (int s : p.bodies[static_cast<size_t>(fr.body)].path_speeds) {
      const auto h = ws.H_W.col(s);
      const Vec3 hw = h.tail<3>();
      const Vec3 v = h.head<3>() + hw.cross(fr.p - ws.p_WB[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(s)])]);
      const int col = p.u_free_of[static_cast<size_t>(s)];
      for (int m = 0; m < na; ++m) {
        const double val = translation[m] ? dk[m].dot(v) + (is_a ? rxd[m].dot(hw) : 0.0) : dk[m].dot(hw);
        ws.A(active[m], col) += sign * val;
      }
    }
  };
  side(f.b, 1.0, false);
  side(f.a, -1.0, true);
}

void ContactResiduals(const Program& p, Workspace& ws, const ContactModel& c, const ContactPoint& cp) {
  for (int i = c.row0; i < c.row0 + c.nrows; ++i) ws.phi[i] = ContactResidual(p, p.rows[static_cast<size_t>(i)], cp);
}

void ContactJacobian(const Program& p, Workspace& ws, const ContactModel& c, const ContactPoint& cp) {
  for (int i = c.row0; i < c.row0 + c.nrows; ++i)
    ws.psi[i] = ContactJacobianRow(p, ws, p.rows[static_cast<size_t>(i)], p.active_of_row[static_cast<size_t>(i)], cp);
}

// Zeroes the entries of ws.A the Jacobians write (each free speed's column from the first to
// the last active row it moves, ws.col_rows of StructuralRows); the others are zero from
// InitConstraintWorkspace on, and nothing writes them. The chain of 40's A is 80 x 81 with
// ~4 entries a column: A.setZero() at every Newton iterate was 6 % of the reduced form's
// instructions (callgrind, DOP853 0.5 s; docs/benchmarks.md, "Cost of one evaluation").
void ZeroJacobian(const Program& p, Workspace& ws) {
  for (int s = 0; s < p.nu; ++s) {
    const int lo = ws.col_rows[2 * static_cast<size_t>(s)], hi = ws.col_rows[2 * static_cast<size_t>(s) + 1];
    if (hi >= lo) ws.A.col(s).segment(lo, hi - lo + 1).setZero();
  }
}

// ConstraintResiduals and ConstraintJacobian at the same positions, as each projection
// iterate needs both: the frames and contact points are placed once for the two.
void ResidualsAndJacobian(const Program& p, Workspace& ws) {
  ZeroJacobian(p, ws);
  for (const LoopClosure& l : p.loops) {
    const LoopFrames f = FramesOf(p, ws, l, true);
    LoopResiduals(p, ws, l, f);
    LoopJacobian(p, ws, l, f);
  }
  for (const ContactModel& c : p.contacts) {
    const ContactPoint cp = ContactAt(p, ws, c);
    ContactResiduals(p, ws, c, cp);
    ContactJacobian(p, ws, c, cp);
  }
  CouplingResiduals(p, ws);
  CouplingJacobian(p, ws, true);
}

}  // namespace

void ConstraintResiduals(const Program& p, Workspace& ws) {
  for (const LoopClosure& l : p.loops) LoopResiduals(p, ws, l, FramesOf(p, ws, l, false));
  for (const ContactModel& c : p.contacts) ContactResiduals(p, ws, c, ContactAt(p, ws, c));
  CouplingResiduals(p, ws);
}

void ConstraintJacobian(const Program& p, Workspace& ws) {
  ZeroJacobian(p, ws);
  for (const LoopClosure& l : p.loops) LoopJacobian(p, ws, l, FramesOf(p, ws, l, true));
  for (const ContactModel& c : p.contacts) ContactJacobian(p, ws, c, ContactAt(p, ws, c));
  CouplingJacobian(p, ws, true);
}

void LoopJacobianRows(const Program& p, Workspace& ws, int loop) {
  const LoopClosure& l = p.loops[static_cast<size_t>(loop)];
  for (int i = l.row0; i < l.row0 + l.nrows; ++i)
    if (int k = p.active_of_row[static_cast<size_t>(i)]; k >= 0) ws.A.row(k).setZero();
  LoopJacobian(p, ws, l, FramesOf(p, ws, l, false), false);
}

double LoopLeverArm(const Program& p, const Workspace& ws, int loop) {
  const LoopClosure& l = p.loops[static_cast<size_t>(loop)];
  double st = 0.0, sa = 0.0;
  int nt = 0, na = 0;
  for (int i = l.row0; i < l.row0 + l.nrows; ++i) {
    const int k = p.active_of_row[static_cast<size_t>(i)];
    if (k < 0) continue;
    const double s = ws.A.row(k).squaredNorm();
    if (p.rows[static_cast<size_t>(i)].kind == RowKind::Translation) {
      st += s;
      ++nt;
    } else {
      sa += s;
      ++na;
    }
  }
  if (nt == 0 || na == 0 || !(st > 0.0) || !(sa > 0.0)) return 1.0;
  return std::sqrt((st / nt) / (sa / na));
}

void ConstraintColumn(const Program& p, const Workspace& ws, int s, Eigen::VectorXd* col) {
  const int J = p.joint_of_speed[static_cast<size_t>(s)];
  const auto h = ws.H_W.col(s);
  const Vec3 hw = h.tail<3>();
  // Does speed s move body X? (J on X's path from the root.)
  auto moves = [&](int X) {
    for (int L = X; L >= 0; L = p.joints[static_cast<size_t>(L)].parent)
      if (L == J) return true;
    return false;
  };
  for (size_t ii = 0; ii < p.rows.size(); ++ii) {
    const ConstraintRow& row = p.rows[ii];
    if (row.contact >= 0) {
      (*col)[static_cast<Eigen::Index>(ii)] = ContactColumn(p, ws, row, s);
      continue;
    }
    if (row.coupling >= 0) {  // (12)
      const CouplingModel& c = p.couplings[static_cast<size_t>(row.coupling)];
      (*col)[static_cast<Eigen::Index>(ii)] =
          (s == CoupledSpeed(p, c.follower) ? 1.0 : 0.0) - (s == CoupledSpeed(p, c.leader) ? c.ratio : 0.0);
      continue;
    }
    const LoopClosure& l = p.loops[static_cast<size_t>(row.loop)];
    const FrameState a = FrameAt(p, ws, l.frame_a), b = FrameAt(p, ws, l.frame_b);
    const Vec3 dk = RowDirection(row, a, b);
    const Vec3 r = b.p - a.p;
    const Vec3 o = ws.p_WB[static_cast<size_t>(J)];
    Vec3 v_a = Vec3::Zero(), w_A = Vec3::Zero(), v_b = Vec3::Zero(), w_B = Vec3::Zero();
    if (moves(a.body)) {
      w_A = hw;
      v_a = h.head<3>() + hw.cross(a.p - o);
    }
    if (moves(b.body)) {
      w_B = hw;
      v_b = h.head<3>() + hw.cross(b.p - o);
    }
    (*col)[static_cast<Eigen::Index>(ii)] = RowRate(row, dk, r, v_a, w_A, v_b, w_B);
  }
}

void ConstraintBias(const Program& p, Workspace& ws) {
  // The reduced path reads the active rows only (SolveConstrained); the sparse path its
  // own selection of rows (kane_sparse.cpp kept_rows), so every row there.
  const bool all_rows = p.solver == SolverPath::Sparse;
  for (const LoopClosure& l : p.loops) {
    const LoopFrames f = FramesOf(p, ws, l, true);
    Vec3 alpha_A, alpha_B;
    const Vec3 a_a = FrameBiasAccel(ws, f.a, &alpha_A);
    const Vec3 a_b = FrameBiasAccel(ws, f.b, &alpha_B);
    for (int i = l.row0; i < l.row0 + l.nrows; ++i) {
      if (!all_rows && p.active_of_row[static_cast<size_t>(i)] < 0) continue;
      const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
      double c;
      if (row.kind == RowKind::Translation) {
        const Vec3 d = f.a.Dir(row.d_aB), r = f.b.p - f.a.p;
        const Vec3 s = f.v_b - f.v_a - f.w_A.cross(r);
        c = f.w_A.cross(d).dot(s) + d.dot(a_b - a_a - alpha_A.cross(r) - f.w_A.cross(f.v_b - f.v_a));  // (5)
      } else {
        const Vec3 e = f.a.Dir(row.d_aB), n = f.b.Dir(row.n_bB);
        c = (f.w_B.cross(n).cross(e) + n.cross(f.w_A.cross(e))).dot(f.w_B - f.w_A) +
            n.cross(e).dot(alpha_B - alpha_A);  // (6)
      }
      ws.cbias[i] = c;
    }
  }
  for (const ContactModel& c : p.contacts) {
    const ContactPoint cp = ContactAt(p, ws, c);
    for (int i = c.row0; i < c.row0 + c.nrows; ++i) ws.cbias[i] = ContactBias(p, ws, p.rows[static_cast<size_t>(i)], cp);
  }
  auto prescribed_udot = [&](int joint) { return CoupledColumn(p, joint) < 0 ? ws.udot[CoupledSpeed(p, joint)] : 0.0; };
  for (const CouplingModel& c : p.couplings)
    ws.cbias[c.row] = prescribed_udot(c.follower) - c.ratio * prescribed_udot(c.leader);  // (13)
}

namespace {
// min/max |R_ii| of the dependent block's factorization (FactorDependent's pivot ratio).
double DependentRatio(const Workspace& ws, int rank) {
  double mn = INFINITY, mx = 0.0;
  for (int k = 0; k < rank; ++k) {
    mn = std::min(mn, ws.qr_dep.DiagAbs(k));
    mx = std::max(mx, ws.qr_dep.DiagAbs(k));
  }
  return mx > 0.0 ? mn / mx : 0.0;
}
}  // namespace

namespace {
// Multiply-adds of SmallQR::Compute on the columns of the dependent speeds order[0 .. rank) in
// that order, from the structural extents ws.col_rows alone: reflector k spans rows k .. end_k,
// and touches the later columns whose extents overlap it, widening them (small_qr.h).
// O(rank^2). The sum only grows, so it stops once it reaches `cap` (returning at least cap).
double SymbolicQRCost(Workspace& ws, const int* order, int rank, double cap) {
  int* lo = ws.order_scratch.data() + rank;
  int* hi = lo + rank;
  for (int j = 0; j < rank; ++j) {
    const auto s = static_cast<size_t>(order[j]);
    lo[j] = ws.col_rows[2 * s];
    hi[j] = ws.col_rows[2 * s + 1] + 1;
  }
  double cost = 0.0;
  for (int k = 0; k < rank && cost < cap; ++k) {
    const int end = std::max(hi[k], k + 1);
    for (int j = k + 1; j < rank; ++j) {
      if (std::max(lo[j], k) >= std::min(hi[j], end)) continue;
      cost += end - k;
      lo[j] = std::min(lo[j], k);
      hi[j] = std::max(hi[j], end);
    }
  }
  return cost;
}

// The dependent speeds sorted by the first active row they move, then the last (ws.col_rows;
// rows are numbered loop by loop), when that makes A_dep's QR at least 1 / kBandedGain
// times cheaper than in the pivoting order: for a chain of loops A_dep becomes
// block-banded, and its Householder QR creates no fill outside the band. Insertion sort:
// stable, and no allocation. The pivoting order's cost is counted only up to the banded
// one's / kBandedGain, which decides (the chain of 40: 4.5 % of the reduced form's
// instructions went to the two counts in full, callgrind DOP853 0.5 s).
void BandedOrder(Workspace& ws, int rank) {
  const auto key = [&](int s) {
    return std::make_pair(ws.col_rows[2 * static_cast<size_t>(s)], ws.col_rows[2 * static_cast<size_t>(s) + 1]);
  };
  std::copy(ws.dep.begin(), ws.dep.end(), ws.order_scratch.begin());
  for (int i = 1; i < rank; ++i) {
    const int s = ws.dep[static_cast<size_t>(i)];
    int j = i;
    for (; j > 0 && key(s) < key(ws.dep[static_cast<size_t>(j - 1)]); --j)
      ws.dep[static_cast<size_t>(j)] = ws.dep[static_cast<size_t>(j - 1)];
    ws.dep[static_cast<size_t>(j)] = s;
  }
  const double banded = SymbolicQRCost(ws, ws.dep.data(), rank, INFINITY);
  const double pivoting = SymbolicQRCost(ws, ws.order_scratch.data(), rank, banded / kBandedGain);
  ws.dep_banded = banded <= kBandedGain * pivoting;
  if (!ws.dep_banded) std::copy(ws.order_scratch.begin(), ws.order_scratch.begin() + rank, ws.dep.begin());
}

// ws.col_rows: for each free speed s, the first and last active row whose bodies it moves
// (its joint on the path from either body of the row to the root); (n_a, -1) for none.
void StructuralRows(const Program& p, Workspace& ws) {
  const auto na = static_cast<int>(p.active_rows.size());
  ws.col_rows.assign(2 * static_cast<size_t>(p.nu), 0);
  for (int s = 0; s < p.nu; ++s) {
    const int J = p.joint_of_speed[static_cast<size_t>(p.u_free[static_cast<size_t>(s)])];
    const auto moves = [&](int X) {
      for (int L = X; L >= 0; L = p.joints[static_cast<size_t>(L)].parent)
        if (L == J) return true;
      return false;
    };
    int lo = na, hi = -1;
    for (int k = 0; k < na; ++k) {
      int a = -1, b = -1;
      RowBodies(p, p.active_rows[static_cast<size_t>(k)], &a, &b);
      if (moves(a) || moves(b)) {
        lo = std::min(lo, k);
        hi = k;
      }
    }
    ws.col_rows[2 * static_cast<size_t>(s)] = lo;
    ws.col_rows[2 * static_cast<size_t>(s) + 1] = hi;
  }
}

// Factors ws.A by column pivoting (ws.qr_A, its first rank pivots) and says whether that
// choice's block is at least kTurnGain times better conditioned than the kept one's (pivot
// ratio q): the loop's rows are well conditioned where its kept block is not, a turning
// point. At a change point the rows lose rank as a whole and pivoting picks the kept block
// again (the same ratio).
bool PivotingIsBetter(Workspace& ws, int rank, double q) {
  ws.qr_A.Compute(ws.A, rank);
  double mn = INFINITY, mx = 0.0;
  for (int k = 0; k < rank; ++k) {
    mn = std::min(mn, ws.qr_A.DiagAbs(k));
    mx = std::max(mx, ws.qr_A.DiagAbs(k));
  }
  return mx > 0.0 && mn >= kTurnGain * q * mx;
}
}  // namespace

int FactorDependent(const Program& p, Workspace& ws) {
  const int rank = p.loop_rank;
  if (rank == 0) return 0;
  auto ratio = [&]() {
    for (int k = 0; k < rank; ++k) ws.A_dep.col(k) = ws.A.col(ws.dep[static_cast<size_t>(k)]);
    ws.qr_dep.Compute(ws.A_dep);
    double mn = INFINITY, mx = 0.0;
    for (int k = 0; k < rank; ++k) {
      mn = std::min(mn, ws.qr_dep.DiagAbs(k));
      mx = std::max(mx, ws.qr_dep.DiagAbs(k));
    }
    return mx > 0.0 ? mn / mx : 0.0;
  };
  auto adopt = [&]() {
    const auto& perm = ws.qr_A.Indices();
    for (int k = 0; k < rank; ++k) ws.dep[static_cast<size_t>(k)] = perm[k];
    ws.dep_banded = false;
    if (rank >= kBandedMinRank) BandedOrder(ws, rank);
    // Independent speeds in increasing order (deterministic beta columns).
    int n = 0;
    for (int s = 0; s < p.nu; ++s) {
      bool d = false;
      for (int k = 0; k < rank; ++k) d = d || ws.dep[static_cast<size_t>(k)] == s;
      if (!d) ws.ind[static_cast<size_t>(n++)] = s;
    }
    ws.partition_valid = true;
    ws.turn_checked = INFINITY;
    ++ws.partition_changes;
  };
  auto choose = [&]() {
    ws.qr_A.Compute(ws.A, rank);  // only the first rank pivots are used
    adopt();
  };
  bool fresh = false;
  if (!ws.partition_valid) {
    choose();
    fresh = true;
  }
  double q = ratio();
  // Held (HoldPartition: the perturbed evaluations of a difference-quotient Jacobian),
  // a degraded partition is kept, so that every column is a derivative of the same
  // function; only a singular one is re-chosen.
  if (q < (ws.hold_partition ? kSingular : kDegraded) && !fresh) {
    choose();
    q = ratio();
  } else if (q < kTurning && !fresh && !ws.hold_partition && rank <= kToRoundOffMaxRank &&
             q < kTurnRecheck * ws.turn_checked) {
    if (PivotingIsBetter(ws, rank, q)) {
      adopt();
      q = ratio();
    } else {
      ws.turn_checked = q;
    }
  }
  if (q >= kTurning) ws.turn_checked = INFINITY;
  if (q < kSingular) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.2g", q);
    ws.error = "closed loop " + LoopOwners(p) + " at a singular configuration at time " + std::to_string(ws.t) +
               ": the constraint Jacobian lost rank (pivot ratio " + buf +
               "; a change point where assembly branches meet, or a dead point), so the loop equations do not "
               "determine the motion through it";
    return 1;
  }
  return 0;
}

void GatherActive(const Program& p, const Eigen::VectorXd& full, Eigen::VectorXd* active) {
  for (size_t k = 0; k < p.active_rows.size(); ++k) (*active)[static_cast<Eigen::Index>(k)] = full[p.active_rows[k]];
}

void SolveDependent(const Workspace& ws, const Eigen::VectorXd& v, Eigen::VectorXd* x) {
  *x = v;  // both have the active rows' size: no allocation; Q^T v in place, then R^-1
  ws.qr_dep.ApplyQt(x);
  ws.qr_dep.SolveR(x->data());
}

void ApplyCoordinateStep(const Program& p, Workspace& ws, const Eigen::VectorXd& du) {
  std::string unused;
  for (const TreeJoint& j : p.joints) {
    bool any = false;
    for (int k = 0; k < j.nu; ++k) any = any || du[j.u0 + k] != 0.0;
    if (!any) continue;
    double dq[7];
    if (!JointKinematicDifferential(j, ws.q.data() + j.q0, du.data() + j.u0, dq, &unused)) continue;
    for (int k = 0; k < j.nq; ++k) ws.q[j.q0 + k] += dq[k];
    const bool quat = (j.type == flat::JointType::Spherical || j.type == flat::JointType::Free) &&
                      j.rotation == flat::RotationCoords::Quaternion;
    if (quat) {
      const int r0 = j.q0 + (j.type == flat::JointType::Free ? 3 : 0);
      ws.q.segment<4>(r0).normalize();
    }
  }
}

void RowBodies(const Program& p, int i, int* body_a, int* body_b) {
  const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
  if (row.coupling >= 0) {  // the bodies the coupled joints move (joint L moves body L)
    *body_a = p.couplings[static_cast<size_t>(row.coupling)].leader;
    *body_b = p.couplings[static_cast<size_t>(row.coupling)].follower;
    return;
  }
  if (row.contact >= 0) {
    *body_a = p.contacts[static_cast<size_t>(row.contact)].body;
    *body_b = -1;
    return;
  }
  const LoopClosure& l = p.loops[static_cast<size_t>(row.loop)];
  *body_a = std::max(-1, p.frames[static_cast<size_t>(l.frame_a)].body);
  *body_b = std::max(-1, p.frames[static_cast<size_t>(l.frame_b)].body);
}

// (3), (4) and contacts.cpp eq. 4 on the mass-centre twists, c the mass centre:
//   translation  J_b = [d; (p_b - c_B) x d],   J_a = -[d; (p_b - c_A) x d]
//   alignment    J_b = [0; k],                 J_a = -[0; k]
//   contact      J   = [d; (P - c) x d]
// A coupling row reads four bodies' twists and has none: the sparse path does not take
// couplings (compiler/loops.cpp ChooseLoopSolver), and its rows stay zero here.
void RowJacobians(const Program& p, const Workspace& ws, int i, Vec6* Ja, Vec6* Jb) {
  Ja->setZero();
  Jb->setZero();
  const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
  if (row.coupling >= 0) return;
  if (row.contact >= 0) {
    const ContactModel& c = p.contacts[static_cast<size_t>(row.contact)];
    if (c.body < 0) return;
    const ContactPoint cp = ContactAt(p, ws, c);
    const Vec3 d = ContactRowDirection(c, row, cp, nullptr);
    Ja->head<3>() = d;
    Ja->tail<3>() = (cp.P - ws.p_WBcm[static_cast<size_t>(c.body)]).cross(d);
    return;
  }
  const LoopClosure& l = p.loops[static_cast<size_t>(row.loop)];
  const FrameState a = FrameAt(p, ws, l.frame_a), b = FrameAt(p, ws, l.frame_b);
  const Vec3 dk = RowDirection(row, a, b);
  if (row.kind == RowKind::Translation) {
    if (b.body >= 0) *Jb << dk, (b.p - ws.p_WBcm[static_cast<size_t>(b.body)]).cross(dk);
    if (a.body >= 0) *Ja << -dk, -(b.p - ws.p_WBcm[static_cast<size_t>(a.body)]).cross(dk);
  } else {
    if (b.body >= 0) Jb->tail<3>() = dk;
    if (a.body >= 0) Ja->tail<3>() = -dk;
  }
}

void ConstraintRates(const Program& p, Workspace& ws) {
  for (const LoopClosure& l : p.loops) {
    const LoopFrames f = FramesOf(p, ws, l, true);
    for (int i = l.row0; i < l.row0 + l.nrows; ++i) {
      const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
      ws.psi[i] = RowRate(row, RowDirection(row, f.a, f.b), f.b.p - f.a.p, f.v_a, f.w_A, f.v_b, f.w_B);
    }
  }
  for (const ContactModel& c : p.contacts) {
    const ContactPoint cp = ContactAt(p, ws, c);
    for (int i = c.row0; i < c.row0 + c.nrows; ++i)
      ws.psi[i] = ContactRowDirection(c, p.rows[static_cast<size_t>(i)], cp, nullptr).dot(cp.vPm);
  }
  for (const CouplingModel& c : p.couplings)
    ws.psi[c.row] = ws.u[CoupledSpeed(p, c.follower)] - c.ratio * ws.u[CoupledSpeed(p, c.leader)];  // (12)
}

int CheckLoopsClosed(const Program& p, Workspace& ws) {
  const double r = ws.phi.cwiseAbs().maxCoeff();
  if (r <= kLoose * p.loop_length) return 0;
  char buf[160];  // %g: a residual of 2e-7 is not "0.000000"
  std::snprintf(buf, sizeof buf, "closed loop cannot be closed (position residual %.3g m, above %.3g, at time %.9g)", r,
                kLoose * p.loop_length, ws.t);
  ws.error = buf;
  return 1;
}

void StepCoordinates(const Program& p, Workspace& ws) {
  ApplyCoordinateStep(p, ws, ws.du_full);
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
}

namespace {

// After A and its factorization at the final positions: the rolling disks' check, then the
// dependent speeds from the velocity constraints (7), u_dep -= A_dep^+ (A u + b), and the
// velocity kinematics of the new speeds. 0, or 1 (recoverable).
int SolveDependentSpeeds(const Program& p, Workspace& ws) {
  if (int s = CheckDisksUpright(p, ws); s != 0) return s;
  const int rank = p.loop_rank;
  if (rank == 0) return 0;
  GatherActive(p, ws.psi, &ws.active_rhs);
  SolveDependent(ws, ws.active_rhs, &ws.dep_solution);
  for (int k = 0; k < rank; ++k) ws.u[p.u_free[static_cast<size_t>(ws.dep[static_cast<size_t>(k)])]] -= ws.dep_solution[k];
  VelocityKinematics(p, ws);
  return 0;
}

}  // namespace

int ProjectStateByPartition(const Program& p, Workspace& ws) {
  if (p.rows.empty()) return 0;
  const double tight = kTight * p.loop_length;
  const int rank = p.loop_rank;
  double last = INFINITY;
  for (int it = 0;; ++it) {
    ResidualsAndJacobian(p, ws);
    if (int s = FactorDependent(p, ws); s != 0) return s;
    const double r = ws.phi.cwiseAbs().maxCoeff();
    if (rank == 0 || it == kMaxNewton) break;
    // Near a singular configuration, on to round-off: a residual c leaves the state on
    // the level set phi = c, which bends from one branch onto another within sqrt(c) of
    // a change point (docs/constraints.md, "Singular configurations").
    if (r <= tight && (r <= kRoundOff * p.loop_length || r > kStall * last || DependentRatio(ws, rank) >= (rank <= kToRoundOffMaxRank || ws.newton_to_round_off ? kToRoundOff : kDegraded)))
      break;
    last = r;
    // Newton step on the dependent coordinates: A_dep du_dep = -phi (7).
    GatherActive(p, ws.phi, &ws.active_rhs);
    SolveDependent(ws, ws.active_rhs, &ws.dep_solution);
    ws.du_full.setZero();
    for (int k = 0; k < rank; ++k) ws.du_full[p.u_free[static_cast<size_t>(ws.dep[static_cast<size_t>(k)])]] = -ws.dep_solution[k];
    StepCoordinates(p, ws);
  }
  if (int s = CheckLoopsClosed(p, ws); s != 0) return s;
  return SolveDependentSpeeds(p, ws);
}

int FactorConstraintsAsIs(const Program& p, Workspace& ws) {
  if (p.rows.empty()) return 0;
  // A without residuals (nothing here reads them), and without the loops' rates A u + b
  // (only the disks' check reads rates: the contacts' rows).
  ZeroJacobian(p, ws);
  for (const LoopClosure& l : p.loops) LoopJacobian(p, ws, l, FramesOf(p, ws, l, false), false);
  for (const ContactModel& c : p.contacts) ContactJacobian(p, ws, c, ContactAt(p, ws, c));
  CouplingJacobian(p, ws, false);
  if (int s = FactorDependent(p, ws); s != 0) return s;
  return CheckDisksUpright(p, ws);
}

void InitConstraintWorkspace(const Program& p, Workspace& ws) {
  const auto nc = static_cast<Eigen::Index>(p.rows.size());
  const auto na = static_cast<Eigen::Index>(p.active_rows.size());
  const int rank = p.loop_rank, nind = p.nu - rank;
  ws.phi = Eigen::VectorXd::Zero(nc);
  ws.phi_drift = Eigen::VectorXd::Zero(nc);
  ws.psi = Eigen::VectorXd::Zero(nc);
  ws.cbias = Eigen::VectorXd::Zero(nc);
  ws.lambda_active = Eigen::VectorXd::Zero(na);
  ws.dep_solution = Eigen::VectorXd::Zero(na);
  ws.active_rhs = Eigen::VectorXd::Zero(na);
  ws.vcol = Eigen::VectorXd::Zero(nc);
  ws.du_full = Eigen::VectorXd::Zero(p.nu_all);
  ws.A = Eigen::MatrixXd::Zero(na, p.nu);
  ws.A_dep = Eigen::MatrixXd::Zero(na, rank);
  ws.qr_A.Resize(na, p.nu);
  ws.qr_dep.Resize(na, rank);
  ws.dep.assign(static_cast<size_t>(rank), 0);
  ws.ind.assign(static_cast<size_t>(nind), 0);
  ws.partition_valid = false;
  StructuralRows(p, ws);
  ws.order_scratch.assign(3 * static_cast<size_t>(rank), 0);
  ws.beta = Eigen::MatrixXd::Zero(p.nu, nind);
  ws.MB = Eigen::MatrixXd::Zero(p.nu, nind);
  ws.Mr = Eigen::MatrixXd::Zero(nind, nind);
  ws.fr = Eigen::VectorXd::Zero(nind);
  ws.udot_p = Eigen::VectorXd::Zero(p.nu);
  ws.llt_r.emplace(nind);
  if (p.reduce_by_passes) {  // (trees and the mass-matrix way: none)
    ws.beta_twists = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, static_cast<Eigen::Index>(p.bodies.size()) * nind);
    ws.accel_p.assign(p.bodies.size(), Vec6::Zero());
  }
  ws.lambda_c = Eigen::VectorXd::Zero(nc);
  ws.g_dep = Eigen::VectorXd::Zero(nc);
  ws.reaction_W.assign(p.bodies.size(), Vec6::Zero());
}

}  // namespace kanesim::rt
