// The chart of the configuration and the independent/dependent partition (reduction.h).
#include "linearize/reduction.h"

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "runtime/constraints/constraints.h"
#include "runtime/kinematics/kinematics.h"

namespace kanesim::lin {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using rt::Vec3;

// Eq. (2).
Eigen::Quaterniond ExpQ(const Vec3& v) {
  const double th = v.norm();
  if (th < 1e-8) return Eigen::Quaterniond(1.0, v.x() / 2, v.y() / 2, v.z() / 2).normalized();
  const double s = std::sin(th / 2) / th;
  return Eigen::Quaterniond(std::cos(th / 2), s * v.x(), s * v.y(), s * v.z());
}

// The inverse of eq. (2) on the branch |v| <= pi.
Vec3 LogQ(Eigen::Quaterniond q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Vec3 vec = q.vec();
  const double s = vec.norm();
  if (s < 1e-12) return 2.0 * vec / q.w();
  return 2.0 * std::atan2(s, q.w()) * vec / s;
}

// Eq. (4).
rt::Mat3 RightJacobianInverse(const Vec3& v) {
  const double th = v.norm();
  const rt::Mat3 K = rt::Skew(v);
  const double c = th < 1e-4 ? 1.0 / 12.0 + th * th / 720.0
                             : 1.0 / (th * th) - (1.0 + std::cos(th)) / (2.0 * th * std::sin(th));
  return rt::Mat3::Identity() + 0.5 * K + c * K * K;
}

// "loop 'cut'", "contact 'c'" or "coupling 'm'", and where it is declared.
std::string RowOwner(const rt::Program& p, const rt::ConstraintRow& row) {
  if (row.coupling >= 0) return "coupling '" + p.couplings[static_cast<size_t>(row.coupling)].name + "'";
  return row.loop >= 0 ? "loop '" + p.loops[static_cast<size_t>(row.loop)].name + "'"
                       : "contact '" + p.contacts[static_cast<size_t>(row.contact)].name + "'";
}
flat::SourceLoc RowLoc(const rt::Program& p, const rt::ConstraintRow& row) {
  if (row.coupling >= 0) return p.couplings[static_cast<size_t>(row.coupling)].loc;
  return row.loop >= 0 ? p.loops[static_cast<size_t>(row.loop)].loc : p.contacts[static_cast<size_t>(row.contact)].loc;
}

bool Holonomic(rt::RowKind k) {
  return k == rt::RowKind::Translation || k == rt::RowKind::Alignment || k == rt::RowKind::ContactNormal ||
         k == rt::RowKind::Coupling;
}

}  // namespace

Status Reduction::Init(const rt::Program& p, const OperatingPoint& op, bool fix_speeds, std::vector<HeldRow> held) {
  p_ = &p;
  held_ = std::move(held);
  ws_ = rt::MakeWorkspace(p);
  if (!inputs_.empty()) rt::SetInputValues(*ws_, inputs_.data());
  t_ = op.t;
  y0_ = op.y;
  const int nq = p.nq, nu = p.nu;
  if (static_cast<int>(op.y.size()) != nq + nu) return {1, "the operating point has the wrong size"};
  q0_ = Eigen::Map<const VectorXd>(op.y.data(), nq);
  u0_ = Eigen::Map<const VectorXd>(op.y.data() + nq, nu);
  length_ = std::max(p.loop_length, 1e-6);

  // The chart: one coordinate per free speed.
  std::vector<int> free_q(static_cast<size_t>(p.nq_all), -1);
  for (int i = 0; i < nq; ++i) free_q[static_cast<size_t>(p.q_free[static_cast<size_t>(i)])] = i;
  coords_.assign(static_cast<size_t>(nu), Coord{});
  coord_names_.assign(static_cast<size_t>(nu), "");
  speed_names_.assign(static_cast<size_t>(nu), "");
  for (int i = 0; i < nu; ++i) {
    const int r = p.u_free[static_cast<size_t>(i)];
    const rt::TreeJoint& j = p.joints[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(r)])];
    const int k = r - j.u0;
    const bool quat = j.nq == j.nu + 1;  // a unit quaternion holds the rotation
    const int nlin = j.type == flat::JointType::Free ? 3 : 0;
    Coord c;
    if (!quat || k < nlin) {
      c.q = free_q[static_cast<size_t>(j.q0 + k)];
      coord_names_[static_cast<size_t>(i)] = j.name + ".q" + (j.nq > 1 ? rt::Index1(k) : "");
    } else {
      c.q = free_q[static_cast<size_t>(j.q0 + nlin)];
      c.comp = k - nlin;
      coord_names_[static_cast<size_t>(i)] = j.name + ".rot" + rt::Index1(k - nlin);
    }
    if (c.q < 0) return {2, "joint '" + j.name + "': a free speed whose coordinate is prescribed"};
    coords_[static_cast<size_t>(i)] = c;
    speed_names_[static_cast<size_t>(i)] = j.name + ".u" + (j.nu > 1 ? rt::Index1(k) : "");
  }

  hol_rows_.clear();
  for (size_t r = 0; r < p.rows.size(); ++r)
    if (Holonomic(p.rows[r].kind)) hol_rows_.push_back(static_cast<int>(r));
  const int nh = static_cast<int>(hol_rows_.size() + held_.size());
  const int nc = static_cast<int>(p.rows.size() + held_.size());

  // The operating point must close every loop.
  VectorXd phi0;
  if (Status s = Phi(q0_, &phi0); !s.ok()) return s;
  if (nh > 0) {
    Eigen::Index worst = 0;
    const double err = phi0.cwiseAbs().maxCoeff(&worst);
    if (err > 1e-7 * length_ && worst >= static_cast<Eigen::Index>(hol_rows_.size())) {
      return {1, fmt::format("the operating point is {:.3g} off a contact that holds there", err)};
    } else if (err > 1e-7 * length_) {
      const rt::ConstraintRow& row = p.rows[static_cast<size_t>(hol_rows_[static_cast<size_t>(worst)])];
      return {1,
              fmt::format("the operating point violates the position constraint {} ({}) by {:.3g}", RowOwner(p, row),
                          row.what, err),
              "linearize about the start values as assembled, or a state of the motion (--at T)", RowLoc(p, row)};
    }
  }

  // Phi = d phi / d xi by central differences; pivoted QR picks the dependent coordinates.
  MatrixXd Jphi(nh, nu);
  if (nh > 0) {
    const double h = 1e-6;
    for (int i = 0; i < nu; ++i) {
      VectorXd xi = VectorXd::Zero(nu), qp(nq), qm(nq), fp, fm;
      xi[i] = h;
      Retract(xi, &qp);
      xi[i] = -h;
      Retract(xi, &qm);
      if (Status s = Phi(qp, &fp); !s.ok()) return s;
      if (Status s = Phi(qm, &fm); !s.ok()) return s;
      Jphi.col(i) = (fp - fm) / (2 * h);
    }
  }
  dq_.clear();
  iq_.clear();
  int rq = 0;
  if (nh > 0) {
    Eigen::ColPivHouseholderQR<MatrixXd> qr(Jphi);
    qr.setThreshold(1e-7);
    rq = static_cast<int>(qr.rank());
    for (int k = 0; k < rq; ++k) dq_.push_back(qr.colsPermutation().indices()[k]);
    std::sort(dq_.begin(), dq_.end());
  }
  for (int i = 0; i < nu; ++i)
    if (std::find(dq_.begin(), dq_.end(), i) == dq_.end()) iq_.push_back(i);
  MatrixXd Phi_dep(nh, rq);
  for (int k = 0; k < rq; ++k) Phi_dep.col(k) = Jphi.col(dq_[static_cast<size_t>(k)]);
  qr_phi_dep_.compute(Phi_dep);
  xi_dep_ = VectorXd::Zero(rq);

  // A: the velocity constraints are affine in u, so each column is one difference.
  MatrixXd A(nc, nu);
  VectorXd psi0;
  if (nc > 0) {
    if (Status s = Psi(q0_, u0_, &psi0); !s.ok()) return s;
    for (int i = 0; i < nu; ++i) {
      VectorXd u = u0_, psi;
      u[i] += 1.0;
      if (Status s = Psi(q0_, u, &psi); !s.ok()) return s;
      A.col(i) = psi - psi0;
    }
  }
  du_.clear();
  iu_.clear();
  int ru = 0;
  if (nc > 0) {
    Eigen::ColPivHouseholderQR<MatrixXd> qr_all(A);
    qr_all.setThreshold(1e-10);
    ru = static_cast<int>(qr_all.rank());
    if (ru < p.loop_rank)
      return {2,
              fmt::format("singular configuration: the constraint Jacobian has rank {} here, {} at the assembled "
                          "start (a dead point or a locked loop; the linear model would not be valid)",
                          ru, p.loop_rank),
              "linearize about a configuration away from it (other start values, --at T)",
              p.loops.empty() ? flat::SourceLoc{} : p.loops.front().loc};
    // The dependent coordinates' speeds first, when they are independent columns of A.
    std::vector<int> S;
    if (rq > 0) {
      MatrixXd As(nc, rq);
      for (int k = 0; k < rq; ++k) As.col(k) = A.col(dq_[static_cast<size_t>(k)]);
      Eigen::ColPivHouseholderQR<MatrixXd> qs(As);
      qs.setThreshold(1e-10);
      if (qs.rank() == rq) S = dq_;
    }
    std::vector<int> rest;
    for (int i = 0; i < nu; ++i)
      if (std::find(S.begin(), S.end(), i) == S.end()) rest.push_back(i);
    MatrixXd R(nc, static_cast<int>(rest.size()));
    for (size_t k = 0; k < rest.size(); ++k) R.col(static_cast<int>(k)) = A.col(rest[k]);
    if (!S.empty()) {
      MatrixXd As(nc, static_cast<int>(S.size()));
      for (size_t k = 0; k < S.size(); ++k) As.col(static_cast<int>(k)) = A.col(S[k]);
      Eigen::HouseholderQR<MatrixXd> qs(As);
      const MatrixXd Q = qs.householderQ() * MatrixXd::Identity(nc, static_cast<int>(S.size()));
      R -= Q * (Q.transpose() * R);
    }
    const int more = ru - static_cast<int>(S.size());
    if (more > 0) {
      Eigen::ColPivHouseholderQR<MatrixXd> qr(R);
      for (int k = 0; k < more; ++k) S.push_back(rest[static_cast<size_t>(qr.colsPermutation().indices()[k])]);
    }
    du_ = S;
    std::sort(du_.begin(), du_.end());
  }
  for (int i = 0; i < nu; ++i)
    if (std::find(du_.begin(), du_.end(), i) == du_.end()) iu_.push_back(i);
  MatrixXd A_dep(nc, ru);
  for (int k = 0; k < ru; ++k) A_dep.col(k) = A.col(du_[static_cast<size_t>(k)]);
  qr_a_dep_.compute(A_dep);

  if (nc > 0) {
    const double vscale = 1.0 + u0_.cwiseAbs().maxCoeff() * length_;
    if (fix_speeds) {
      VectorXd u = u0_;
      if (Status s = SolveSpeeds(q0_, &u); !s.ok()) return s;
      u0_ = u;
      for (int i = 0; i < nu; ++i) y0_[static_cast<size_t>(nq + i)] = u0_[i];
    } else if (Eigen::Index worst = 0; psi0.cwiseAbs().maxCoeff(&worst) > 1e-7 * vscale) {
      if (worst >= static_cast<Eigen::Index>(p.rows.size()))
        return {1, fmt::format("the operating point moves off a contact that holds there (speed {:.3g})",
                               std::abs(psi0[worst]))};
      const rt::ConstraintRow& row = p.rows[static_cast<size_t>(worst)];
      return {1,
              fmt::format("the operating point violates the velocity constraint {} ({}) by {:.3g}", RowOwner(p, row),
                          row.what, std::abs(psi0[worst])),
              "start speeds must satisfy the loops and rolling contacts (leave the dependent ones to the assembly)",
              RowLoc(p, row)};
    }
  }
  return {};
}

void Reduction::Retract(const VectorXd& xi, VectorXd* qf) const {
  *qf = q0_;
  for (size_t i = 0; i < coords_.size(); ++i) {
    const Coord& c = coords_[i];
    if (c.comp < 0) {
      (*qf)[c.q] += xi[static_cast<int>(i)];
    } else if (c.comp == 0) {  // the block's first component: apply the whole rotation
      const Vec3 v(xi[static_cast<int>(i)], xi[static_cast<int>(i) + 1], xi[static_cast<int>(i) + 2]);
      Eigen::Quaterniond Q0(q0_[c.q], q0_[c.q + 1], q0_[c.q + 2], q0_[c.q + 3]);
      Q0.normalize();
      const Eigen::Quaterniond Q = Q0 * ExpQ(v);
      (*qf)[c.q] = Q.w();
      (*qf)[c.q + 1] = Q.x();
      (*qf)[c.q + 2] = Q.y();
      (*qf)[c.q + 3] = Q.z();
    }
  }
}

VectorXd Reduction::ChartOf(const VectorXd& y) const {
  VectorXd xi(static_cast<int>(coords_.size()));
  for (size_t i = 0; i < coords_.size(); ++i) {
    const Coord& c = coords_[i];
    if (c.comp < 0) {
      xi[static_cast<int>(i)] = y[c.q] - q0_[c.q];
    } else if (c.comp == 0) {
      Eigen::Quaterniond Q0(q0_[c.q], q0_[c.q + 1], q0_[c.q + 2], q0_[c.q + 3]);
      Eigen::Quaterniond Q(y[c.q], y[c.q + 1], y[c.q + 2], y[c.q + 3]);
      xi.segment<3>(static_cast<int>(i)) = LogQ(Q0.normalized().conjugate() * Q.normalized());
    }
  }
  return xi;
}

double Reduction::CoordMagnitude(int i) const {
  const Coord& c = coords_[static_cast<size_t>(i)];
  return c.comp < 0 ? std::abs(q0_[c.q]) : 1.0;
}

void Reduction::ChartRates(const VectorXd& y, const double* qdot, VectorXd* xidot) const {
  xidot->resize(static_cast<int>(coords_.size()));
  const VectorXd xi = ChartOf(y);
  for (size_t i = 0; i < coords_.size(); ++i) {
    const Coord& c = coords_[i];
    if (c.comp < 0) {
      (*xidot)[static_cast<int>(i)] = qdot[c.q];
    } else if (c.comp == 0) {  // eq. (3)
      const Eigen::Quaterniond Q = Eigen::Quaterniond(y[c.q], y[c.q + 1], y[c.q + 2], y[c.q + 3]).normalized();
      const Eigen::Quaterniond Qd(qdot[c.q], qdot[c.q + 1], qdot[c.q + 2], qdot[c.q + 3]);
      const Vec3 w_b = 2.0 * (Q.conjugate() * Qd).vec();
      xidot->segment<3>(static_cast<int>(i)) = RightJacobianInverse(xi.segment<3>(static_cast<int>(i))) * w_b;
    }
  }
}

Status Reduction::Phi(const VectorXd& qf, VectorXd* phi) {
  const rt::Program& p = *p_;
  const int nh = static_cast<int>(hol_rows_.size());
  phi->resize(nh + static_cast<int>(held_.size()));
  if (phi->size() == 0) return {};
  VectorXd y(p.nq + p.nu);
  y << qf, u0_;
  if (nh > 0) {
    if (rt::UnpackState(p, *ws_, t_, y.data()) != 0) return {2, ws_->error};
    rt::PositionKinematics(p, *ws_);
    rt::ConstraintResiduals(p, *ws_);
    for (int k = 0; k < nh; ++k) (*phi)[k] = ws_->phi[hol_rows_[static_cast<size_t>(k)]];
  }
  for (size_t k = 0; k < held_.size(); ++k) {  // a held coordinate's change, a plane contact's gap
    const HeldRow& h = held_[k];
    double gap = 0.0, bias = 0.0;
    std::vector<double> J(static_cast<size_t>(p.nu));
    if (h.plane >= 0 && rt::PlaneContactRow(p, *ws_, t_, y.data(), h.plane, &gap, J.data(), &bias) != 0)
      return {2, ws_->error};
    const int q = coords_[static_cast<size_t>(std::max(h.speed, 0))].q;
    (*phi)[nh + static_cast<int>(k)] = h.plane >= 0 ? gap : qf[q] - q0_[q];
  }
  return {};
}

Status Reduction::Psi(const VectorXd& qf, const VectorXd& uf, VectorXd* psi) {
  const rt::Program& p = *p_;
  VectorXd y(p.nq + p.nu);
  y << qf, uf;
  if (rt::UnpackState(p, *ws_, t_, y.data()) != 0) return {2, ws_->error};
  rt::PositionKinematics(p, *ws_);
  rt::VelocityKinematics(p, *ws_);
  rt::ConstraintRates(p, *ws_);
  const int nc = static_cast<int>(p.rows.size());
  psi->resize(nc + static_cast<int>(held_.size()));
  psi->head(nc) = ws_->psi.head(nc);
  for (size_t k = 0; k < held_.size(); ++k) {  // a held speed, a plane contact's normal speed
    const HeldRow& h = held_[k];
    double rate = h.plane >= 0 ? 0.0 : uf[h.speed];
    if (h.plane >= 0) {
      double gap = 0.0, bias = 0.0;
      VectorXd J(p.nu);
      if (rt::PlaneContactRow(p, *ws_, t_, y.data(), h.plane, &gap, J.data(), &bias) != 0) return {2, ws_->error};
      rate = J.dot(uf);
    }
    (*psi)[nc + static_cast<int>(k)] = rate;
  }
  return {};
}

// Chord iterations: the dependent speeds' block of A at the operating point.
Status Reduction::SolveSpeeds(const VectorXd& qf, VectorXd* uf) {
  if (du_.empty()) return {};
  const double vscale = 1.0 + uf->cwiseAbs().maxCoeff() * length_;
  double last = 0.0;
  for (int it = 0; it < 60; ++it) {
    VectorXd psi;
    if (Status s = Psi(qf, *uf, &psi); !s.ok()) return s;
    last = psi.size() ? psi.cwiseAbs().maxCoeff() : 0.0;
    const VectorXd d = qr_a_dep_.solve(psi);
    for (size_t k = 0; k < du_.size(); ++k) (*uf)[du_[k]] -= d[static_cast<int>(k)];
    // Converged when the step reaches rounding, or stops shrinking near it.
    if (d.cwiseAbs().maxCoeff() <= 1e-15 * vscale || (it > 0 && last <= 1e-13 * vscale)) return {};
  }
  return {2, fmt::format("the dependent speeds do not converge near the operating point (velocity residual {:.3g})",
                         last)};
}

Status Reduction::StateOf(const VectorXd& xi_I, const VectorXd& du_I, VectorXd* y) {
  const rt::Program& p = *p_;
  const int nu = p.nu;
  VectorXd xi = VectorXd::Zero(nu), qf(p.nq);
  for (size_t k = 0; k < iq_.size(); ++k) xi[iq_[k]] = xi_I[static_cast<int>(k)];
  if (dq_.empty()) {
    Retract(xi, &qf);
  } else {
    // Chord iterations on phi(q(xi)) = 0 for the dependent coordinates.
    bool done = false;
    for (int it = 0; it < 60 && !done; ++it) {
      for (size_t k = 0; k < dq_.size(); ++k) xi[dq_[k]] = xi_dep_[static_cast<int>(k)];
      Retract(xi, &qf);
      VectorXd phi;
      if (Status s = Phi(qf, &phi); !s.ok()) return s;
      const VectorXd d = qr_phi_dep_.solve(phi);
      xi_dep_ -= d;
      done = d.cwiseAbs().maxCoeff() <= 1e-15 * (1.0 + xi_dep_.cwiseAbs().maxCoeff());
    }
    for (size_t k = 0; k < dq_.size(); ++k) xi[dq_[k]] = xi_dep_[static_cast<int>(k)];
    Retract(xi, &qf);
    VectorXd phi;
    if (Status s = Phi(qf, &phi); !s.ok()) return s;
    if (!done && phi.cwiseAbs().maxCoeff() > 1e-12 * length_)
      return {2, fmt::format("the loop cannot be closed near the operating point (residual {:.3g})",
                             phi.cwiseAbs().maxCoeff())};
  }
  VectorXd uf = u0_;
  for (size_t k = 0; k < iu_.size(); ++k) uf[iu_[k]] += du_I[static_cast<int>(k)];
  if (Status s = SolveSpeeds(qf, &uf); !s.ok()) return s;
  y->resize(p.nq + nu);
  *y << qf, uf;
  return {};
}

}  // namespace kanesim::lin
