// Lesser's diagonal generalized speeds (Lesser 1992, "A geometrical interpretation of Kane's
// equations", §6, eqs. 81-92; docs/notation.md "Diagonal speeds"): `kanesim run --speeds
// diagonal`. The tangent basis tau_1..tau_n is orthogonalized by Gram-Schmidt in the kinetic
// metric (a . b = sum_L m_L v_a . v_b + w_a . I_L w_b), in a chosen order, without normalizing:
//
//   tau'_i = tau_i - sum_{j<i} (tau_i . tau'_j / d_j) tau'_j,   d_i = tau'_i . tau'_i     (83)
//
// In matrix form, with M = tau^T tau (the mass matrix of Kane's equations) in that order,
// this is the unit lower-triangular factorization
//
//   M = L D L^T,   tau = tau' L^T,   w = L^T u,   T = 1/2 u^T M u = 1/2 sum_i d_i w_i^2 (1)
//
// so w_i = u_i + sum_{j>i} L_ji u_j (eqs. 91-92: the first speed collects all the others,
// the last is u_n itself). Kane's equations on tau' are diagonal (Lesser §6, last paragraph):
//
//   d_i wdot_i = (L^-1 f)_i + sum_{j>i} X_ij w_j,   X = L^-1 Mdot L^-T                   (2)
//
// from D wdot = D (L^T udot + Ldot^T u), L^-1 M udot = D L^T udot and Ldot = L S D^-1 with S
// the strictly lower part of X (differentiate (1): X = (L^-1 Ldot) D + Ddot + D (L^-1 Ldot)^T).
// Mdot = dM/dt along the motion is taken by central differences of M(t +- h, q +- h qdot)
// with one Richardson step (error O(h^4) + eps/h, about 1e-12 relative).
//
// Closed loops and rolling contacts (constraint rows): the same on the constrained tangent
// basis, the independent speeds u_I of the partition at the start (held for the run): u =
// beta u_I, M~ = beta^T M beta = L D L^T, w = L^T u_I (dof entries). beta's columns are the
// motions with one independent speed 1 and the others 0 (rt::ProjectByPartition), and M~ comes
// from the kinetic energy by polarization, T(beta x) = 1/2 x^T M~ x (ConstrainedBasis). The
// multiplier form (no partition) and rheonomic constraints (T not a quadratic form in u_I)
// are refused. No end stops or plane contacts.
#pragma once

#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/integrator.h"

namespace kanesim::sim {

enum class Speeds { kJoint, kDiagonal };  // `--speeds joint|diagonal`

// The free speeds' names, in state order: "shoulder.u", "ball.u[2]".
std::vector<std::string> FreeSpeedNames(const rt::Program& program);

// The Gram-Schmidt order: order[i] = the free speed that is the i-th. The speeds of the joints
// named (in the order given) first, then the others in tree order (root to leaf). Empty and
// *error set for an unknown joint, a joint named twice or one without free speeds.
std::vector<int> SpeedOrder(const rt::Program& program, const std::vector<std::string>& joints, std::string* error);

// Why this program cannot run in diagonal speeds ("" when it can).
std::string DiagonalSpeedsRefusal(const rt::Program& program);

// How many diagonal speeds: the free speeds, or with constraint rows the degrees of freedom.
int DiagonalSpeedCount(const rt::Program& program);

// Which joint speeds enter each w_i (the structural pattern of L^T: M_rs can be non-zero only
// when one of the two joints lies on the other's path to the root, and the factorization
// fills in by elimination), as lines for `kanesim check`.
std::string DescribeConstruction(const rt::Program& program, const std::vector<int>& order);

// Closed loops and rolling contacts: the independent speeds and the basis beta of the
// constrained tangent space, and the reduced mass matrix M~ = beta^T M beta.
class ConstrainedBasis {
 public:
  explicit ConstrainedBasis(const rt::Program& program);
  // The partition at the state y (consistent), held from now on. 0, or nonzero with *error.
  int Init(double t, const double* y, std::string* error);
  const std::vector<int>& Independent() const { return independent_; }  // free speed indices
  // out = [q of y projected onto the position constraints; beta u_I] (StateSize entries).
  int Complete(double t, const double* y, const double* u_independent, double* out);
  // M~ (column-major, dof x dof) at the coordinates of y: M~_ii = 2 T(beta e_i),
  // M~_ij = T(beta (e_i + e_j)) - T(beta e_i) - T(beta e_j).
  int ReducedMass(double t, const double* y, double* M);
  const std::string& Error() const { return error_; }

 private:
  double Energy(double t, const double* y, const double* u_independent, int* status);

  const rt::Program& program_;
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> ws_, out_ws_;
  std::shared_ptr<const rt::SignalPlan> energy_;
  std::vector<int> independent_;
  std::vector<double> x_, yy_, zz_;
  std::string error_;
};

// M (permuted to `order`) = L D L^T, unit lower L: eqs. (83) as a factorization.
class DiagonalFactor {
 public:
  explicit DiagonalFactor(std::vector<int> order);
  int Size() const { return n_; }
  // Factors the free-speed mass matrix M (column-major, n x n, state order). 0, or 1 when a
  // pivot d_i is not above 1e-14 of the largest diagonal entry (not positive definite).
  int Factor(const double* M);
  void SpeedsToW(const double* u, double* w) const;  // w = L^T u (eq. 1)
  void WToSpeeds(const double* w, double* u) const;  // u = L^-T w
  const Eigen::MatrixXd& L() const { return L_; }    // in the permuted order
  const Eigen::VectorXd& d() const { return d_; }
  const std::vector<int>& order() const { return order_; }

 private:
  int n_;
  std::vector<int> order_;
  Eigen::MatrixXd L_;
  Eigen::VectorXd d_;
  mutable Eigen::VectorXd tmp_;
};

// The equations of motion in the state z = [q_free; w] around an OdeSystem in y = [q_free;
// u_free] (the engine's): Rhs by eq. (2). With constraint rows, w has dof entries (the
// independent speeds') and Init must be called at the start before anything else.
class DiagonalOde final : public OdeSystem {
 public:
  DiagonalOde(const rt::Program& program, OdeSystem& inner, std::vector<int> order);
  // Constraint rows: the partition at the start state y (0, or nonzero with FailureCause()).
  int Init(double t, const double* y);
  int Size() const override { return nq_ + n_; }
  int Rhs(double t, const double* z, double* zdot) override;
  std::string FailureCause() const override { return own_error_.empty() ? inner_.FailureCause() : own_error_; }
  // z <-> y at time t (factors M at z's coordinates). 0 or Rhs's codes.
  int ToSpeeds(double t, const double* z, double* y);
  int ToW(double t, const double* y, double* z);
  // After ToSpeeds or ToW: w, d and each speed's energy 1/2 d_i w_i^2 (3 n values).
  void Columns(const double* z, double* out) const;
  const DiagonalFactor& factor() const { return factor_; }
  // The inner system's events and step checks (rolling contacts' lift-off, the loops' branch
  // monitor), on y = ToSpeeds(z).
  int NumEvents() const override { return inner_.NumEvents(); }
  int EventFunctions(double t, const double* z, double* g) override;
  int Event(double t, double* z, int i) override;
  bool ChecksSteps() const override { return inner_.ChecksSteps(); }
  int StepAccepted(double t, const double* z) override;
  void HoldForJacobian(bool on) override { inner_.HoldForJacobian(on); }

 private:
  int FactorAt(double t, const double* y);  // M(q of y, t) into factor_
  int Speeds(double t, const double* z, double* y);
  int MassAt(double t, const double* y, Eigen::MatrixXd* M);
  int MassRate(double t, const double* y, const double* ydot);  // Mdot into Mdot_

  const rt::Program& program_;
  OdeSystem& inner_;
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> ws_;  // MassMatrix's
  std::unique_ptr<ConstrainedBasis> basis_;  // constraint rows only
  std::vector<int> order_all_;               // the order over all free speeds
  int nq_, n_;
  DiagonalFactor factor_;
  Eigen::MatrixXd M_, Mp_, Mdot_, X_;  // n x n scratch
  std::vector<double> y_, ydot_, yh_;  // [q; u] scratch
  std::vector<double> ui_, uidot_;     // independent speeds (constraint rows)
  std::string own_error_;
};

}  // namespace kanesim::sim
