// The independent reference of the equal-link parallelogram tests (issue 20): on the
// parallelogram branch the rods turn together and the couplers translate, so the whole
// mechanism is one crank with lumped inertia, T = (1/2) J w^2, V = G sin(theta), and
//   theta'' = -(G / J) cos(theta).
// Used by tests/stress/loop_branch_test.cpp (the CLI, every integrator and form) and
// tests/constraints/change_point_bridge_test.cpp (the bridge over change points), which
// derive J and G for their models.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace kanesim::lumped_crank {

struct Crank {
  double J = 0.0;  // lumped moment of inertia about the crank pivot
  double G = 0.0;  // gravity's moment amplitude: V = G sin(theta)
};

// tests/stress/models/parallelogram_chain.mech with its default parameters (the model's
// header): N + 1 rods of mass 0.5 and N couplers of mass 1, every link 0.6 long.
inline Crank ParallelogramChain(int n) {
  const double a = 0.6, m_rod = 0.5, m_c = 1.0, g = 9.81;
  return {(n + 1) * m_rod * a * a / 3.0 + n * m_c * a * a, g * ((n + 1) * m_rod * a / 2.0 + n * m_c * a)};
}

// Max |theta_i - theta_ref(t_i)| over the rows (t, th, w: time, crank angle and speed),
// theta_ref integrated from the first row's angle and speed by classical Runge-Kutta with
// steps of at most h (its own error far below the tests' bounds).
inline double MaxAngleError(const Crank& c, const std::vector<double>& t, const std::vector<double>& th,
                            const std::vector<double>& w, double h_max) {
  const double k = c.G / c.J;
  auto acc = [k](double q) { return -k * std::cos(q); };
  double x = th[0], v = w[0], now = t[0], err = 0.0;
  for (size_t i = 0; i < t.size(); ++i) {
    while (now < t[i] - 1e-13) {
      const double h = std::min(h_max, t[i] - now);
      const double k1x = v, k1v = acc(x);
      const double k2x = v + h / 2 * k1v, k2v = acc(x + h / 2 * k1x);
      const double k3x = v + h / 2 * k2v, k3v = acc(x + h / 2 * k2x);
      const double k4x = v + h * k3v, k4v = acc(x + h * k3x);
      x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
      v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      now += h;
    }
    err = std::max(err, std::fabs(th[i] - x));
  }
  return err;
}

// The chain's file, below the source root (`N` loops, parameter `theta0` the start angle).
inline const char* const kChainPath = "/tests/stress/models/parallelogram_chain.mech";

// Signals of the chain of n: rj0.q, rj0.u, then rj[1..n].<part> for each of `parts` in turn
// ({"q", "u"}: every q, then every u); per_rod: each rod's parts together (rj[1].q, rj[1].u,
// rj[2].q, ...).
inline std::vector<std::string> ChainSignals(int n, const std::vector<std::string>& parts, bool per_rod = false) {
  std::vector<std::string> s = {"rj0.q", "rj0.u"};
  auto rod = [](int i, const std::string& part) { return "rj[" + std::to_string(i) + "]." + part; };
  if (per_rod) {
    for (int i = 1; i <= n; ++i)
      for (const std::string& part : parts) s.push_back(rod(i, part));
  } else {
    for (const std::string& part : parts)
      for (int i = 1; i <= n; ++i) s.push_back(rod(i, part));
  }
  return s;
}

// Rows of the chain of n with the signals [rj0.q, rj0.u, rj[1..n].q, rj[1..n].u]: the max
// over the rows of the lumped energy's error against the first row's (relative), of how far
// a rod's angle is off rod 0's (mod 2 pi: on the branch they are equal) and of how far the
// rods' speeds are apart.
struct ChainRowErrors {
  double energy = 0.0, off = 0.0, apart = 0.0;
};
inline ChainRowErrors ChainErrors(int n, const std::vector<std::vector<double>>& rows) {
  const Crank c = ParallelogramChain(n);
  auto energy = [&c](const std::vector<double>& row) { return 0.5 * c.J * row[1] * row[1] + c.G * std::sin(row[0]); };
  ChainRowErrors e;
  if (rows.empty()) return e;
  const double e0 = energy(rows.front());
  for (const auto& row : rows) {
    e.energy = std::max(e.energy, std::fabs(energy(row) - e0) / std::fabs(e0));
    for (int i = 0; i < n; ++i) {
      e.off = std::max(e.off, std::fabs(std::remainder(row[2 + static_cast<size_t>(i)] - row[0], 2 * M_PI)));
      e.apart = std::max(e.apart, std::fabs(row[2 + static_cast<size_t>(n + i)] - row[1]));
    }
  }
  return e;
}

}  // namespace kanesim::lumped_crank
