// Recursive path: Kane's equations of an open tree (Lesser eqs. 22-25, grouped per
// subtree as in kane_dense.cpp eq. (3)) eliminated leaves to root, then solved root to
// leaves. The unknowns are the free udot; the body accelerations are linear in them:
//
//   A_L = X_LP A_P + S_L udot_L,   X_LP A = [a + alpha x (o_L - o_P);  alpha],  A_ground = 0  (1)
//   S_L^T sum_{B in subtree(L)} X*_BL (Mb_B A_B - w_B) = Q_L                                 (2)
//
// where A_L = [a; alpha] is the part of body L's acceleration at its origin o_L that
// depends on the free udot (the rest, with free udot = 0, is in the bias accelerations),
// S_L the free columns of the joint's tangent generators H_W (twists at o_L), Mb_B the
// spatial inertia of body B about o_B, w_B = [F_B - m_B a_bias_B; T_B - I_B alpha_bias_B
// - w_B x I_B w_B] moved from c_B to o_B (the applied and bias-inertia wrench, as in the
// dense path), X*_BL moves a wrench from o_B to o_L, and Q_L the joint forces of joint L.
//
// Elimination (the articulated-body recursion, Featherstone 2008 §7.3, read as Gaussian
// block elimination of (2) in leaf-first order). Suppose that for every child C of L
//   sum_{B in subtree(C)} X*_BC (Mb_B A_B - w_B) = Ia_C A_C + pa_C.                         (3)
// Then (2) for C with (1) gives its udot in terms of its parent's acceleration:
//   U_C = Ia_C S_C,  D_C = S_C^T U_C,  u_C = Q_C - S_C^T pa_C                               (4)
//   udot_C = D_C^-1 (u_C - U_C^T X_CL A_L)                                                 (5)
// and substituting (5) into (3) makes it linear in A_L alone, so (3) holds for L with
//   Ia_L = Mb_L + sum_C X*_CL (Ia_C - U_C D_C^-1 U_C^T) X_CL                                 (6)
//   pa_L = -w_L + sum_C X*_CL (pa_C + U_C D_C^-1 u_C)                                        (7)
// (at a leaf: Ia = Mb, pa = -w). Backward pass: (4), (6), (7) for L = K-1 .. 0 (children
// follow parents in tree order); step L adds Mb_L and -w_L to its children's shares, and
// the first child the pass reaches writes its share into the parent, the others add
// (TreeLayout::first_share), so nothing is zeroed or built in a pass of its own.
// Forward pass: (5) and (1) for L = 0 .. K-1.
//
// The D_L are the pivot blocks of the mass matrix M = tau^T Mb tau eliminated in
// leaf-first order (Schur complements), so they are positive definite exactly when M is;
// a pivot below kSingularPivot of the largest diagonal entry means M is singular to
// working precision, the same test as the dense path's Cholesky.
#include "runtime/kane/kane_tree.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <string>

namespace kanesim::rt {

namespace {

// kSingularPivot (kane_tree.h) bounds a squared pivot of a D_L against the largest
// diagonal entry of the D_L.
// PlanarLayout: two joint axes count as parallel when |a x b| <= kPlanarAxisTol |a| |b|
// (axes written parallel are so exactly or to rounding); the out-of-plane terms the planar
// recursion leaves out are of this relative size.
constexpr double kPlanarAxisTol = 1e-13;

template <int NF>
using Mat6N = Eigen::Matrix<double, 6, NF>;
template <int NF>
using MatN = Eigen::Matrix<double, NF, NF>;
template <int NF>
using VecN = Eigen::Matrix<double, NF, 1>;

// The smallest squared pivot and the largest diagonal entry of the D_L seen so far.
struct PivotRange {
  double min_pivot_sq = std::numeric_limits<double>::infinity();
  double max_diag = 0.0;
};

// kBlocks: a spatial inertia [A, B; B^T, C] (A, C symmetric) in tree_Ia is kept by its
// upper-right block B and the upper triangles of A and C only; the lower-left block and
// the strict lower triangles of A and C are stale. Articulated (below) holds just those
// entries; the general joints' elimination (Eliminate, Eliminate1) calls Mirror first.
inline void Mirror(Mat6* Ia) {
  Mat6& M = *Ia;
  M.bottomLeftCorner<3, 3>() = M.topRightCorner<3, 3>().transpose();
  M(1, 0) = M(0, 1), M(2, 0) = M(0, 2), M(2, 1) = M(1, 2);
  M(4, 3) = M(3, 4), M(5, 3) = M(3, 5), M(5, 4) = M(4, 5);
}

// An articulated inertia and bias wrench (Ia, pa) as named scalars, kBlocks. A step of
// the backward pass works on one of these in registers and hands it to the next step
// directly when that step is the parent (a chain); a round trip through tree_Ia would
// store it in 8-byte pieces and read it back in 16-byte ones, which stalls the store
// forwarding of every entry.
struct Articulated {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;                             // A
  double b00 = 0, b01 = 0, b02 = 0, b10 = 0, b11 = 0, b12 = 0, b20 = 0, b21 = 0, b22 = 0;  // B: b_ik = Ia(i, 3 + k)
  double c00 = 0, c01 = 0, c02 = 0, c11 = 0, c12 = 0, c22 = 0;                             // C
  double p0 = 0, p1 = 0, p2 = 0, p3 = 0, p4 = 0, p5 = 0;                                   // pa = [force; torque]
};

// The kBlocks entries of tree_Ia[L], tree_pa[L] and back.
inline Articulated Load(const Mat6& M, const Vec6& p) {
  Articulated X;
  X.a00 = M(0, 0), X.a01 = M(0, 1), X.a02 = M(0, 2), X.a11 = M(1, 1), X.a12 = M(1, 2), X.a22 = M(2, 2);
  X.b00 = M(0, 3), X.b01 = M(0, 4), X.b02 = M(0, 5);
  X.b10 = M(1, 3), X.b11 = M(1, 4), X.b12 = M(1, 5);
  X.b20 = M(2, 3), X.b21 = M(2, 4), X.b22 = M(2, 5);
  X.c00 = M(3, 3), X.c01 = M(3, 4), X.c02 = M(3, 5), X.c11 = M(4, 4), X.c12 = M(4, 5), X.c22 = M(5, 5);
  X.p0 = p[0], X.p1 = p[1], X.p2 = p[2], X.p3 = p[3], X.p4 = p[4], X.p5 = p[5];
  return X;
}

inline void Store(const Articulated& X, Mat6* Ia, Vec6* pa) {
  Mat6& M = *Ia;
  M(0, 0) = X.a00, M(0, 1) = X.a01, M(0, 2) = X.a02, M(1, 1) = X.a11, M(1, 2) = X.a12, M(2, 2) = X.a22;
  M(0, 3) = X.b00, M(0, 4) = X.b01, M(0, 5) = X.b02;
  M(1, 3) = X.b10, M(1, 4) = X.b11, M(1, 5) = X.b12;
  M(2, 3) = X.b20, M(2, 4) = X.b21, M(2, 5) = X.b22;
  M(3, 3) = X.c00, M(3, 4) = X.c01, M(3, 5) = X.c02, M(4, 4) = X.c11, M(4, 5) = X.c12, M(5, 5) = X.c22;
  Vec6& p = *pa;
  p[0] = X.p0, p[1] = X.p1, p[2] = X.p2, p[3] = X.p3, p[4] = X.p4, p[5] = X.p5;
}

// Y += Z, entry by entry.
inline void Add(const Articulated& Z, Articulated* Y) {
  Articulated& X = *Y;
  X.a00 += Z.a00, X.a01 += Z.a01, X.a02 += Z.a02, X.a11 += Z.a11, X.a12 += Z.a12, X.a22 += Z.a22;
  X.b00 += Z.b00, X.b01 += Z.b01, X.b02 += Z.b02;
  X.b10 += Z.b10, X.b11 += Z.b11, X.b12 += Z.b12;
  X.b20 += Z.b20, X.b21 += Z.b21, X.b22 += Z.b22;
  X.c00 += Z.c00, X.c01 += Z.c01, X.c02 += Z.c02, X.c11 += Z.c11, X.c12 += Z.c12, X.c22 += Z.c22;
  X.p0 += Z.p0, X.p1 += Z.p1, X.p2 += Z.p2, X.p3 += Z.p3, X.p4 += Z.p4, X.p5 += Z.p5;
}

// Body L's own spatial inertia Mb_L about o_L (mass m, central inertia I, world axes,
// r = c_L - o_L), mapping the acceleration [a_o; alpha] to the wrench [f; n_o]:
//   [m 1, -m D; m D, I - m D D],  D = [r]x,  -D D = |r|^2 1 - r r^T,
// and -w_L = [-f; -n - r x f] (f, n the wrench w_L at c_L): the leaf values of (6), (7),
// added to the children's shares in X (zero at a leaf). With w_L of the class comment,
//   f = F - m a_bias_cm,  n = T - I alpha_bias - w x I w.
void AddBody(const Program& p, const Workspace& ws, size_t L, Articulated* X) {
  const double m = p.bodies[L].mass;
  const Mat3& I = ws.I_W[L];
  const double i00 = I(0, 0), i01 = I(0, 1), i02 = I(0, 2), i11 = I(1, 1), i12 = I(1, 2), i22 = I(2, 2);
  const Vec3 &o = ws.p_WB[L], &c = ws.p_WBcm[L];
  const double r0 = c.x() - o.x(), r1 = c.y() - o.y(), r2 = c.z() - o.z();
  const Vec3 &F = ws.F_W[L], &a = ws.a_bias_cm[L];
  const double f0 = F.x() - m * a.x(), f1 = F.y() - m * a.y(), f2 = F.z() - m * a.z();
  const Vec3 &w = ws.w_WB[L], &al = ws.alpha_bias[L], &T = ws.T_W[L];
  const double w0 = w.x(), w1 = w.y(), w2 = w.z(), l0 = al.x(), l1 = al.y(), l2 = al.z();
  const double k0 = i00 * w0 + i01 * w1 + i02 * w2;  // I w
  const double k1 = i01 * w0 + i11 * w1 + i12 * w2;
  const double k2 = i02 * w0 + i12 * w1 + i22 * w2;
  const double n0 = T.x() - (i00 * l0 + i01 * l1 + i02 * l2) - (w1 * k2 - w2 * k1);
  const double n1 = T.y() - (i01 * l0 + i11 * l1 + i12 * l2) - (w2 * k0 - w0 * k2);
  const double n2 = T.z() - (i02 * l0 + i12 * l1 + i22 * l2) - (w0 * k1 - w1 * k0);
  Articulated& M = *X;
  const double x = m * r0, y = m * r1, z = m * r2;  // m r
  const double mrr = x * r0 + y * r1 + z * r2;
  M.a00 += m, M.a11 += m, M.a22 += m;  // A = m 1
  M.b10 -= z, M.b20 += y;              // B = -m D
  M.b01 += z, M.b21 -= x;
  M.b02 -= y, M.b12 += x;
  M.c00 += i00 + mrr - x * r0, M.c01 += i01 - x * r1;  // C = I - m D D
  M.c11 += i11 + mrr - y * r1, M.c02 += i02 - x * r2;
  M.c22 += i22 + mrr - z * r2, M.c12 += i12 - y * r2;
  M.p0 -= f0, M.p1 -= f1, M.p2 -= f2;
  M.p3 += -n0 - (r1 * f2 - r2 * f1);
  M.p4 += -n1 - (r2 * f0 - r0 * f2);
  M.p5 += -n2 - (r0 * f1 - r1 * f0);
}

// X*_LP Ia X_LP of (6) and X*_LP pa of (7): the inertia and wrench about o_L moved to
// o_P, with X = [1, -R; 0, 1], R = [r]x, r = o_L - o_P. With Ia = [A, B; B^T, C] it is
//   [A, B + G; B^T + G^T, C + R B + B^T R^T + R A R^T],  G = A R^T (row i: r x A_i),
// and with F = R (B + G/2) the lower-right block is C + F + F^T (R A R^T = R G is
// symmetric), so every product is a column-wise cross product with r; the wrench's
// torque gains r x f.
Articulated Moved(const Articulated& M, double r0, double r1, double r2) {
  Articulated N;
  const double a00 = M.a00, a01 = M.a01, a02 = M.a02, a11 = M.a11, a12 = M.a12, a22 = M.a22;
  // G(i, k) = (r x A_i)_k, A_i = column i of A.
  const double g00 = r1 * a02 - r2 * a01, g01 = r2 * a00 - r0 * a02, g02 = r0 * a01 - r1 * a00;
  const double g10 = r1 * a12 - r2 * a11, g11 = r2 * a01 - r0 * a12, g12 = r0 * a11 - r1 * a01;
  const double g20 = r1 * a22 - r2 * a12, g21 = r2 * a02 - r0 * a22, g22 = r0 * a12 - r1 * a02;
  // E = B + G / 2, F(i, k) = (r x E_k)_i.
  const double e00 = M.b00 + 0.5 * g00, e10 = M.b10 + 0.5 * g10, e20 = M.b20 + 0.5 * g20;
  const double e01 = M.b01 + 0.5 * g01, e11 = M.b11 + 0.5 * g11, e21 = M.b21 + 0.5 * g21;
  const double e02 = M.b02 + 0.5 * g02, e12 = M.b12 + 0.5 * g12, e22 = M.b22 + 0.5 * g22;
  const double f00 = r1 * e20 - r2 * e10, f10 = r2 * e00 - r0 * e20, f20 = r0 * e10 - r1 * e00;
  const double f01 = r1 * e21 - r2 * e11, f11 = r2 * e01 - r0 * e21, f21 = r0 * e11 - r1 * e01;
  const double f02 = r1 * e22 - r2 * e12, f12 = r2 * e02 - r0 * e22, f22 = r0 * e12 - r1 * e02;
  N.a00 = a00, N.a01 = a01, N.a02 = a02, N.a11 = a11, N.a12 = a12, N.a22 = a22;
  N.b00 = M.b00 + g00, N.b01 = M.b01 + g01, N.b02 = M.b02 + g02;
  N.b10 = M.b10 + g10, N.b11 = M.b11 + g11, N.b12 = M.b12 + g12;
  N.b20 = M.b20 + g20, N.b21 = M.b21 + g21, N.b22 = M.b22 + g22;
  N.c00 = M.c00 + f00 + f00, N.c01 = M.c01 + f01 + f10, N.c02 = M.c02 + f02 + f20;
  N.c11 = M.c11 + f11 + f11, N.c12 = M.c12 + f12 + f21, N.c22 = M.c22 + f22 + f22;
  N.p0 = M.p0, N.p1 = M.p1, N.p2 = M.p2;
  N.p3 = M.p3 + r1 * M.p2 - r2 * M.p1;
  N.p4 = M.p4 + r2 * M.p0 - r0 * M.p2;
  N.p5 = M.p5 + r0 * M.p1 - r1 * M.p0;
  return N;
}

// S_L: the free columns of the joint's tangent generators.
template <int NF>
Mat6N<NF> FreeColumns(const Workspace& ws, const TreeLayout::JointBlock& J) {
  if (J.contiguous) return ws.H_W.middleCols<NF>(J.cols[0]);
  Mat6N<NF> S;
  for (int k = 0; k < NF; ++k) S.col(k) = ws.H_W.col(J.cols[static_cast<size_t>(k)]);
  return S;
}

// Backward step of joint L: (4), then Ia and pa turned into the brackets of (6) and (7).
// Returns false when D_L is not positive definite.
template <int NF>
bool Eliminate(const Workspace& ws, const TreeLayout::JointBlock& J, double* U_data, double* Dinv_data,
               double* u_data, Mat6* Ia, Vec6* pa, PivotRange* piv) {
  Mirror(Ia);
  const Mat6N<NF> S = FreeColumns<NF>(ws, J);
  Eigen::Map<Mat6N<NF>> U(U_data);
  Eigen::Map<MatN<NF>> Dinv(Dinv_data);
  Eigen::Map<VecN<NF>> u(u_data);
  U.noalias() = *Ia * S;                        // (4)
  const MatN<NF> D = S.transpose() * U;         // (4)
  for (int k = 0; k < NF; ++k) u[k] = ws.Q[J.cols[static_cast<size_t>(k)]] - S.col(k).dot(*pa);  // (4)
  piv->max_diag = std::max(piv->max_diag, D.diagonal().maxCoeff());
  if constexpr (NF == 1) {
    const double d = D(0, 0);
    if (!(d > 0.0)) return false;
    piv->min_pivot_sq = std::min(piv->min_pivot_sq, d);
    Dinv(0, 0) = 1.0 / d;
  } else {
    const Eigen::LLT<MatN<NF>> llt(D);
    if (llt.info() != Eigen::Success) return false;
    piv->min_pivot_sq = std::min(piv->min_pivot_sq, llt.matrixLLT().diagonal().cwiseAbs2().minCoeff());
    Dinv = llt.solve(MatN<NF>::Identity());
  }
  const Mat6N<NF> UD = U * Dinv;
  Ia->noalias() -= UD * U.transpose();  // bracket of (6)
  pa->noalias() += UD * u;              // bracket of (7)
  return true;
}

// Forward step of joint L: (5) and (1), given the parent's A_P and A = X_LP A_P; writes
// udot_L. The stored U is X_LP^T U (see SolveTree), so (5) reads A_P, not A.
template <int NF>
void Substitute(const TreeLayout::JointBlock& J, const double* U_data, const double* Dinv_data,
                const double* u_data, const Vec6& AP, Workspace& ws, Vec6* A) {
  const Eigen::Map<const Mat6N<NF>> U(U_data);
  const Eigen::Map<const MatN<NF>> Dinv(Dinv_data);
  const Eigen::Map<const VecN<NF>> u(u_data);
  const VecN<NF> ud = Dinv * (u - U.transpose() * AP);  // (5)
  *A += FreeColumns<NF>(ws, J) * ud;                    // (1)
  for (int k = 0; k < NF; ++k) ws.udot[J.cols[static_cast<size_t>(k)]] = ud[k];
}

// One free speed on a revolute joint in tree direction (the common case): S_L = [0; h],
// so only Ia's right half and pa's torque enter (4): U = [B h; C h], d = h . C h. The
// bracket of (6) updates B and the upper triangles of A and C only (kBlocks).
bool EliminateAngular(const Vec3& h, double Q, double* U_data, double* Dinv_data, double* u_data, Articulated* Ia,
                      PivotRange* piv) {
  Articulated& M = *Ia;
  const double h0 = h.x(), h1 = h.y(), h2 = h.z();
  const double U0 = M.b00 * h0 + M.b01 * h1 + M.b02 * h2;  // (4): B h
  const double U1 = M.b10 * h0 + M.b11 * h1 + M.b12 * h2;
  const double U2 = M.b20 * h0 + M.b21 * h1 + M.b22 * h2;
  const double U3 = M.c00 * h0 + M.c01 * h1 + M.c02 * h2;  // (4): C h
  const double U4 = M.c01 * h0 + M.c11 * h1 + M.c12 * h2;
  const double U5 = M.c02 * h0 + M.c12 * h1 + M.c22 * h2;
  const double d = h0 * U3 + h1 * U4 + h2 * U5;
  const double u = Q - (h0 * M.p3 + h1 * M.p4 + h2 * M.p5);
  piv->max_diag = std::max(piv->max_diag, d);
  if (!(d > 0.0)) return false;
  piv->min_pivot_sq = std::min(piv->min_pivot_sq, d);
  const double dinv = 1.0 / d;
  *Dinv_data = dinv;
  *u_data = u;
  U_data[0] = U0, U_data[1] = U1, U_data[2] = U2, U_data[3] = U3, U_data[4] = U4, U_data[5] = U5;
  const double V0 = U0 * dinv, V1 = U1 * dinv, V2 = U2 * dinv, V3 = U3 * dinv, V4 = U4 * dinv, V5 = U5 * dinv;
  // Bracket of (6): Ia - U D^-1 U^T, blocks A, B, C only (kBlocks).
  M.a00 -= V0 * U0, M.a01 -= V0 * U1, M.a02 -= V0 * U2, M.a11 -= V1 * U1, M.a12 -= V1 * U2, M.a22 -= V2 * U2;
  M.b00 -= V0 * U3, M.b01 -= V0 * U4, M.b02 -= V0 * U5;
  M.b10 -= V1 * U3, M.b11 -= V1 * U4, M.b12 -= V1 * U5;
  M.b20 -= V2 * U3, M.b21 -= V2 * U4, M.b22 -= V2 * U5;
  M.c00 -= V3 * U3, M.c01 -= V3 * U4, M.c02 -= V3 * U5, M.c11 -= V4 * U4, M.c12 -= V4 * U5, M.c22 -= V5 * U5;
  // Bracket of (7): pa + U D^-1 u.
  M.p0 += V0 * u, M.p1 += V1 * u, M.p2 += V2 * u, M.p3 += V3 * u, M.p4 += V4 * u, M.p5 += V5 * u;
  return true;
}

// One free speed, any other joint: (4) with the full column s.
bool Eliminate1(const Workspace& ws, const TreeLayout::JointBlock& J, double* U_data, double* Dinv_data,
                double* u_data, Mat6* Ia, Vec6* pa, PivotRange* piv) {
  const auto s = ws.H_W.col(J.cols[0]);
  Eigen::Map<Vec6> U(U_data);
  Mirror(Ia);
  U.noalias() = *Ia * s;  // (4)
  const double d = s.dot(U);
  const double u = ws.Q[J.cols[0]] - s.dot(*pa);
  piv->max_diag = std::max(piv->max_diag, d);
  if (!(d > 0.0)) return false;
  piv->min_pivot_sq = std::min(piv->min_pivot_sq, d);
  const double dinv = 1.0 / d;
  *Dinv_data = dinv;
  *u_data = u;
  const Vec6 Ud = U * dinv;
  Ia->noalias() -= Ud * U.transpose();  // bracket of (6)
  *pa += Ud * u;                        // bracket of (7)
  return true;
}

void Substitute1(const TreeLayout::JointBlock& J, const double* U_data, const double* Dinv_data, const double* u_data,
                 const Vec6& AP, Workspace& ws, Vec6* A) {
  const Eigen::Map<const Vec6> U(U_data);
  const double ud = *Dinv_data * (*u_data - U.dot(AP));  // (5)
  *A += ws.H_W.col(J.cols[0]) * ud;                     // (1)
  ws.udot[J.cols[0]] = ud;
}

// Dispatch on the joint's number of free speeds (fixed-size blocks for each).
bool EliminateJoint(const Workspace& ws, const TreeLayout::JointBlock& J, double* U, double* Dinv, double* u,
                    Mat6* Ia, Vec6* pa, PivotRange* piv) {
  switch (J.nf) {
    case 0: return true;
    case 1: return Eliminate1(ws, J, U, Dinv, u, Ia, pa, piv);
    case 2: return Eliminate<2>(ws, J, U, Dinv, u, Ia, pa, piv);
    case 3: return Eliminate<3>(ws, J, U, Dinv, u, Ia, pa, piv);
    case 4: return Eliminate<4>(ws, J, U, Dinv, u, Ia, pa, piv);
    case 5: return Eliminate<5>(ws, J, U, Dinv, u, Ia, pa, piv);
    default: return Eliminate<6>(ws, J, U, Dinv, u, Ia, pa, piv);
  }
}

void SubstituteJoint(const TreeLayout::JointBlock& J, const double* U, const double* Dinv, const double* u,
                     const Vec6& AP, Workspace& ws, Vec6* A) {
  switch (J.nf) {
    case 0: return;
    case 1: return Substitute1(J, U, Dinv, u, AP, ws, A);
    case 2: return Substitute<2>(J, U, Dinv, u, AP, ws, A);
    case 3: return Substitute<3>(J, U, Dinv, u, AP, ws, A);
    case 4: return Substitute<4>(J, U, Dinv, u, AP, ws, A);
    case 5: return Substitute<5>(J, U, Dinv, u, AP, ws, A);
    default: return Substitute<6>(J, U, Dinv, u, AP, ws, A);
  }
}

// A planar tree (TreeLayout::planar): every joint `angular`; every root joint's axis
// (world) parallel to the first root's; every other joint's axis in its parent body's
// frame (axis_P) parallel to the parent joint's own axis there (joints[P].axis: a revolute
// joint turns its child about that axis, so it is the same vector in the child body's
// frame in every configuration). By induction down the tree every h_L = R_WB[P] axis_P
// is then s_L n in every configuration, with s_L = s_P (axis_P . axis of P).
void PlanarLayout(const Program& p, TreeLayout* T) {
  T->planar = false;
  for (const TreeLayout::JointBlock& J : T->joints)
    if (!J.angular) return;
  const auto parallel = [](const Vec3& a, const Vec3& b) {
    return a.cross(b).norm() <= kPlanarAxisTol * a.norm() * b.norm();
  };
  const size_t K = p.joints.size();
  std::vector<double> s(K), Inn(K);
  Vec3 n = Vec3::Zero();
  for (size_t L = 0; L < K; ++L) {
    const TreeJoint& j = p.joints[L];
    if (j.parent < 0) {
      if (n.isZero()) n = j.axis_P.normalized();
      if (!parallel(j.axis_P, n)) return;
      s[L] = j.axis_P.dot(n);
    } else {
      const auto P = static_cast<size_t>(j.parent);
      const Vec3& aP = p.joints[P].axis;
      if (!parallel(j.axis_P, aP)) return;
      s[L] = s[P] * j.axis_P.dot(aP);
    }
    // n = R_WB a / s (a: the joint's axis in body L's frame), so n . I_W n = a^T I a / s^2.
    const Vec3& a = j.axis;
    Inn[L] = a.dot(p.bodies[L].I_BBcm_B * a) / (s[L] * s[L]);
  }
  T->planar = !T->joints.empty();
  T->plane_n = n;
  T->plane_e1 = n.unitOrthogonal();  // as the loops' joint rows (compile/loops.cpp)
  T->plane_e2 = n.cross(T->plane_e1);
  T->plane_s = std::move(s);
  T->plane_Inn = std::move(Inn);
}

}  // namespace

void BuildTree(Program& p) {
  auto layout = std::make_shared<TreeLayout>();
  layout->joints.resize(p.joints.size());
  layout->parent.resize(p.joints.size());
  int d0 = 0;
  for (size_t L = 0; L < p.joints.size(); ++L) {
    const TreeJoint& j = p.joints[L];
    TreeLayout::JointBlock& J = layout->joints[L];
    layout->parent[L] = j.parent;
    for (int k = 0; k < j.nu; ++k) {
      const int s = j.u0 + k;
      const int f = p.u_free_of[static_cast<size_t>(s)];
      if (f < 0) continue;
      if (J.nf == 0) J.f0 = f;
      J.cols[static_cast<size_t>(J.nf++)] = s;
    }
    J.contiguous = J.nf == j.nu;
    J.angular = J.nf == 1 && j.single_axis && j.type == flat::JointType::Revolute;
    J.d0 = d0;
    d0 += J.nf * J.nf;
  }
  layout->d_size = d0;
  PlanarLayout(p, layout.get());
  if (layout->planar) {
    const Vec3& n = layout->plane_n;
    char axis[96];
    std::snprintf(axis, sizeof axis, "(%.6g, %.6g, %.6g)", n.x(), n.y(), n.z());
    p.solver_reason += std::string("; planar: every joint a revolute about axes parallel to ") + axis +
                       ", so the recursion runs on 3x3 blocks";
  }
  // The backward pass reaches a parent's children from the last one in tree order: that
  // one writes its share, the others add theirs.
  layout->first_share.assign(p.joints.size(), 0);
  layout->has_children.assign(p.joints.size(), 0);
  for (size_t L = p.joints.size(); L-- > 0;) {
    const int P = layout->parent[L];
    if (P < 0) continue;
    const auto uP = static_cast<size_t>(P);
    layout->first_share[L] = !layout->has_children[uP];
    layout->has_children[uP] = 1;
  }
  p.tree = std::move(layout);
}

void InitTreeWorkspace(const Program& p, Workspace& ws) {
  const size_t K = p.bodies.size();
  ws.tree_Ia.assign(K, Mat6::Zero());
  ws.tree_pa.assign(K, Vec6::Zero());
  ws.tree_A.assign(K, Vec6::Zero());
  ws.tree_U = Eigen::VectorXd::Zero(6 * p.nu);
  ws.tree_Dinv = Eigen::VectorXd::Zero(p.tree->d_size);
  ws.tree_u = Eigen::VectorXd::Zero(p.nu);
  if (p.tree->planar) ws.tree_plane.assign(K, std::array<double, 12>{});
}

int SingularMassMatrix(Workspace& ws) {
  ws.error = "singular mass matrix (a body without mass or inertia moved by a joint?)";
  return -1;
}

int SolveTree(const Program& p, Workspace& ws) {
  return p.tree->planar ? SolveTreePlanar(p, ws) : SolveTreeSpatial(p, ws);
}

int SolveTreeSpatial(const Program& p, Workspace& ws) {
  if (p.nu == 0) return 0;
  const TreeLayout& T = *p.tree;
  const int K = static_cast<int>(p.bodies.size());
  PivotRange piv;
  // Backward pass, leaves to root: (4), (6), (7); a child moves its share into its parent.
  // The share of a child whose parent is the next body of the pass (a chain) stays in
  // `carry`, the others go through tree_Ia, tree_pa.
  Articulated carry;
  bool carried = false;  // carry holds body L's children's shares
  for (int L = K - 1; L >= 0; --L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    Mat6& Ia = ws.tree_Ia[uL];
    Vec6& pa = ws.tree_pa[uL];
    // Body L's own inertia Mb_L and -w_L about o_L: (6), (7) at a leaf, else added.
    Articulated X = carried ? carry : T.has_children[uL] ? Load(Ia, pa) : Articulated();
    AddBody(p, ws, uL, &X);
    double* U = ws.tree_U.data() + 6 * J.f0;
    double* Dinv = ws.tree_Dinv.data() + J.d0;
    double* u = ws.tree_u.data() + J.f0;
    if (J.angular) {
      if (!EliminateAngular(ws.H_W.col(J.cols[0]).tail<3>(), ws.Q[J.cols[0]], U, Dinv, u, &X, &piv))
        return SingularMassMatrix(ws);
    } else if (J.nf > 0) {
      Store(X, &Ia, &pa);
      if (!EliminateJoint(ws, J, U, Dinv, u, &Ia, &pa, &piv)) return SingularMassMatrix(ws);
      X = Load(Ia, pa);
    }
    const int P = T.parent[uL];
    carried = P >= 0 && P == L - 1;
    if (P < 0) continue;
    const auto uP = static_cast<size_t>(P);
    const Vec3 &o = ws.p_WB[uL], &oP = ws.p_WB[uP];
    const double r0 = o.x() - oP.x(), r1 = o.y() - oP.y(), r2 = o.z() - oP.z();
    Articulated S = Moved(X, r0, r1, r2);  // (6), (7)
    if (!T.first_share[uL]) Add(Load(ws.tree_Ia[uP], ws.tree_pa[uP]), &S);
    if (carried)
      carry = S;
    else
      Store(S, &ws.tree_Ia[uP], &ws.tree_pa[uP]);
    // U_L^T X_LP A_P = (X_LP^T U_L)^T A_P with X_LP^T [U_v; U_w] = [U_v; U_w + r x U_v],
    // r = o_L - o_P: stored so, (5) in the forward pass waits only for A_P, not for the
    // shift of A_P to o_L as well.
    for (int k = 0; k < J.nf; ++k, U += 6) {
      U[3] += r1 * U[2] - r2 * U[1];
      U[4] += r2 * U[0] - r0 * U[2];
      U[5] += r0 * U[1] - r1 * U[0];
    }
  }
  if (!(piv.min_pivot_sq > kSingularPivot * piv.max_diag)) return SingularMassMatrix(ws);
  // Forward pass, root to leaves: (5), (1). A revolute joint's child takes A_P from the
  // previous step in registers when P = L - 1 (a chain); everything else goes through
  // tree_A, which every step writes.
  double c0 = 0, c1 = 0, c2 = 0, c3 = 0, c4 = 0, c5 = 0;  // A of the previous step
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    const int P = T.parent[uL];
    const double* U = ws.tree_U.data() + 6 * J.f0;
    const double* Dinv = ws.tree_Dinv.data() + J.d0;
    const double* u = ws.tree_u.data() + J.f0;
    Vec6& A = ws.tree_A[uL];
    if (P < 0) {
      A.setZero();
      SubstituteJoint(J, U, Dinv, u, A, ws, &A);
    } else {
      const auto uP = static_cast<size_t>(P);
      const Vec6& AP = ws.tree_A[uP];
      if (P != L - 1) c0 = AP[0], c1 = AP[1], c2 = AP[2], c3 = AP[3], c4 = AP[4], c5 = AP[5];
      const Vec3 &o = ws.p_WB[uL], &oP = ws.p_WB[uP];
      const double r0 = o.x() - oP.x(), r1 = o.y() - oP.y(), r2 = o.z() - oP.z();
      const double a0 = c0 + c4 * r2 - c5 * r1;  // X_LP A_P
      const double a1 = c1 + c5 * r0 - c3 * r2;
      const double a2 = c2 + c3 * r1 - c4 * r0;
      if (J.angular) {
        const double ud = *Dinv * (*u - (U[0] * c0 + U[1] * c1 + U[2] * c2 + U[3] * c3 + U[4] * c4 + U[5] * c5));  // (5)
        const auto h = ws.H_W.col(J.cols[0]);
        c0 = a0, c1 = a1, c2 = a2;
        c3 += h[3] * ud;  // (1)
        c4 += h[4] * ud;
        c5 += h[5] * ud;
        A[0] = c0, A[1] = c1, A[2] = c2, A[3] = c3, A[4] = c4, A[5] = c5;
        ws.udot[J.cols[0]] = ud;
        continue;
      }
      A[0] = a0, A[1] = a1, A[2] = a2, A[3] = c3, A[4] = c4, A[5] = c5;
      SubstituteJoint(J, U, Dinv, u, AP, ws, &A);
    }
    c0 = A[0], c1 = A[1], c2 = A[2], c3 = A[3], c4 = A[4], c5 = A[5];
  }
  return 0;
}

// ----------------------------------------------------------------------------- planar trees
// A tree whose joints are all revolute about axes parallel to one world direction n (the
// double pendulum, a planar linkage opened at its cut joints, a walker in its sagittal
// plane). Every free column is S_L = [0; s_L n] (s_L = h_L . n), so the free-udot part of
// every body's acceleration (1) stays in the plane: a in span(e1, e2), alpha along n, with
// (e1, e2, n) right-handed. Write A = (a1, a2, alpha) in those coordinates and a wrench
// as (f1, f2, tau) = (f . e1, f . e2, n . torque). Then
// - X_LP maps the in-plane components of A_P to in-plane components only, and X*_LP the
//   in-plane rows of a wrench to in-plane rows only (alpha x r and (r x f) . n read the
//   in-plane parts of r = o_L - o_P and f alone), so the in-plane 3x3 block of every
//   product in (6), (7) is the product of the in-plane blocks;
// - S_L^T picks tau, so (2) reads only the in-plane rows.
// The recursion (4)-(7) therefore closes on 3x3 blocks: out-of-plane forces, torques and
// accelerations are carried by the joints' reactions and never enter udot. With
// (x, y) = in-plane coordinates of c_L - o_L, body L's inertia about o_L is
//   Mb_L = [m, 0, -m y;  0, m, m x;  -m y, m x, I_nn + m (x^2 + y^2)],  I_nn = n . I n   (8)
// and its bias wrench -w_L = (-f1, -f2, -(tau_c + x f2 - y f1)) with f = F - m a_bias_cm,
// tau_c = n . (T - I alpha_bias - w x I w) = n . T: the angular velocities are all along
// n, so alpha_bias = sum w_P x w_rel = 0 and w x I w has no n part. I_nn is constant: n is
// +-(body L's axis in its own frame).
// Eliminating joint L: U = s_L (b1, b2, c) (the column alpha of Ia), d = s_L^2 c; the
// bracket of (6) clears that row and column (b, c -> 0), leaving the 2x2 block A; moved
// by (x, y) = in-plane r, with g = (-y, x):
//   X*_LP [A, 0; 0, 0] X_LP = [A, A g; g^T A, g^T A g],  tau += x f2 - y f1.               (9)
// About 60 flops per body against ~280 for the 6x6 form; the same pivots D_L.

namespace {

// An articulated inertia and bias wrench of the planar recursion, in plane coordinates:
// Ia = [a11, a12, b1; a12, a22, b2; b1, b2, c], pa = (p1, p2, p3).
struct Plane {
  double a11 = 0, a12 = 0, a22 = 0, b1 = 0, b2 = 0, c = 0, p1 = 0, p2 = 0, p3 = 0;
};

inline Plane LoadPlane(const std::array<double, 12>& v) {
  return {v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]};
}

inline void StorePlane(const Plane& X, std::array<double, 12>* v) {
  std::array<double, 12>& w = *v;
  w[0] = X.a11, w[1] = X.a12, w[2] = X.a22, w[3] = X.b1, w[4] = X.b2, w[5] = X.c;
  w[6] = X.p1, w[7] = X.p2, w[8] = X.p3;
}

// Body L's Mb_L (8) and -w_L added to X.
void AddBodyPlane(const Program& p, const Workspace& ws, size_t L, Plane* X) {
  const TreeLayout& T = *p.tree;
  const Vec3 &n = T.plane_n, &e1 = T.plane_e1, &e2 = T.plane_e2;
  const double m = p.bodies[L].mass;
  const Vec3 d = ws.p_WBcm[L] - ws.p_WB[L];
  const double x = d.dot(e1), y = d.dot(e2);
  const Vec3 f = ws.F_W[L] - m * ws.a_bias_cm[L];
  const double f1 = f.dot(e1), f2 = f.dot(e2);
  const double tau = ws.T_W[L].dot(n);  // alpha_bias = 0 and w x I w has no n part: w is along n
  Plane& M = *X;
  M.a11 += m, M.a22 += m;
  M.b1 -= m * y, M.b2 += m * x;
  M.c += T.plane_Inn[L] + m * (x * x + y * y);
  M.p1 -= f1, M.p2 -= f2;
  M.p3 -= tau + (x * f2 - y * f1);
}

}  // namespace

int SolveTreePlanar(const Program& p, Workspace& ws) {
  const TreeLayout& T = *p.tree;
  const int K = static_cast<int>(p.bodies.size());
  const Vec3 &e1 = T.plane_e1, &e2 = T.plane_e2;
  PivotRange piv;
  // Backward pass, leaves to root: (4), (6), (7) on 3x3 blocks; a chain's share stays in
  // `carry`, the others go through tree_plane. Per joint, tree_U keeps U moved to the
  // parent (9) in 0..2, s_L in 3 and the in-plane r in 4, 5 for the forward pass.
  Plane carry;
  bool carried = false;
  for (int L = K - 1; L >= 0; --L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    Plane X = carried ? carry : T.has_children[uL] ? LoadPlane(ws.tree_plane[uL]) : Plane();
    AddBodyPlane(p, ws, uL, &X);
    const int col = J.cols[0];
    const double s = T.plane_s[uL];
    const double U1 = s * X.b1, U2 = s * X.b2, U3 = s * X.c;  // (4)
    const double d = s * U3;
    const double u = ws.Q[col] - s * X.p3;
    piv.max_diag = std::max(piv.max_diag, d);
    if (!(d > 0.0)) return SingularMassMatrix(ws);
    piv.min_pivot_sq = std::min(piv.min_pivot_sq, d);
    const double dinv = 1.0 / d;
    ws.tree_Dinv[J.d0] = dinv;
    ws.tree_u[J.f0] = u;
    double* U = ws.tree_U.data() + 6 * J.f0;
    U[3] = s;
    const int P = T.parent[uL];
    carried = P >= 0 && P == L - 1;
    if (P < 0) {
      U[0] = U1, U[1] = U2, U[2] = U3, U[4] = U[5] = 0.0;
      continue;
    }
    // Brackets of (6), (7): the alpha row and column cleared, the 2x2 block and pa updated.
    const double a11 = X.a11 - U1 * U1 * dinv, a12 = X.a12 - U1 * U2 * dinv, a22 = X.a22 - U2 * U2 * dinv;
    const double ud = u * dinv;
    const double p1 = X.p1 + U1 * ud, p2 = X.p2 + U2 * ud, p3 = X.p3 + U3 * ud;
    const auto uP = static_cast<size_t>(P);
    const Vec3 r = ws.p_WB[uL] - ws.p_WB[uP];
    const double x = r.dot(e1), y = r.dot(e2);
    Plane S;  // (9)
    S.a11 = a11, S.a12 = a12, S.a22 = a22;
    S.b1 = x * a12 - y * a11, S.b2 = x * a22 - y * a12;
    S.c = x * S.b2 - y * S.b1;
    S.p1 = p1, S.p2 = p2, S.p3 = p3 + x * p2 - y * p1;
    if (!T.first_share[uL]) {
      const Plane O = LoadPlane(ws.tree_plane[uP]);
      S.a11 += O.a11, S.a12 += O.a12, S.a22 += O.a22, S.b1 += O.b1, S.b2 += O.b2, S.c += O.c;
      S.p1 += O.p1, S.p2 += O.p2, S.p3 += O.p3;
    }
    if (carried)
      carry = S;
    else
      StorePlane(S, &ws.tree_plane[uP]);
    U[0] = U1, U[1] = U2, U[2] = U3 + x * U2 - y * U1;  // X_LP^T U, as in SolveTreeSpatial
    U[4] = x, U[5] = y;
  }
  if (!(piv.min_pivot_sq > kSingularPivot * piv.max_diag)) return SingularMassMatrix(ws);
  // Forward pass, root to leaves: (5), then (1) in the plane; a chain's A_P in registers.
  double c1 = 0, c2 = 0, c3 = 0;  // A of the previous step
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    const int P = T.parent[uL];
    const double* U = ws.tree_U.data() + 6 * J.f0;
    if (P < 0) {
      c1 = c2 = c3 = 0.0;
    } else if (P != L - 1) {
      const std::array<double, 12>& AP = ws.tree_plane[static_cast<size_t>(P)];
      c1 = AP[9], c2 = AP[10], c3 = AP[11];
    }
    const double ud = ws.tree_Dinv[J.d0] * (ws.tree_u[J.f0] - (U[0] * c1 + U[1] * c2 + U[2] * c3));  // (5)
    const double x = U[4], y = U[5];
    c1 -= c3 * y, c2 += c3 * x, c3 += U[3] * ud;  // (1)
    std::array<double, 12>& A = ws.tree_plane[uL];
    A[9] = c1, A[10] = c2, A[11] = c3;
    ws.udot[J.cols[0]] = ud;
  }
  return 0;
}

}  // namespace kanesim::rt
