// The independent coordinates and speeds about an operating point (docs/linearize.md,
// "States"): a chart of the configuration, the holonomic constraints solved for the
// dependent chart coordinates, the velocity constraints for the dependent speeds.
//
// Chart (one coordinate xi_i per free speed u_i, in the same order):
//   scalar joint coordinate q_k (q_k' = u_i, or N(q) u for Cardan/Euler angles):
//       q_k = q_k0 + xi_i
//   unit quaternion Q of a spherical or free joint (u = w_ab in b, body-fixed):
//       Q = Q0 (x) Exp(xi_b),  Exp(v) = (cos(|v|/2), sin(|v|/2) v/|v|)            (2)
//       xi_b' = J_r^-1(xi_b) w_b,   w_b = 2 vec(Q^* (x) Q')                          (3)
//       J_r^-1(v) = 1 + [v]x / 2 + (1/|v|^2 - (1 + cos|v|) / (2 |v| sin|v|)) [v]x^2  (4)
// where J_r is the right Jacobian of SO(3) (Sola, Deray & Atchuthan, "A micro Lie theory
// for state estimation in robotics", 2018, eqs. 143-144).
//
// Partition: holonomic rows phi(q(xi)) = 0 (loop rows, a contact's normal row): column
// pivoted QR of Phi = d phi / d xi picks rank(Phi) dependent chart coordinates D_q;
// velocity rows A u + b = 0 (every row): the speeds of D_q first, then column pivoting on
// the part of A that they leave, up to rank(A) dependent speeds D_u.
#pragma once

#include <Eigen/Core>
#include <Eigen/QR>
#include <memory>
#include <string>
#include <vector>

#include "linearize/linearize.h"
#include "runtime/program/program.h"

namespace kanesim::lin {

// A constraint row the operating point adds (docs/linearize.md "End stops, contacts and
// friction"): a free speed held at zero with its coordinate fixed (a joint resting on its
// stop, a stuck joint), or a plane contact at rest (its gap and normal speed held at zero).
struct HeldRow {
  int speed = -1;  // free speed index, or -1
  int plane = -1;  // plane contact index (rt::PlaneContacts), or -1
};

class Reduction {
 public:
  // Builds the chart and the partition at `op`. With `fix_speeds`, the dependent speeds
  // of op are solved for (an equilibrium search sets every speed to zero first);
  // otherwise op must satisfy the velocity constraints (status 1 if not). `held`: rows
  // that hold at op besides the program's, holonomic like a loop's.
  Status Init(const rt::Program& p, const OperatingPoint& op, bool fix_speeds, std::vector<HeldRow> held = {});
  // The model's inputs (rt::InputName order) the configuration is evaluated with (a
  // prescribed motion may read them); before Init. Empty: none.
  void SetInputs(const std::vector<double>& u) { inputs_ = u; }

  int nu() const { return p_->nu; }
  const std::vector<int>& indep_coords() const { return iq_; }  // chart indices
  const std::vector<int>& indep_speeds() const { return iu_; }   // free speed indices
  const std::string& coord_name(int i) const { return coord_names_[static_cast<size_t>(i)]; }
  const std::string& speed_name(int i) const { return speed_names_[static_cast<size_t>(i)]; }
  const std::vector<double>& y0() const { return y0_; }
  double t() const { return t_; }

  // y = [q_free; u_free] for independent chart coordinates xi_I and speed deviations
  // du_I (the dependent ones solved for). Status 2 when the loop cannot be closed.
  Status StateOf(const Eigen::VectorXd& xi_I, const Eigen::VectorXd& du_I, Eigen::VectorXd* y);
  // The chart rates xi' (nu) at the state y last built by StateOf, from q_free'.
  void ChartRates(const Eigen::VectorXd& y, const double* qdot_free, Eigen::VectorXd* xidot) const;
  // The chart coordinates (nu) of the configuration in y (xi of eq. 2, by the logarithm).
  Eigen::VectorXd ChartOf(const Eigen::VectorXd& y) const;
  // The size of what chart coordinate i moves: |q_k0| of a scalar coordinate, 1 for a
  // quaternion's rotation vector (the components are at most 1). A step in it below about
  // eps times this is lost when added (linearize.cpp, eq. 8).
  double CoordMagnitude(int i) const;

 private:
  struct Coord {
    int q = -1;      // free q index (additive), or of the quaternion's w (rotation)
    int comp = -1;   // -1: additive; 0..2: component of a quaternion block
  };
  void Retract(const Eigen::VectorXd& xi, Eigen::VectorXd* qf) const;
  Status Phi(const Eigen::VectorXd& qf, Eigen::VectorXd* phi);
  Status Psi(const Eigen::VectorXd& qf, const Eigen::VectorXd& uf, Eigen::VectorXd* psi);
  Status SolveSpeeds(const Eigen::VectorXd& qf, Eigen::VectorXd* uf);

  const rt::Program* p_ = nullptr;
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> ws_{nullptr, nullptr};
  std::vector<double> inputs_;  // SetInputs
  double t_ = 0.0;
  std::vector<double> y0_;
  Eigen::VectorXd q0_, u0_;                 // free coordinates and speeds of the operating point
  std::vector<Coord> coords_;               // per chart coordinate (nu)
  std::vector<std::string> coord_names_, speed_names_;  // per chart coordinate / free speed
  std::vector<int> hol_rows_;               // rows with a position form
  std::vector<HeldRow> held_;               // rows the operating point adds (after the program's)
  std::vector<int> iq_, dq_, iu_, du_;      // independent / dependent chart coordinates and speeds
  Eigen::HouseholderQR<Eigen::MatrixXd> qr_phi_dep_;  // Phi(:, D_q)
  Eigen::HouseholderQR<Eigen::MatrixXd> qr_a_dep_;    // A(:, D_u)
  Eigen::VectorXd xi_dep_;                  // last dependent chart coordinates (warm start)
  double length_ = 1.0;                     // position tolerance scale
};

}  // namespace kanesim::lin
