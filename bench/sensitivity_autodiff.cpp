// Forward-mode differentiation against central differences for the two terms of the
// variational equations (issue 44, docs/integrators.md "Sensitivities"): ∂f/∂p and
// (∂f/∂y) s, on the chain of examples/chain.mech (N thin rods on alternating z/y revolute
// joints). kanesim's kernel is double only; to measure what templating it would buy, a
// compact articulated-body kernel of the same chain, templated on the scalar, is evaluated
//   (a) with Eigen's AutoDiffScalar (one direction: exact to round-off), and
//   (b) by central differences with kanesim's steps (sim/sensitivity.cpp):
//       ∂f/∂p: δ = cbrt(ε) max(|p|, 1e-3);  (∂f/∂y) s: h = cbrt(ε) (1 + |y|∞) / |s|∞.
// The compact kernel's f is first checked against rt::Derivative at the same state, and
// its ∂f/∂L against differences of kanesim's own programs compiled at L ± δ.
//
//   build/bench/sensitivity_autodiff [reps]
#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <random>
#include <unsupported/Eigen/AutoDiff>
#include <vector>

#include "compiler/compiler.h"
#include "runtime/runtime.h"
#include "tests/support/builders.h"

namespace {

template <class S>
using V3 = Eigen::Matrix<S, 3, 1>;
template <class S>
using M3 = Eigen::Matrix<S, 3, 3>;
template <class S>
using V6 = Eigen::Matrix<S, 6, 1>;  // spatial vector, angular above linear
template <class S>
using M6 = Eigen::Matrix<S, 6, 6>;

template <class S>
M3<S> Skew(const V3<S>& a) {
  M3<S> m;
  m << S(0), -a.z(), a.y(), a.z(), S(0), -a.x(), -a.y(), a.x(), S(0);
  return m;
}

// Motion cross product v ×m w and force cross product v ×f f (Featherstone 2008, eq. 2.31-2.32).
template <class S>
V6<S> CrossM(const V6<S>& v, const V6<S>& w) {
  V6<S> r;
  r << v.template head<3>().cross(w.template head<3>()),
      v.template head<3>().cross(w.template tail<3>()) + v.template tail<3>().cross(w.template head<3>());
  return r;
}
template <class S>
V6<S> CrossF(const V6<S>& v, const V6<S>& f) {
  V6<S> r;
  r << v.template head<3>().cross(f.template head<3>()) + v.template tail<3>().cross(f.template tail<3>()),
      v.template head<3>().cross(f.template tail<3>());
  return r;
}

// The chain's q̈ by the articulated-body algorithm (Featherstone 2008, table 7.1), every
// quantity in its body's frame at the joint. Body i: a rod of mass m and length L along
// its x, mass centre at L/2, central inertia diag(0, mL²/12, mL²/12); joint i at the tip of
// rod i-1 (world origin for i = 1) about z (i odd) or y (i even), fixed in the parent.
template <class S>
void ChainAccel(int N, const S& m, const S& L, const S* q, const S* u, S* qdd) {
  const S I_t = m * L * L / S(12);
  V3<S> c(L / S(2), S(0), S(0));
  M6<S> I_body;  // spatial inertia about the joint (Featherstone eq. 2.63)
  I_body.setZero();
  const M3<S> cx = Skew(c);
  M3<S> I_c = M3<S>::Zero();
  I_c(1, 1) = I_t;
  I_c(2, 2) = I_t;
  I_body.template topLeftCorner<3, 3>() = I_c - m * cx * cx;
  I_body.template topRightCorner<3, 3>() = m * cx;
  I_body.template bottomLeftCorner<3, 3>() = -m * cx;
  I_body.template bottomRightCorner<3, 3>() = m * M3<S>::Identity();

  std::vector<M6<S>> X(N), IA(N);
  std::vector<V6<S>> v(N), cb(N), pA(N), U(N), a(N), Svec(N);
  std::vector<S> D(N), uu(N);
  V6<S> a0;
  a0 << S(0), S(0), S(0), S(0), S(9.81), S(0);  // base acceleration -g
  for (int i = 0; i < N; ++i) {
    V3<S> axis = (i % 2 == 0) ? V3<S>(S(0), S(0), S(1)) : V3<S>(S(0), S(1), S(0));
    const M3<S> E = Eigen::AngleAxis<S>(q[i], axis).toRotationMatrix().transpose();  // parent → body
    const V3<S> r = i == 0 ? V3<S>::Zero() : V3<S>(L, S(0), S(0));
    X[i].setZero();  // motion transform parent → body (eq. 2.24)
    X[i].template topLeftCorner<3, 3>() = E;
    X[i].template bottomRightCorner<3, 3>() = E;
    X[i].template bottomLeftCorner<3, 3>() = -E * Skew(r);
    Svec[i] << axis, V3<S>::Zero();
    const V6<S> vJ = Svec[i] * u[i];
    v[i] = (i == 0 ? V6<S>(V6<S>::Zero()) : V6<S>(X[i] * v[i - 1])) + vJ;
    cb[i] = CrossM(v[i], vJ);
    IA[i] = I_body;
    pA[i] = CrossF(v[i], V6<S>(I_body * v[i]));
  }
  for (int i = N - 1; i >= 0; --i) {
    U[i] = IA[i] * Svec[i];
    D[i] = Svec[i].dot(U[i]);
    uu[i] = -Svec[i].dot(pA[i]);
    if (i > 0) {
      const M6<S> Ia = IA[i] - U[i] * U[i].transpose() / D[i];
      const V6<S> pa = pA[i] + Ia * cb[i] + U[i] * (uu[i] / D[i]);
      IA[i - 1] += X[i].transpose() * Ia * X[i];
      pA[i - 1] += X[i].transpose() * pa;
    }
  }
  for (int i = 0; i < N; ++i) {
    a[i] = X[i] * (i == 0 ? a0 : a[i - 1]) + cb[i];
    qdd[i] = (uu[i] - U[i].dot(a[i])) / D[i];
    a[i] += Svec[i] * qdd[i];
  }
}

// f(y) = [u, q̈] for y = [q, u].
template <class S>
void ChainRhs(int N, const S& m, const S& L, const S* y, S* ydot) {
  for (int i = 0; i < N; ++i) ydot[i] = y[N + i];
  ChainAccel<S>(N, m, L, y, y + N, ydot + N);
}

using AD = Eigen::AutoDiffScalar<Eigen::Matrix<double, 1, 1>>;  // one direction

// ∂f/∂L by forward mode: L seeded with derivative 1.
void DfDpAD(int N, double L, const std::vector<double>& y, std::vector<double>& out, std::vector<AD>& ya,
            std::vector<AD>& fa) {
  for (size_t i = 0; i < y.size(); ++i) ya[i] = AD(y[i], Eigen::Matrix<double, 1, 1>::Zero());
  const AD La(L, Eigen::Matrix<double, 1, 1>::Ones());
  ChainRhs<AD>(N, AD(1.0, Eigen::Matrix<double, 1, 1>::Zero()), La, ya.data(), fa.data());
  for (size_t i = 0; i < y.size(); ++i) out[i] = fa[i].derivatives()(0);
}

// (∂f/∂y) s by forward mode: y seeded with derivative s.
void JsAD(int N, double L, const std::vector<double>& y, const std::vector<double>& s, std::vector<double>& out,
          std::vector<AD>& ya, std::vector<AD>& fa) {
  for (size_t i = 0; i < y.size(); ++i) ya[i] = AD(y[i], Eigen::Matrix<double, 1, 1>::Constant(s[i]));
  const AD z(0.0, Eigen::Matrix<double, 1, 1>::Zero());
  ChainRhs<AD>(N, AD(1.0, z.derivatives()), AD(L, z.derivatives()), ya.data(), fa.data());
  for (size_t i = 0; i < y.size(); ++i) out[i] = fa[i].derivatives()(0);
}

// Vector mode: kDirs directions (of y; the cost does not depend on the seeds) in one pass,
// as m sensitivities would need 2m directions per evaluation of the augmented system.
constexpr int kDirs = 8;
using ADV = Eigen::AutoDiffScalar<Eigen::Matrix<double, kDirs, 1>>;
void JsADVector(int N, double L, const std::vector<double>& y, const std::vector<double>& s,
                std::vector<double>& out, std::vector<ADV>& ya, std::vector<ADV>& fa) {
  using D = Eigen::Matrix<double, kDirs, 1>;
  for (size_t i = 0; i < y.size(); ++i) {
    D d;
    for (int k = 0; k < kDirs; ++k) d(k) = s[(i + static_cast<size_t>(k)) % s.size()];
    ya[i] = ADV(y[i], d);
  }
  ChainRhs<ADV>(N, ADV(1.0, D::Zero()), ADV(L, D::Zero()), ya.data(), fa.data());
  for (size_t i = 0; i < y.size(); ++i) out[i] = fa[i].derivatives()(0);
}

const double kCbrtEps = std::cbrt(std::numeric_limits<double>::epsilon());

void DfDpCD(int N, double L, const std::vector<double>& y, std::vector<double>& out, std::vector<double>& fp,
            std::vector<double>& fm) {
  const double d = kCbrtEps * std::max(std::fabs(L), 1e-3);
  ChainRhs<double>(N, 1.0, L + d, y.data(), fp.data());
  ChainRhs<double>(N, 1.0, L - d, y.data(), fm.data());
  for (size_t i = 0; i < y.size(); ++i) out[i] = (fp[i] - fm[i]) / (2 * d);
}

void JsCD(int N, double L, const std::vector<double>& y, const std::vector<double>& s, std::vector<double>& out,
          std::vector<double>& yp, std::vector<double>& fp, std::vector<double>& fm) {
  double ny = 0, ns = 0;
  for (size_t i = 0; i < y.size(); ++i) {
    ny = std::max(ny, std::fabs(y[i]));
    ns = std::max(ns, std::fabs(s[i]));
  }
  const double h = kCbrtEps * (1 + ny) / ns;
  for (size_t i = 0; i < y.size(); ++i) yp[i] = y[i] + h * s[i];
  ChainRhs<double>(N, 1.0, 0.5, yp.data(), fp.data());
  for (size_t i = 0; i < y.size(); ++i) yp[i] = y[i] - h * s[i];
  ChainRhs<double>(N, 1.0, 0.5, yp.data(), fm.data());
  (void)L;
  for (size_t i = 0; i < y.size(); ++i) out[i] = (fp[i] - fm[i]) / (2 * h);
}

// Seconds per call of each of `fs`, timed in turn within every repetition (a loaded
// machine slows all of them alike), then the median over `reps` repetitions of each.
std::vector<double> MedianMicros(int reps, const std::vector<std::function<void()>>& fs) {
  std::vector<int> inner(fs.size(), 1);
  for (size_t j = 0; j < fs.size(); ++j) {
    for (;;) {  // a batch long enough for the clock (~5 ms)
      auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < inner[j]; ++k) fs[j]();
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > 5e-3) break;
      inner[j] *= 2;
    }
  }
  std::vector<std::vector<double>> t(fs.size());
  for (int r = 0; r < reps; ++r) {
    for (size_t j = 0; j < fs.size(); ++j) {
      auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < inner[j]; ++k) fs[j]();
      t[j].push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1e6 / inner[j]);
    }
  }
  std::vector<double> med;
  for (auto& v : t) {
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    med.push_back(v[v.size() / 2]);
  }
  return med;
}

double MaxAbs(const std::vector<double>& a) {
  double r = 0;
  for (double x : a) r = std::max(r, std::fabs(x));
  return r;
}
double MaxDiff(const std::vector<double>& a, const std::vector<double>& b) {
  double r = 0;
  for (size_t i = 0; i < a.size(); ++i) r = std::max(r, std::fabs(a[i] - b[i]));
  return r;
}

// kanesim's f of test::Chain(N, 1, L) at y (rt::Derivative, the automatic solver path).
bool KanesimRhs(int N, double L, const std::vector<double>& y, std::vector<double>& f) {
  auto r = kanesim::rt::Compile(kanesim::test::Chain(N, 1.0, L), kanesim::rt::CompileOptions{});
  if (!r.program || kanesim::rt::StateSize(*r.program) != 2 * N) return false;
  auto ws = kanesim::rt::MakeWorkspace(*r.program);
  return kanesim::rt::Derivative(*r.program, *ws, 0.0, y.data(), f.data()) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::atoi(argv[1]) : 9;
  std::printf("cost in evaluations of f (double); AD8/dir: 8 directions in one pass, per direction\n");
  std::printf("%4s %9s %9s %8s %8s %8s %8s %8s %8s %10s %10s\n", "N", "f_check", "dfdL_chk", "f_us", "dfdp_AD",
              "dfdp_CD", "Js_AD", "Js_CD", "AD8/dir", "dfdp_diff", "Js_diff");
  for (int N : {2, 10, 50}) {
    const double L = 0.5;
    const size_t n = static_cast<size_t>(2 * N);
    std::mt19937 rng(44);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    std::vector<double> y(n), s(n), f(n), fk(n), fkp(n), fkm(n);
    for (auto& x : y) x = uni(rng);
    for (auto& x : s) x = uni(rng);
    // Same equations: f against kanesim's, and ∂f/∂L against kanesim's programs at L ± δ.
    ChainRhs<double>(N, 1.0, L, y.data(), f.data());
    const double d = kCbrtEps * L;
    if (!KanesimRhs(N, L, y, fk) || !KanesimRhs(N, L + d, y, fkp) || !KanesimRhs(N, L - d, y, fkm)) {
      std::fprintf(stderr, "kanesim failed to compile or evaluate the chain of %d\n", N);
      return 1;
    }
    std::vector<double> dk(n), dad(n), dcd(n), jad(n), jcd(n), yp(n), fp(n), fm(n);
    std::vector<AD> ya(n), fa(n);
    for (size_t i = 0; i < n; ++i) dk[i] = (fkp[i] - fkm[i]) / (2 * d);
    DfDpAD(N, L, y, dad, ya, fa);
    DfDpCD(N, L, y, dcd, fp, fm);
    JsAD(N, L, y, s, jad, ya, fa);
    JsCD(N, L, y, s, jcd, yp, fp, fm);
    const double f_check = MaxDiff(f, fk) / MaxAbs(fk);
    const double dk_check = MaxDiff(dad, dk) / MaxAbs(dad);
    std::vector<double> jv(n);
    std::vector<ADV> yv(n), fv(n);
    const auto t = MedianMicros(reps, {[&] { ChainRhs<double>(N, 1.0, L, y.data(), f.data()); },
                                       [&] { DfDpAD(N, L, y, dad, ya, fa); }, [&] { DfDpCD(N, L, y, dcd, fp, fm); },
                                       [&] { JsAD(N, L, y, s, jad, ya, fa); },
                                       [&] { JsCD(N, L, y, s, jcd, yp, fp, fm); },
                                       [&] { JsADVector(N, L, y, s, jv, yv, fv); }});
    std::printf("%4d %9.1e %9.1e %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %10.1e %10.1e\n", N, f_check, dk_check, t[0],
                t[1] / t[0], t[2] / t[0], t[3] / t[0], t[4] / t[0], t[5] / t[0] / kDirs,
                MaxDiff(dad, dcd) / MaxAbs(dad), MaxDiff(jad, jcd) / MaxAbs(jad));
  }
  return 0;
}
