#include "sim/diagonal_speeds.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "runtime/program/program.h"

namespace kanesim::sim {
namespace {

// A pivot d_i at or below this fraction of M's largest diagonal entry: not positive definite
// in double precision (the speeds are dependent there).
constexpr double kPivotFloor = 1e-14;
// Mdot's difference step: h = kRateStep / max(|qdot|_inf, 1 /s), the error of the Richardson
// step O((h w)^4) + eps / (h w) relative, near its smallest at eps^(1/5) ~ 7e-4.
constexpr double kRateStep = 1.4e-3;

int JointOfFreeSpeed(const rt::Program& p, int free_speed) {
  return p.joint_of_speed[static_cast<size_t>(p.u_free[static_cast<size_t>(free_speed)])];
}

// Whether joint a lies on joint b's path to the root (a ancestor of or equal to b).
bool OnPath(const rt::Program& p, int a, int b) {
  for (int j = b; j >= 0; j = p.joints[static_cast<size_t>(j)].parent)
    if (j == a) return true;
  return false;
}

// Constraint rows: the independent speeds of the partition at the start, in the order; every
// w_i may hold every later one (beta couples them all).
std::string DescribeConstrained(const rt::Program& p, const std::vector<int>& order, const std::vector<std::string>& names) {
  ConstrainedBasis basis(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)));
  rt::InitialState(p, y.data());
  std::string error;
  if (basis.Init(rt::StartTime(p), y.data(), &error) != 0) return "diagonal speeds: not available (" + error + ")\n";
  const std::vector<int>& ind = basis.Independent();
  std::vector<int> sorted;
  for (int s : order)
    if (std::find(ind.begin(), ind.end(), s) != ind.end()) sorted.push_back(s);
  std::string out =
      "diagonal speeds (Lesser 1992 eqs. 81-92) on the constrained basis: u = beta u_I, beta^T M beta = L D L^T, "
      "w = L^T u_I over the independent speeds ";
  for (size_t a = 0; a < sorted.size(); ++a) out += (a ? ", " : "") + names[static_cast<size_t>(sorted[a])];
  out += " (the partition at the start)\n";
  for (size_t i = 0; i < sorted.size(); ++i) {
    out += "  w[" + std::to_string(i + 1) + "] = " + names[static_cast<size_t>(sorted[i])];
    for (size_t j = i + 1; j < sorted.size(); ++j)
      out += " + L[" + std::to_string(j + 1) + "," + std::to_string(i + 1) + "] " + names[static_cast<size_t>(sorted[j])];
    out += "\n";
  }
  return out;
}

}  // namespace

std::vector<std::string> FreeSpeedNames(const rt::Program& p) {
  std::vector<std::string> names;
  for (int i = 0; i < p.nu; ++i) {
    const int r = p.u_free[static_cast<size_t>(i)];
    const rt::TreeJoint& j = p.joints[static_cast<size_t>(JointOfFreeSpeed(p, i))];
    names.push_back(j.name + (j.nu == 1 ? ".u" : ".u[" + std::to_string(r - j.u0 + 1) + "]"));
  }
  return names;
}

std::vector<int> SpeedOrder(const rt::Program& p, const std::vector<std::string>& joints, std::string* error) {
  std::map<std::string, std::vector<int>> speeds_of;
  for (int i = 0; i < p.nu; ++i) speeds_of[p.joints[static_cast<size_t>(JointOfFreeSpeed(p, i))].name].push_back(i);
  std::vector<int> order;
  std::vector<char> taken(static_cast<size_t>(p.nu), 0);
  for (const std::string& name : joints) {
    auto it = speeds_of.find(name);
    if (it == speeds_of.end()) {
      bool exists = std::any_of(p.joints.begin(), p.joints.end(), [&](const rt::TreeJoint& j) { return j.name == name; });
      *error = "--speed-order: " + (exists ? "joint '" + name + "' has no free speeds" : "no joint named '" + name + "'");
      return {};
    }
    if (taken[static_cast<size_t>(it->second.front())]) {
      *error = "--speed-order: joint '" + name + "' is named twice";
      return {};
    }
    for (int s : it->second) {
      order.push_back(s);
      taken[static_cast<size_t>(s)] = 1;
    }
  }
  for (int i = 0; i < p.nu; ++i)
    if (!taken[static_cast<size_t>(i)]) order.push_back(i);
  return order;
}

std::string DiagonalSpeedsRefusal(const rt::Program& p) {
  if (!p.rows.empty() && p.solver == rt::SolverPath::Sparse)
    return "--speeds diagonal: closed loops on the multiplier form (--solver sparse) have no independent speeds; "
           "use --solver dense";
  if (!p.rows.empty() && !p.q_prescribed.empty())
    return "--speeds diagonal: closed loops or rolling contacts with prescribed motion are not supported (the "
           "kinetic energy is not a quadratic form in the independent speeds)";
  if (!rt::EndStops(p).empty() || !rt::PlaneContacts(p).empty())
    return "--speeds diagonal: end stops and plane contacts are not supported (their impacts act on the joint speeds)";
  for (const rt::FrictionJoint& f : rt::FrictionJoints(p))
    if (f.exact) return "--speeds diagonal: exact stick-slip friction is not supported (it holds a joint speed)";
  if (p.nu == 0) return "--speeds diagonal: the model has no free speeds";
  return "";
}

int DiagonalSpeedCount(const rt::Program& p) { return p.rows.empty() ? p.nu : p.nu - p.loop_rank; }

std::string DescribeConstruction(const rt::Program& p, const std::vector<int>& order) {
  const std::vector<std::string> names = FreeSpeedNames(p);
  if (!p.rows.empty()) return DescribeConstrained(p, order, names);
  const int n = static_cast<int>(order.size());
  std::string out = "diagonal speeds (Lesser 1992 eqs. 81-92): w = L^T u, M = L D L^T in the order ";
  for (int a = 0; a < n; ++a) out += (a ? ", " : "") + names[static_cast<size_t>(order[static_cast<size_t>(a)])];
  out += "\n";
  constexpr int kMaxPrinted = 200;  // the symbolic elimination is O(n^3)
  if (n > kMaxPrinted) return out + "  (" + std::to_string(n) + " speeds: the construction is not printed)\n";
  // Structural pattern of M, then the fill-in of the elimination in this order.
  std::vector<char> B(static_cast<size_t>(n * n), 0);
  auto at = [&](int i, int j) -> char& { return B[static_cast<size_t>(i * n + j)]; };
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const int ja = JointOfFreeSpeed(p, order[static_cast<size_t>(a)]), jb = JointOfFreeSpeed(p, order[static_cast<size_t>(b)]);
      at(a, b) = OnPath(p, ja, jb) || OnPath(p, jb, ja);
    }
  for (int k = 0; k < n; ++k)
    for (int i = k + 1; i < n; ++i)
      if (at(i, k))
        for (int j = k + 1; j < n; ++j)
          if (at(j, k)) at(i, j) = 1;
  for (int i = 0; i < n; ++i) {
    out += "  w[" + std::to_string(i + 1) + "] = " + names[static_cast<size_t>(order[static_cast<size_t>(i)])];
    for (int j = i + 1; j < n; ++j)
      if (at(j, i)) out += " + L[" + std::to_string(j + 1) + "," + std::to_string(i + 1) + "] " + names[static_cast<size_t>(order[static_cast<size_t>(j)])];
    out += "\n";
  }
  return out;
}

ConstrainedBasis::ConstrainedBasis(const rt::Program& program)
    : program_(program), ws_(rt::MakeWorkspace(program)), out_ws_(rt::MakeWorkspace(program)),
      yy_(static_cast<size_t>(rt::StateSize(program))), zz_(yy_.size()) {
  std::string error;
  energy_ = rt::PlanSignals(program, {"kinetic_energy"}, &error);
}

int ConstrainedBasis::Init(double t, const double* y, std::string* error) {
  std::vector<double> f(yy_.size());
  std::vector<int> states;
  double diag = 0.0;
  if (!energy_) {
    *error = "the kinetic energy cannot be evaluated";
    return -1;
  }
  if (rt::Derivative(program_, *ws_, t, y, f.data()) != 0) {
    *error = rt::ErrorMessage(*ws_);
    return -1;
  }
  if (!rt::ProjectedStates(program_, *ws_, &states, &diag)) {
    *error = "the constraints have no partition into dependent and independent speeds here";
    return -1;
  }
  rt::HoldPartition(*ws_, true);
  std::vector<char> dependent(static_cast<size_t>(program_.nu), 0);
  for (int s : states)
    if (s >= program_.nq) dependent[static_cast<size_t>(s - program_.nq)] = 1;
  independent_.clear();
  for (int i = 0; i < program_.nu; ++i)
    if (!dependent[static_cast<size_t>(i)]) independent_.push_back(i);
  if (independent_.empty()) {
    *error = "the constraints leave no free speed";
    return -1;
  }
  x_.assign(independent_.size(), 0.0);
  return 0;
}

int ConstrainedBasis::Complete(double t, const double* y, const double* u_independent, double* out) {
  const int nq = program_.nq;
  std::copy(y, y + nq, yy_.begin());
  std::fill(yy_.begin() + nq, yy_.end(), 0.0);
  for (size_t i = 0; i < independent_.size(); ++i) yy_[static_cast<size_t>(nq + independent_[i])] = u_independent[i];
  if (rt::ProjectByPartition(program_, *ws_, t, yy_.data(), out) != 0) {
    error_ = rt::ErrorMessage(*ws_);
    if (error_.empty()) error_ = "the state cannot be projected onto the constraints";
    return 1;
  }
  // The held partition is re-chosen only at a singular configuration; then u_I are no longer
  // the independent speeds and w would change its meaning: stop there.
  for (size_t i = 0; i < independent_.size(); ++i)
    if (out[nq + independent_[i]] != u_independent[i]) {
      error_ = "the independent speeds changed at a singular configuration of the constraints (diagonal speeds "
               "keep those of the start)";
      return -1;
    }
  return 0;
}

double ConstrainedBasis::Energy(double t, const double* y, const double* u_independent, int* status) {
  double T = 0.0;
  if ((*status = Complete(t, y, u_independent, zz_.data())) != 0) return 0.0;
  if ((*status = rt::EvalSignals(program_, *energy_, *out_ws_, t, zz_.data(), &T)) != 0) error_ = rt::ErrorMessage(*out_ws_);
  return T;
}

int ConstrainedBasis::ReducedMass(double t, const double* y, double* M) {
  const size_t m = independent_.size();
  std::vector<double> Ti(m);
  int status = 0;
  for (size_t i = 0; i < m; ++i) {
    x_[i] = 1.0;
    Ti[i] = Energy(t, y, x_.data(), &status);
    x_[i] = 0.0;
    if (status != 0) return status;
    M[i * m + i] = 2.0 * Ti[i];
  }
  for (size_t i = 0; i < m; ++i)
    for (size_t j = i + 1; j < m; ++j) {
      x_[i] = x_[j] = 1.0;
      const double Tij = Energy(t, y, x_.data(), &status);
      x_[i] = x_[j] = 0.0;
      if (status != 0) return status;
      M[j * m + i] = M[i * m + j] = Tij - Ti[i] - Ti[j];
    }
  return 0;
}

DiagonalFactor::DiagonalFactor(std::vector<int> order)
    : n_(static_cast<int>(order.size())), order_(std::move(order)), L_(Eigen::MatrixXd::Identity(n_, n_)),
      d_(Eigen::VectorXd::Zero(n_)), tmp_(n_) {}

int DiagonalFactor::Factor(const double* M) {
  const auto n = static_cast<size_t>(n_);
  auto A = [&](int a, int b) {
    return M[static_cast<size_t>(order_[static_cast<size_t>(b)]) * n + static_cast<size_t>(order_[static_cast<size_t>(a)])];
  };
  double scale = 0.0;
  for (int a = 0; a < n_; ++a) scale = std::max(scale, std::abs(A(a, a)));
  for (int j = 0; j < n_; ++j) {
    double s = A(j, j);
    for (int k = 0; k < j; ++k) s -= L_(j, k) * L_(j, k) * d_(k);
    if (!(s > kPivotFloor * scale)) return 1;
    d_(j) = s;
    for (int i = j + 1; i < n_; ++i) {
      double x = A(i, j);
      for (int k = 0; k < j; ++k) x -= L_(i, k) * L_(j, k) * d_(k);
      L_(i, j) = x / s;
    }
  }
  return 0;
}

void DiagonalFactor::SpeedsToW(const double* u, double* w) const {
  for (int a = 0; a < n_; ++a) {
    double s = u[order_[static_cast<size_t>(a)]];
    for (int b = a + 1; b < n_; ++b) s += L_(b, a) * u[order_[static_cast<size_t>(b)]];
    w[a] = s;
  }
}

void DiagonalFactor::WToSpeeds(const double* w, double* u) const {
  for (int a = n_ - 1; a >= 0; --a) {
    double s = w[a];
    for (int b = a + 1; b < n_; ++b) s -= L_(b, a) * tmp_(b);
    tmp_(a) = s;
  }
  for (int a = 0; a < n_; ++a) u[order_[static_cast<size_t>(a)]] = tmp_(a);
}

DiagonalOde::DiagonalOde(const rt::Program& program, OdeSystem& inner, std::vector<int> order)
    : program_(program), inner_(inner), ws_(rt::MakeWorkspace(program)),
      basis_(program.rows.empty() ? nullptr : std::make_unique<ConstrainedBasis>(program)), order_all_(order),
      nq_(rt::NumQ(program)), n_(rt::NumU(program)), factor_(std::move(order)), M_(n_, n_), Mp_(n_, n_),
      Mdot_(n_, n_), X_(n_, n_), y_(static_cast<size_t>(rt::StateSize(program))), ydot_(y_.size()), yh_(y_.size()),
      ui_(static_cast<size_t>(n_)), uidot_(static_cast<size_t>(n_)) {}

int DiagonalOde::Init(double t, const double* y) {
  if (!basis_) return 0;
  if (basis_->Init(t, y, &own_error_) != 0) return -1;
  // The order restricted to the independent speeds, as positions among them.
  const std::vector<int>& ind = basis_->Independent();
  std::vector<int> order;
  for (int s : order_all_) {
    auto it = std::find(ind.begin(), ind.end(), s);
    if (it != ind.end()) order.push_back(static_cast<int>(it - ind.begin()));
  }
  n_ = static_cast<int>(ind.size());
  if (n_ != DiagonalSpeedCount(program_)) {
    own_error_ = "the partition at the start has " + std::to_string(n_) + " independent speeds, not " +
                 std::to_string(DiagonalSpeedCount(program_));
    return -1;
  }
  factor_ = DiagonalFactor(std::move(order));
  for (Eigen::MatrixXd* A : {&M_, &Mp_, &Mdot_, &X_}) A->resize(n_, n_);
  ui_.resize(static_cast<size_t>(n_));
  uidot_.resize(static_cast<size_t>(n_));
  return 0;
}

int DiagonalOde::MassAt(double t, const double* y, Eigen::MatrixXd* M) {
  own_error_.clear();
  if (basis_) {
    if (int s = basis_->ReducedMass(t, y, M->data()); s != 0) {
      own_error_ = basis_->Error();
      return s;
    }
    return 0;
  }
  if (int s = rt::MassMatrix(program_, *ws_, t, y, M->data()); s != 0) {
    own_error_ = rt::ErrorMessage(*ws_);
    return s;
  }
  return 0;
}

// y = [q; u] of z = [q; w] after FactorAt: u = L^-T w, completed by beta with constraint rows.
int DiagonalOde::Speeds(double t, const double* z, double* y) {
  if (!basis_) {
    std::copy(z, z + nq_, y);
    factor_.WToSpeeds(z + nq_, y + nq_);
    return 0;
  }
  factor_.WToSpeeds(z + nq_, ui_.data());
  if (int s = basis_->Complete(t, z, ui_.data(), y); s != 0) {
    own_error_ = basis_->Error();
    return s;
  }
  return 0;
}

int DiagonalOde::EventFunctions(double t, const double* z, double* g) {
  if (int s = ToSpeeds(t, z, y_.data()); s != 0) return s;
  return inner_.EventFunctions(t, y_.data(), g);
}

int DiagonalOde::Event(double t, double* z, int i) {
  if (int s = ToSpeeds(t, z, y_.data()); s != 0) return s;
  const int s = inner_.Event(t, y_.data(), i);
  if (s < 0) return s;
  std::vector<double> y(y_);
  return ToW(t, y.data(), z) != 0 ? -1 : s;
}

int DiagonalOde::StepAccepted(double t, const double* z) {
  if (int s = ToSpeeds(t, z, y_.data()); s != 0) return s;
  return inner_.StepAccepted(t, y_.data());
}

int DiagonalOde::FactorAt(double t, const double* y) {
  if (int s = MassAt(t, y, &M_); s != 0) return s;
  if (factor_.Factor(M_.data()) != 0) {
    own_error_ = "singular mass matrix (a pivot of the diagonal speeds' L D L^T vanished)";
    return 1;
  }
  return 0;
}

// Mdot along (t, q(t)): central differences at h and h/2, one Richardson step.
int DiagonalOde::MassRate(double t, const double* y, const double* ydot) {
  double rate = 1.0;
  for (int i = 0; i < nq_; ++i) rate = std::max(rate, std::abs(ydot[i]));
  const double h = kRateStep / rate;
  for (int level = 0; level < 2; ++level) {
    const double hl = level == 0 ? h : 0.5 * h;
    for (int sign = -1; sign <= 1; sign += 2) {
      std::copy(y, y + yh_.size(), yh_.begin());
      for (int i = 0; i < nq_; ++i) yh_[static_cast<size_t>(i)] += sign * hl * ydot[i];
      if (int s = MassAt(t + sign * hl, yh_.data(), &Mp_); s != 0) return s;
      const double c = (level == 0 ? -1.0 / 3.0 : 4.0 / 3.0) * sign / (2.0 * hl);
      if (level == 0 && sign < 0) Mdot_ = c * Mp_;
      else Mdot_ += c * Mp_;
    }
  }
  return 0;
}

int DiagonalOde::Rhs(double t, const double* z, double* zdot) {
  if (int s = FactorAt(t, z); s != 0) return s;
  if (int s = Speeds(t, z, y_.data()); s != 0) return s;
  if (int s = inner_.Rhs(t, y_.data(), ydot_.data()); s != 0) return s;
  if (int s = MassRate(t, y_.data(), ydot_.data()); s != 0) return s;
  // X = L^-1 Mdot L^-T in the order (eq. 2), through X1 = L^-1 Mdot: X = L^-1 X1^T.
  const std::vector<int>& order = factor_.order();
  for (int b = 0; b < n_; ++b)
    for (int a = 0; a < n_; ++a) X_(a, b) = Mdot_(order[static_cast<size_t>(a)], order[static_cast<size_t>(b)]);
  const auto L = factor_.L().triangularView<Eigen::UnitLower>();
  L.solveInPlace(X_);
  X_.transposeInPlace();
  L.solveInPlace(X_);
  // wdot = L^T udot + D^-1 strictupper(X) w (udot: the independent speeds' with constraint rows).
  const double* udot = ydot_.data() + nq_;
  if (basis_) {
    const std::vector<int>& ind = basis_->Independent();
    for (int i = 0; i < n_; ++i) uidot_[static_cast<size_t>(i)] = udot[ind[static_cast<size_t>(i)]];
    udot = uidot_.data();
  }
  factor_.SpeedsToW(udot, zdot + nq_);
  const double* w = z + nq_;
  const Eigen::VectorXd& d = factor_.d();
  for (int i = 0; i < n_; ++i) {
    double s = 0.0;
    for (int j = i + 1; j < n_; ++j) s += X_(i, j) * w[j];
    zdot[nq_ + i] += s / d(i);
  }
  std::copy(ydot_.begin(), ydot_.begin() + nq_, zdot);
  return 0;
}

int DiagonalOde::ToSpeeds(double t, const double* z, double* y) {
  if (int s = FactorAt(t, z); s != 0) return s;
  return Speeds(t, z, y);
}

int DiagonalOde::ToW(double t, const double* y, double* z) {
  if (int s = FactorAt(t, y); s != 0) return s;
  std::copy(y, y + nq_, z);
  const double* u = y + nq_;
  if (basis_) {
    const std::vector<int>& ind = basis_->Independent();
    for (int i = 0; i < n_; ++i) ui_[static_cast<size_t>(i)] = u[ind[static_cast<size_t>(i)]];
    u = ui_.data();
  }
  factor_.SpeedsToW(u, z + nq_);
  return 0;
}

void DiagonalOde::Columns(const double* z, double* out) const {
  const double* w = z + nq_;
  const Eigen::VectorXd& d = factor_.d();
  for (int i = 0; i < n_; ++i) {
    out[i] = w[i];
    out[n_ + i] = d(i);
    out[2 * n_ + i] = 0.5 * d(i) * w[i] * w[i];
  }
}

}  // namespace kanesim::sim
