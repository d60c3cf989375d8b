// Sparse path: Newton-Euler per body, joined by per-joint kinematic rows, solved as one
// sparse linear system whose pattern is fixed at compile time (Lesser eqs. 26-29, 68-73).
//
// Unknowns per body L (block of 12): A_L = [a_L; alpha_L] (mass-centre and angular
// acceleration), the free udot of joint L (nf), and the constraint-force coefficients
// s_L (6 - nf) on the complement basis gamma_L of joint L. Rows per body:
//
//   kinematic (6):     A_L - X_LP A_P - S_L udot_L = kappa_L                          (1)
//   Newton-Euler (6):  Mb_L A_L - G_L gamma_L s_L + sum_C G_LC gamma_C s_C
//                        = W_L - [0; w_L x I_L w_L] + G_L W^Q_L - sum_C G_LC W^Q_C      (2)
// where
//   S_L       tangent block: columns tau_{L,r} = [H^v_r + H^w_r x (c_L - o_L); H^w_r]
//   X_LP      rigid transport of P's acceleration: a_L = a_P + alpha_P x (c_L - c_P)
//   kappa_L   = A_bias_L - X_LP A_bias_P (bias accelerations with free udot = 0)
//   gamma_L   orthonormal complement of the free columns of H_L (twists at o_L):
//             H_L^T gamma_L = 0, so the constraint wrench does no work (Lesser eq. 27)
//   G_L       moves a wrench at o_L to c_L: [f; t + (o_L - c_L) x f]
//   G_LC      the same from child joint point o_C to c_L
//   W^Q_L     = H_L (H_L^T H_L)^-1 Q_L: the joint force as a wrench with H_L^T W^Q = Q
//   lambda_L  = gamma_L s_L + W^Q_L: the wrench the parent exerts on L at o_L.
// Each block couples only a body, its parent and its children, so KLU factors a chain
// or tree in time linear in K (the symbolic analysis is done once at compile time).
//
// Closed loops and rolling contacts (the multiplier form; the reduced form is in
// constraints.cpp): each independent constraint row i adds one unknown mu_i and one row.
// A row reads the velocities of at most two bodies, d/dt phi_i = sum_L J_iL . [v_cm; w]_L
// (constraints.cpp RowJacobians), so on the mass-centre accelerations it is
//   constraint (1 per row):  sum_L J_iL . A_L = J_i . A_bias - c_i                      (3)
// (c_i the acceleration residual with free udot = 0, J_i . A_bias its body part), and its
// force J_iL mu_i enters the Newton-Euler rows (2) of those bodies:
//   Mb_L A_L - ... - sum_i J_iL mu_i = ...                                               (4)
// so mu = lambda of reactions.cpp (A^T lambda = M udot - f). The rows touch only the two
// bodies of a cut joint, so the system stays as sparse as the tree's. Rows that pivoted QR
// found redundant at the assembled start (Program::redundant_rows) are left out: their
// multipliers are zero, a particular solution of the indeterminate components. With a
// zero right side except -phi (or -psi) in the rows (3), the same matrix gives the
// smallest correction in the kinetic metric, du^T M du, that closes the constraints to
// first order: the projection ProjectStateSparse (at the end of this file).
#include <klu.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "runtime/constraints/constraints.h"
#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"

namespace kanesim::rt {

struct SparsePattern {
  int n = 0;                          // 12 K + kept constraint rows
  int n_body = 0;                     // 12 K
  std::vector<int> kept_rows;         // multiplier m -> constraint row (Program::rows) at the assembled start
  // A loop that keeps a redundant row that is not zero (compile/loops.cpp: an
  // overconstrained linkage) has more rows than multipliers; which of them the multipliers
  // take is re-chosen at every factorization (ChooseLoopRows), as any fixed choice loses
  // rank somewhere on the motion. Its rows all act on the same two bodies, so the
  // system's pattern is the same whichever it takes.
  struct RowChoice {
    int loop = -1;
    std::vector<int> mults;  // its multipliers
    std::vector<int> rows;   // its active rows (Program::rows)
  };
  std::vector<RowChoice> row_choices;
  std::vector<std::array<int, 2>> row_bodies;  // per multiplier: its bodies (-1: none), as RowBodies
  std::vector<int> Ap, Ai;            // CSC pattern
  std::vector<int> slot;              // entry number (visit order) -> CSC value index
  std::vector<std::vector<int>> children;
  std::vector<int> nf;                // free speeds per joint
  std::vector<std::vector<int>> free_speeds;  // full speed indices per joint
};

struct SparseSymbolic {
  klu_common common;
  klu_symbolic* symbolic = nullptr;
};

struct SparseNumeric {
  klu_common common;
  klu_numeric* numeric = nullptr;
  bool fresh = false;  // the last factorization chose its pivots (klu_factor, not klu_refactor)
};

void DestroySparseSymbolic(SparseSymbolic* s) {
  if (!s) return;
  if (s->symbolic) klu_free_symbolic(&s->symbolic, &s->common);
  delete s;
}

void DestroySparseNumeric(SparseNumeric* s) {
  if (!s) return;
  if (s->numeric) klu_free_numeric(&s->numeric, &s->common);
  delete s;
}

namespace {

// Reciprocal pivot growth bound: below it the pivot order chosen by the last full
// factorization is no longer trusted and KLU factors again with fresh pivoting.
constexpr double kRefactorRcond = 1e-12;
// Relative residual (against the largest product |A_ij x_j|) above which one step of
// iterative refinement runs: a few units of round-off.
constexpr double kRefineResidual = 1e-13;
// Below this after a fresh factorization the system is singular (e.g. a massless link).
constexpr double kSingularRcond = 1e-15;

// Orthonormal basis of span(S)'s complement in R^6 by Householder QR of S (6 x nf):
// S = Q R with Q = H_0 ... H_{nf-1}; the last 6 - nf columns of Q are the complement.
void Complement(Mat6 A, int nf, Mat6* Q) {
  Q->setIdentity();
  for (int k = 0; k < nf; ++k) {
    Vec6 v = Vec6::Zero();
    double norm2 = 0.0;
    for (int i = k; i < 6; ++i) norm2 += A(i, k) * A(i, k);
    const double norm = std::sqrt(norm2);
    if (norm == 0.0) continue;
    const double alpha = A(k, k) > 0.0 ? -norm : norm;
    for (int i = k; i < 6; ++i) v[i] = A(i, k);
    v[k] -= alpha;
    const double vn = v.norm();
    if (vn == 0.0) continue;
    v /= vn;
    for (int c = k; c < 6; ++c) {  // A <- H A
      const double d = 2.0 * v.dot(A.col(c));
      A.col(c) -= d * v;
    }
    for (int r = 0; r < 6; ++r) {  // Q <- Q H
      const double d = 2.0 * Q->row(r).dot(v);
      Q->row(r) -= d * v.transpose();
    }
  }
}

// Visits every structural entry of the system in one fixed order; `values` false
// visits the pattern only (compile time). put(row, col, value).
template <class Put>
void VisitSystem(const Program& p, const SparsePattern& sp, const Workspace* ws, Put put) {
  const bool values = ws != nullptr;
  const int K = static_cast<int>(p.bodies.size());
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const int P = p.joints[uL].parent;
    const int nf = sp.nf[uL], nc = 6 - nf;
    const int base = 12 * L;
    // (1) kinematic rows.
    for (int i = 0; i < 6; ++i) put(base + i, base + i, 1.0);
    if (P >= 0) {
      const int pb = 12 * P;
      Mat3 rx = Mat3::Zero();
      if (values) rx = Skew(ws->p_WBcm[uL] - ws->p_WBcm[static_cast<size_t>(P)]);
      for (int i = 0; i < 3; ++i) put(base + i, pb + i, -1.0);
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) put(base + i, pb + 3 + k, rx(i, k));
      for (int i = 0; i < 3; ++i) put(base + 3 + i, pb + 3 + i, -1.0);
    }
    for (int c = 0; c < nf; ++c) {
      Vec6 t = Vec6::Zero();
      if (values) {
        const auto h = ws->H_W.col(sp.free_speeds[uL][static_cast<size_t>(c)]);
        t.head<3>() = h.head<3>() + h.tail<3>().cross(ws->p_WBcm[uL] - ws->p_WB[uL]);
        t.tail<3>() = h.tail<3>();
      }
      for (int i = 0; i < 6; ++i) put(base + i, base + 6 + c, -t[i]);
    }
    // (2) Newton-Euler rows.
    const double m = p.bodies[uL].mass;
    for (int i = 0; i < 3; ++i) put(base + 6 + i, base + i, m);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) put(base + 9 + i, base + 3 + k, values ? ws->I_W[uL](i, k) : 0.0);
    for (int c = 0; c < nc; ++c) {
      Vec6 g = Vec6::Zero();
      if (values) {
        const Vec6 d = ws->D_W[uL].col(c);
        g.head<3>() = d.head<3>();
        g.tail<3>() = d.tail<3>() + (ws->p_WB[uL] - ws->p_WBcm[uL]).cross(d.head<3>());
      }
      for (int i = 0; i < 6; ++i) put(base + 6 + i, base + 6 + nf + c, -g[i]);
    }
    for (int C : sp.children[uL]) {
      const auto uC = static_cast<size_t>(C);
      const int ncC = 6 - sp.nf[uC];
      for (int c = 0; c < ncC; ++c) {
        Vec6 g = Vec6::Zero();
        if (values) {
          const Vec6 d = ws->D_W[uC].col(c);
          g.head<3>() = d.head<3>();
          g.tail<3>() = d.tail<3>() + (ws->p_WB[uC] - ws->p_WBcm[uL]).cross(d.head<3>());
        }
        for (int i = 0; i < 6; ++i) put(base + 6 + i, 12 * C + 6 + sp.nf[uC] + c, g[i]);
      }
    }
  }
  // (3) and (4): a row and a column per kept constraint row.
  for (size_t m = 0; m < sp.kept_rows.size(); ++m) {
    const int row = sp.n_body + static_cast<int>(m);
    for (int k = 0; k < 2; ++k) {
      const int L = sp.row_bodies[m][static_cast<size_t>(k)];
      if (L < 0) continue;
      const Vec6 J = values ? ws->row_J[2 * m + static_cast<size_t>(k)] : Vec6::Zero();
      for (int i = 0; i < 6; ++i) put(row, 12 * L + i, J[i]);
      for (int i = 0; i < 6; ++i) put(12 * L + 6 + i, row, -J[i]);
    }
  }
}

int Fail(Workspace& ws, const char* what) {
  ws.error = what;
  return -1;
}

}  // namespace

bool BuildSparse(Program& p, std::string* error) {
  auto sp = std::make_shared<SparsePattern>();
  const int K = static_cast<int>(p.bodies.size());
  sp->n_body = 12 * K;
  for (int i = 0; i < static_cast<int>(p.rows.size()); ++i) {
    if (std::binary_search(p.redundant_rows.begin(), p.redundant_rows.end(), i)) continue;
    std::array<int, 2> bodies;
    RowBodies(p, i, &bodies[0], &bodies[1]);
    if (bodies[0] == bodies[1]) bodies[1] = -1;  // both frames on one body: one block
    if (bodies[0] < 0 && bodies[1] < 0) {
      *error = "constraint row " + std::to_string(i) + " moves no body";
      return false;
    }
    sp->kept_rows.push_back(i);
    sp->row_bodies.push_back(bodies);
  }
  for (size_t li = 0; li < p.loops.size(); ++li) {
    SparsePattern::RowChoice rc;
    rc.loop = static_cast<int>(li);
    const LoopClosure& l = p.loops[li];
    for (int i = l.row0; i < l.row0 + l.nrows; ++i)
      if (p.active_of_row[static_cast<size_t>(i)] >= 0) rc.rows.push_back(i);
    for (size_t m = 0; m < sp->kept_rows.size(); ++m)
      if (p.rows[static_cast<size_t>(sp->kept_rows[m])].loop == rc.loop) rc.mults.push_back(static_cast<int>(m));
    if (!rc.mults.empty() && rc.rows.size() > rc.mults.size()) sp->row_choices.push_back(std::move(rc));
  }
  sp->n = sp->n_body + static_cast<int>(sp->kept_rows.size());
  sp->children.assign(static_cast<size_t>(K), {});
  sp->nf.assign(static_cast<size_t>(K), 0);
  sp->free_speeds.assign(static_cast<size_t>(K), {});
  for (int L = 0; L < K; ++L) {
    const TreeJoint& j = p.joints[static_cast<size_t>(L)];
    if (j.parent >= 0) sp->children[static_cast<size_t>(j.parent)].push_back(L);
    for (int k = 0; k < j.nu; ++k)
      if (p.u_free_of[static_cast<size_t>(j.u0 + k)] >= 0) sp->free_speeds[static_cast<size_t>(L)].push_back(j.u0 + k);
    sp->nf[static_cast<size_t>(L)] = static_cast<int>(sp->free_speeds[static_cast<size_t>(L)].size());
  }
  // Triplets in visit order, then CSC with each entry's slot.
  std::vector<int> rows, cols;
  VisitSystem(p, *sp, nullptr, [&](int r, int c, double) {
    rows.push_back(r);
    cols.push_back(c);
  });
  const size_t nnz = rows.size();
  sp->Ap.assign(static_cast<size_t>(sp->n) + 1, 0);
  for (int c : cols) sp->Ap[static_cast<size_t>(c) + 1]++;
  for (int c = 0; c < sp->n; ++c) sp->Ap[static_cast<size_t>(c) + 1] += sp->Ap[static_cast<size_t>(c)];
  std::vector<int> next(sp->Ap.begin(), sp->Ap.end() - 1);
  sp->Ai.assign(nnz, 0);
  sp->slot.assign(nnz, 0);
  for (size_t e = 0; e < nnz; ++e) {
    const int at = next[static_cast<size_t>(cols[e])]++;
    sp->Ai[static_cast<size_t>(at)] = rows[e];
    sp->slot[e] = at;
  }
  // KLU wants sorted row indices within a column: sort each column, carrying slots.
  std::vector<int> entry_at(nnz);
  for (size_t e = 0; e < nnz; ++e) entry_at[static_cast<size_t>(sp->slot[e])] = static_cast<int>(e);
  std::vector<int> perm;
  for (int c = 0; c < sp->n; ++c) {
    const int b = sp->Ap[static_cast<size_t>(c)], end = sp->Ap[static_cast<size_t>(c) + 1];
    perm.assign(entry_at.begin() + b, entry_at.begin() + end);
    std::sort(perm.begin(), perm.end(),
              [&](int x, int y) { return rows[static_cast<size_t>(x)] < rows[static_cast<size_t>(y)]; });
    for (int i = b; i < end; ++i) {
      const auto entry = static_cast<size_t>(perm[static_cast<size_t>(i - b)]);
      sp->Ai[static_cast<size_t>(i)] = rows[entry];
      sp->slot[entry] = i;
    }
  }
  p.sparse = sp;
  std::string note = "sparse K-vector system: ";
  note.append(std::to_string(sp->n)).append(" unknowns");
  if (!sp->kept_rows.empty())
    note.append(" (").append(std::to_string(sp->kept_rows.size())).append(" constraint multipliers)");
  note.append(", ").append(std::to_string(nnz)).append(" non-zeros, KLU symbolic analysis done once");
  p.notes.push_back(note);
  if (!p.sparse_symbolic && sp->n > 0) {
    std::shared_ptr<SparseSymbolic> sym(new SparseSymbolic, DestroySparseSymbolic);
    klu_defaults(&sym->common);
    // No block triangular form: the system is one irreducible block, and BTF's maximum
    // transversal, which puts non-zeros on the diagonal before AMD orders it, doubled
    // the fill of L + U on the four-bar ladder (N = 32: 27 000 entries without, 49 000
    // with) and made the factorization 2-3x slower; partial pivoting handles the zero
    // diagonal of the multiplier rows instead.
    sym->common.btf = 0;
    sym->symbolic = klu_analyze(sp->n, sp->Ap.data(), sp->Ai.data(), &sym->common);
    if (!sym->symbolic) {
      *error = std::string("klu_analyze failed (status ").append(std::to_string(sym->common.status)).append(")");
      return false;
    }
    p.sparse_symbolic = sym;
  }
  return true;
}

void InitSparseWorkspace(const Program& p, Workspace& ws) {
  const size_t K = p.bodies.size();
  ws.Ax.assign(p.sparse->Ai.size(), 0.0);
  ws.x.assign(static_cast<size_t>(p.sparse->n), 0.0);
  ws.b.assign(static_cast<size_t>(p.sparse->n), 0.0);
  ws.r.assign(static_cast<size_t>(p.sparse->n), 0.0);
  ws.lambda_W.assign(K, Vec6::Zero());
  ws.D_W.assign(K, Mat6::Zero());
  ws.row_J.assign(2 * p.sparse->kept_rows.size(), Vec6::Zero());
  ws.sparse_rows = p.sparse->kept_rows;
  ws.klu.reset(new SparseNumeric);
  klu_defaults(&ws.klu->common);
  ws.klu->common.btf = 0;  // as the symbolic analysis
}

namespace {

// Solves in place on ws.x with the current factorization; after a refactorization (pivot
// order of an earlier configuration) one step of iterative refinement, r = b - A x,
// x += A^-1 r, when the residual is not at round-off level: the old pivot order's growth
// at a far-away configuration can cost digits (seen as 2e-12 relative error without it).
int SolveInPlace(const Program& p, Workspace& ws) {
  const SparsePattern& sp = *p.sparse;
  SparseSymbolic& sym = *p.sparse_symbolic;
  SparseNumeric& num = *ws.klu;
  const int* Ap = sp.Ap.data();
  const int* Ai = sp.Ai.data();
  const double* Ax = ws.Ax.data();
  std::copy(ws.x.begin(), ws.x.end(), ws.b.begin());
  if (!klu_solve(sym.symbolic, num.numeric, sp.n, 1, ws.x.data(), &num.common))
    return Fail(ws, "singular mass matrix (sparse solve failed)");
  if (num.fresh) return 0;
  std::copy(ws.b.begin(), ws.b.end(), ws.r.begin());
  double r_max = 0.0, b_max = 0.0;
  for (int c = 0; c < sp.n; ++c) {
    const double xc = ws.x[static_cast<size_t>(c)];
    for (int k = Ap[c]; k < Ap[c + 1]; ++k) {
      ws.r[static_cast<size_t>(Ai[k])] -= Ax[k] * xc;
      b_max = std::max(b_max, std::fabs(Ax[k] * xc));
    }
  }
  for (int i = 0; i < sp.n; ++i) r_max = std::max(r_max, std::fabs(ws.r[static_cast<size_t>(i)]));
  if (r_max > kRefineResidual * b_max) {
    klu_solve(sym.symbolic, num.numeric, sp.n, 1, ws.r.data(), &num.common);
    for (int i = 0; i < sp.n; ++i) ws.x[static_cast<size_t>(i)] += ws.r[static_cast<size_t>(i)];
  }
  return 0;
}

}  // namespace

namespace {

// Re-chooses the rows of each loop of SparsePattern::row_choices that its multipliers
// take, at the current positions: the best-conditioned ones by pivoted Cholesky of the
// loop's rows' Gram matrix G = S A_l A_l^T S (at most 6 x 6; S divides translation rows by
// the loop's lever arm, LoopLeverArm) — the largest remaining diagonal, then its Schur
// complement, as many times as the loop has multipliers. The same as column-pivoted QR of
// (S A_l)^T. The chosen rows, in row order, into ws.sparse_rows.
void ChooseLoopRows(const Program& p, const SparsePattern& sp, Workspace& ws) {
  for (const SparsePattern::RowChoice& rc : sp.row_choices) {
    LoopJacobianRows(p, ws, rc.loop);
    const double len = LoopLeverArm(p, ws, rc.loop);
    const int n = static_cast<int>(std::min<size_t>(rc.rows.size(), 6));
    double scale[6];
    int k[6];
    for (int i = 0; i < n; ++i) {
      const ConstraintRow& row = p.rows[static_cast<size_t>(rc.rows[static_cast<size_t>(i)])];
      scale[i] = row.kind == RowKind::Translation ? 1.0 / len : 1.0;
      k[i] = p.active_of_row[static_cast<size_t>(rc.rows[static_cast<size_t>(i)])];
    }
    Mat6 G = Mat6::Zero();
    for (int i = 0; i < n; ++i)
      for (int j = 0; j <= i; ++j) G(i, j) = G(j, i) = scale[i] * scale[j] * ws.A.row(k[i]).dot(ws.A.row(k[j]));
    bool taken[6] = {false, false, false, false, false, false};
    for (size_t c = 0; c < rc.mults.size(); ++c) {
      int best = -1;
      for (int i = 0; i < n; ++i)
        if (!taken[i] && (best < 0 || G(i, i) > G(best, best))) best = i;
      taken[best] = true;
      const double d = G(best, best);
      if (!(d > 0.0)) continue;
      const Vec6 g = G.col(best) / std::sqrt(d);
      G -= g * g.transpose();
    }
    size_t c = 0;
    for (int i = 0; i < n; ++i)
      if (taken[i]) ws.sparse_rows[static_cast<size_t>(rc.mults[c++])] = rc.rows[static_cast<size_t>(i)];
  }
}

}  // namespace

int FactorSparse(const Program& p, Workspace& ws) {
  const SparsePattern& sp = *p.sparse;
  const size_t K = p.bodies.size();
  ChooseLoopRows(p, sp, ws);
  // Complement bases (they depend on the positions only).
  for (size_t L = 0; L < K; ++L) {
    const int nf = sp.nf[L];
    Mat6 S = Mat6::Zero();
    for (int c = 0; c < nf; ++c) S.col(c) = ws.H_W.col(sp.free_speeds[L][static_cast<size_t>(c)]);
    Mat6 Q;
    Complement(S, nf, &Q);
    ws.D_W[L].leftCols(6 - nf) = Q.rightCols(6 - nf);
  }
  for (size_t m = 0; m < sp.kept_rows.size(); ++m) {
    Vec6 Ja, Jb;
    RowJacobians(p, ws, ws.sparse_rows[m], &Ja, &Jb);
    // Slot 1 empty (frame b on the world, a contact, or both frames on one body, merged by
    // BuildSparse): slot 0 takes the sum, Jb being zero in the first two cases.
    ws.row_J[2 * m] = sp.row_bodies[m][1] < 0 ? Vec6(Ja + Jb) : Ja;
    ws.row_J[2 * m + 1] = Jb;
  }
  // Values, in the visit order of the pattern.
  size_t e = 0;
  double* Ax = ws.Ax.data();
  const int* slot = sp.slot.data();
  VisitSystem(p, sp, &ws, [&](int, int, double v) { Ax[slot[e++]] = v; });
  // Factor: the numeric object is created once (first call) and refactored after.
  SparseSymbolic& sym = *p.sparse_symbolic;
  SparseNumeric& num = *ws.klu;
  int* Ap = const_cast<int*>(sp.Ap.data());
  int* Ai = const_cast<int*>(sp.Ai.data());
  ws.sparse_ready = false;
  num.fresh = false;
  if (num.numeric) {
    if (!klu_refactor(Ap, Ai, Ax, sym.symbolic, num.numeric, &num.common))
      return Fail(ws, "singular mass matrix (sparse refactorization failed)");
    klu_rcond(sym.symbolic, num.numeric, &num.common);
    if (!(num.common.rcond > kRefactorRcond)) klu_free_numeric(&num.numeric, &num.common);
  }
  if (!num.numeric) {
    num.numeric = klu_factor(Ap, Ai, Ax, sym.symbolic, &num.common);
    if (!num.numeric) return Fail(ws, "singular mass matrix (sparse factorization failed)");
    num.fresh = true;
    klu_rcond(sym.symbolic, num.numeric, &num.common);
  }
  ws.sparse_rcond = num.common.rcond;
  if (num.fresh && !(num.common.rcond > kSingularRcond))
    return Fail(ws, "singular mass matrix (a body without mass or inertia moved by a joint?)");
  ws.sparse_ready = true;
  return 0;
}

bool SparseHasFactor(const Workspace& ws) { return ws.klu && ws.klu->numeric; }

int SparseCorrection(const Program& p, Workspace& ws, const Eigen::VectorXd& residual, Eigen::VectorXd* du_full) {
  const SparsePattern& sp = *p.sparse;
  std::fill(ws.x.begin(), ws.x.end(), 0.0);
  for (size_t m = 0; m < sp.kept_rows.size(); ++m)
    ws.x[static_cast<size_t>(sp.n_body) + m] = -residual[ws.sparse_rows[m]];
  if (int s = SolveInPlace(p, ws); s != 0) return s;
  du_full->setZero();
  for (size_t L = 0; L < p.bodies.size(); ++L) {
    const double* x = ws.x.data() + 12 * L;
    for (int c = 0; c < sp.nf[L]; ++c) (*du_full)[sp.free_speeds[L][static_cast<size_t>(c)]] = x[6 + c];
  }
  return 0;
}

int SolveSparse(const Program& p, Workspace& ws) {
  const SparsePattern& sp = *p.sparse;
  const size_t K = p.bodies.size();
  if (K == 0) return 0;
  if (!ws.sparse_ready)
    if (int s = FactorSparse(p, ws); s != 0) return s;
  // The joint-force wrenches W^Q (kept in lambda_W for now).
  for (size_t L = 0; L < K; ++L) {
    const int nf = sp.nf[L];
    Vec6 WQ = Vec6::Zero();
    if (nf > 0) {
      Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1> Qj(nf);
      for (int c = 0; c < nf; ++c) Qj[c] = ws.Q[sp.free_speeds[L][static_cast<size_t>(c)]];
      if (Qj.squaredNorm() > 0.0) {
        Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6> S(6, nf);
        for (int c = 0; c < nf; ++c) S.col(c) = ws.H_W.col(sp.free_speeds[L][static_cast<size_t>(c)]);
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6> StS = S.transpose() * S;
        Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1> z = StS.ldlt().solve(Qj);
        WQ = S * z;
      }
    }
    ws.lambda_W[L] = WQ;
  }
  // Right-hand sides (1) and (2).
  for (size_t L = 0; L < K; ++L) {
    double* b = ws.x.data() + 12 * L;
    const int P = p.joints[L].parent;
    Vec3 ka = ws.a_bias_cm[L], kw = ws.alpha_bias[L];
    if (P >= 0) {
      const auto uP = static_cast<size_t>(P);
      ka -= ws.a_bias_cm[uP] + ws.alpha_bias[uP].cross(ws.p_WBcm[L] - ws.p_WBcm[uP]);
      kw -= ws.alpha_bias[uP];
    }
    const Vec3 gyro = ws.w_WB[L].cross(ws.I_W[L] * ws.w_WB[L]);
    const Vec6& WQ = ws.lambda_W[L];
    Vec3 f = ws.F_W[L] + WQ.head<3>();
    Vec3 t = ws.T_W[L] - gyro + WQ.tail<3>() + (ws.p_WB[L] - ws.p_WBcm[L]).cross(WQ.head<3>());
    for (int C : sp.children[L]) {
      const auto uC = static_cast<size_t>(C);
      const Vec6& WC = ws.lambda_W[uC];
      f -= WC.head<3>();
      t -= WC.tail<3>() + (ws.p_WB[uC] - ws.p_WBcm[L]).cross(WC.head<3>());
    }
    for (int i = 0; i < 3; ++i) {
      b[i] = ka[i];
      b[3 + i] = kw[i];
      b[6 + i] = f[i];
      b[9 + i] = t[i];
    }
  }
  // (3): J_i . A_bias - c_i.
  if (!sp.kept_rows.empty()) {
    ConstraintBias(p, ws);
    for (size_t m = 0; m < sp.kept_rows.size(); ++m) {
      double v = -ws.cbias[ws.sparse_rows[m]];
      for (int k = 0; k < 2; ++k) {
        const int L = sp.row_bodies[m][static_cast<size_t>(k)];
        if (L < 0) continue;
        const Vec6& J = ws.row_J[2 * m + static_cast<size_t>(k)];
        const auto uL = static_cast<size_t>(L);
        v += J.head<3>().dot(ws.a_bias_cm[uL]) + J.tail<3>().dot(ws.alpha_bias[uL]);
      }
      ws.x[static_cast<size_t>(sp.n_body) + m] = v;
    }
  }
  if (int s = SolveInPlace(p, ws); s != 0) return s;
  // Read udot, the joint reaction wrenches lambda_L = gamma_L s_L + W^Q_L and the
  // constraint multipliers.
  for (size_t L = 0; L < K; ++L) {
    const double* x = ws.x.data() + 12 * L;
    const int nf = sp.nf[L];
    for (int c = 0; c < nf; ++c) ws.udot[sp.free_speeds[L][static_cast<size_t>(c)]] = x[6 + c];
    for (int c = 0; c < 6 - nf; ++c) ws.lambda_W[L] += ws.D_W[L].col(c) * x[6 + nf + c];
  }
  if (!sp.kept_rows.empty()) {
    ws.lambda_c.setZero();
    for (size_t m = 0; m < sp.kept_rows.size(); ++m)
      ws.lambda_c[ws.sparse_rows[m]] = ws.x[static_cast<size_t>(sp.n_body) + m];
  }
  return 0;
}


// The projection onto the constraint manifold on this path (kane.h ProjectState).
namespace {

// The sparse path's projection first iterates with the factorization of the previous
// evaluation (chord steps: no new factorization) while each step shrinks the residual by
// at least kChordRate, at most kMaxChord times, then takes Newton steps.
constexpr int kMaxChord = 4;
constexpr double kChordRate = 0.1;
// Below this pivot ratio (KLU's rcond estimate, rows scaled) of the sparse path's
// factorization at the projected positions, the loop is at a singular configuration.
constexpr double kSparseSingular = 1e-12;

// `factored`: the factorization went through with a small pivot ratio (else it met an
// exactly zero pivot).
int SparseSingular(const Program& p, Workspace& ws, bool factored) {
  char buf[64];
  if (factored)
    std::snprintf(buf, sizeof buf, "pivot ratio of the multiplier system %.2g", ws.sparse_rcond);
  else
    std::snprintf(buf, sizeof buf, "the multiplier system has a zero pivot");
  ws.error = "closed loop " + LoopOwners(p) + " at a singular configuration at time " + std::to_string(ws.t) +
             ": the constraint rows lost rank (" + buf +
             "; a change point where assembly branches meet, or a dead point), so the loop equations do not "
             "determine the motion through it";
  return 1;
}

}  // namespace

// ProjectState on the sparse path: the steps of kane.h SparseCorrection, chord steps with
// the previous evaluation's factorization while they contract, Newton after.
int ProjectStateSparse(const Program& p, Workspace& ws) {
  const double tight = kProjectTight * p.loop_length;
  ConstraintResiduals(p, ws);
  bool newton = !SparseHasFactor(ws);
  double last = INFINITY;
  for (int it = 0;; ++it) {
    const double r = ws.phi.cwiseAbs().maxCoeff();
    if (r <= tight || it == kMaxChord + kProjectMaxNewton) break;
    if (r > kChordRate * last || it >= kMaxChord) newton = true;
    last = r;
    if (newton && !ws.sparse_ready && FactorSparse(p, ws) != 0) return SparseSingular(p, ws, false);
    if (int s = SparseCorrection(p, ws, ws.phi, &ws.du_full); s != 0) return s;
    StepCoordinates(p, ws);
    ws.sparse_ready = false;
    ConstraintResiduals(p, ws);
  }
  if (int s = CheckLoopsClosed(p, ws); s != 0) return s;
  if (!ws.sparse_ready && FactorSparse(p, ws) != 0) return SparseSingular(p, ws, false);
  if (!(ws.sparse_rcond > kSparseSingular)) return SparseSingular(p, ws, true);
  ConstraintRates(p, ws);
  if (int s = CheckDisksUpright(p, ws); s != 0) return s;
  if (int s = SparseCorrection(p, ws, ws.psi, &ws.du_full); s != 0) return s;
  ws.u += ws.du_full;
  VelocityKinematics(p, ws);
  return 0;
}

}  // namespace kanesim::rt
