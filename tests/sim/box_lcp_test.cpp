// sim/box_lcp.h against two independent answers: enumeration of every choice of states
// (3^m solves, the one choice whose conditions hold), and the problem's own conditions.
#include "sim/box_lcp.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace kanesim::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Problem {
  std::vector<double> A, q, lo, hi;
};

// A random positive definite A = B B^T + 0.1 I with a spread of scales, and bounds of every
// kind: a box about 0, one side infinite (a stop's reaction), both infinite (a free speed).
Problem Random(std::mt19937& rng, size_t m) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd B(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  for (Eigen::Index i = 0; i < B.rows(); ++i)
    for (Eigen::Index j = 0; j < B.cols(); ++j) B(i, j) = u(rng) * std::pow(10.0, i % 3);
  const Eigen::MatrixXd S = B * B.transpose() + 0.1 * Eigen::MatrixXd::Identity(B.rows(), B.cols());
  Problem p;
  for (size_t i = 0; i < m; ++i) {
    for (size_t j = 0; j < m; ++j) p.A.push_back(S(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
    p.q.push_back(5.0 * u(rng));
    const double b = std::abs(u(rng));
    switch (rng() % 4) {
      case 0: p.lo.push_back(-b), p.hi.push_back(b); break;
      case 1: p.lo.push_back(-b), p.hi.push_back(kInf); break;
      case 2: p.lo.push_back(-kInf), p.hi.push_back(b); break;
      default: p.lo.push_back(-b), p.hi.push_back(2.0 * b); break;
    }
  }
  return p;
}

// Every choice of states, each solved; the x of the choices whose conditions hold.
std::vector<std::vector<double>> Enumerate(const Problem& p) {
  const size_t m = p.q.size();
  size_t cases = 1;
  for (size_t k = 0; k < m; ++k) cases *= 3;
  std::vector<std::vector<double>> found;
  for (size_t c = 0; c < cases; ++c) {
    std::vector<int> s(m);
    size_t code = c;
    bool finite = true;
    for (size_t k = 0; k < m; ++k, code /= 3) {
      s[k] = static_cast<int>(code % 3) - 1;
      finite = finite && (s[k] != -1 || std::isfinite(p.lo[k])) && (s[k] != 1 || std::isfinite(p.hi[k]));
    }
    if (!finite) continue;
    std::vector<double> x(m, 0.0);
    std::vector<Eigen::Index> F;
    for (size_t k = 0; k < m; ++k) {
      if (s[k] == 0) F.push_back(static_cast<Eigen::Index>(k));
      else x[k] = s[k] < 0 ? p.lo[k] : p.hi[k];
    }
    const auto n = static_cast<Eigen::Index>(F.size());
    Eigen::MatrixXd AF(n, n);
    Eigen::VectorXd b(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto ki = static_cast<size_t>(F[static_cast<size_t>(i)]);
      b[i] = -p.q[ki];
      for (size_t j = 0; j < m; ++j)
        if (s[j] != 0) b[i] -= p.A[ki * m + j] * x[j];
      for (Eigen::Index c2 = 0; c2 < n; ++c2) AF(i, c2) = p.A[ki * m + static_cast<size_t>(F[static_cast<size_t>(c2)])];
    }
    const Eigen::VectorXd xf = AF.partialPivLu().solve(b);
    for (Eigen::Index i = 0; i < n; ++i) x[static_cast<size_t>(F[static_cast<size_t>(i)])] = xf[i];
    bool ok = true;
    for (size_t k = 0; k < m && ok; ++k) {
      double w = p.q[k];
      for (size_t j = 0; j < m; ++j) w += p.A[k * m + j] * x[j];
      if (s[k] == 0) ok = x[k] >= p.lo[k] - 1e-12 && x[k] <= p.hi[k] + 1e-12;
      if (s[k] < 0) ok = w >= -1e-12;
      if (s[k] > 0) ok = w <= 1e-12;
    }
    if (ok) found.push_back(x);
  }
  return found;
}

TEST(BoxLcp, EqualsTheOneChoiceEnumerationFinds) {
  std::mt19937 rng(20261201);
  int bound = 0, free_ = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const size_t m = 1 + static_cast<size_t>(trial % 7);
    const Problem p = Random(rng, m);
    const BoxLcpResult r = SolveBoxLcp(p.A, p.q, p.lo, p.hi);
    ASSERT_TRUE(r.solved) << "trial " << trial;
    const auto found = Enumerate(p);
    ASSERT_FALSE(found.empty()) << "trial " << trial;
    for (const auto& x : found)  // (degenerate choices give the same x)
      for (size_t k = 0; k < m; ++k) EXPECT_NEAR(r.x[k], x[k], 1e-9 * (1.0 + std::abs(x[k]))) << "trial " << trial;
    for (BoxState s : r.state) (s == BoxState::kFree ? free_ : bound)++;
  }
  EXPECT_GT(bound, 100);  // both kinds of state were exercised
  EXPECT_GT(free_, 100);
}

TEST(BoxLcp, MeetsItsConditionsAtTheSizeOfAHumanoid) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const Problem p = Random(rng, 32);
    const BoxLcpResult r = SolveBoxLcp(p.A, p.q, p.lo, p.hi);
    ASSERT_TRUE(r.solved) << "trial " << trial;
    double scale = 1.0;
    for (size_t k = 0; k < 32; ++k) scale = std::max({scale, std::abs(p.q[k]), std::abs(r.w[k])});
    for (size_t k = 0; k < 32; ++k) {
      double w = p.q[k];
      for (size_t j = 0; j < 32; ++j) w += p.A[k * 32 + j] * r.x[j];
      EXPECT_NEAR(w, r.w[k], 1e-10 * scale);
      EXPECT_GE(r.x[k], p.lo[k]);
      EXPECT_LE(r.x[k], p.hi[k]);
      if (r.state[k] == BoxState::kFree) {
        EXPECT_NEAR(w, 0.0, 1e-10 * scale);
      } else if (r.state[k] == BoxState::kLower) {
        EXPECT_GE(w, -1e-10 * scale);
      } else {
        EXPECT_LE(w, 1e-10 * scale);
      }
    }
  }
}

// One joint at rest: held while the force it needs, -q / a, is within its bound, else it
// slides the way that force pulls with its friction at the bound against it.
TEST(BoxLcp, OneJointIsCoulombsLaw) {
  const std::vector<double> A{0.5};
  BoxLcpResult held = SolveBoxLcp(A, {0.3}, {-1.0}, {1.0});  // needs -0.6
  ASSERT_TRUE(held.solved);
  EXPECT_EQ(held.state[0], BoxState::kFree);
  EXPECT_DOUBLE_EQ(held.x[0], -0.6);
  BoxLcpResult slides = SolveBoxLcp(A, {0.8}, {-1.0}, {1.0});  // needs -1.6: slides forwards
  ASSERT_TRUE(slides.solved);
  EXPECT_EQ(slides.state[0], BoxState::kLower);
  EXPECT_DOUBLE_EQ(slides.x[0], -1.0);
  EXPECT_DOUBLE_EQ(slides.w[0], 0.3);  // accelerating the way it slides
}

TEST(BoxLcp, RefusesAMatrixThatIsNotPositiveDefinite) {
  EXPECT_FALSE(SolveBoxLcp({1.0, 2.0, 2.0, 1.0}, {-1.0, -1.0}, {-kInf, -kInf}, {kInf, kInf}).solved);
  EXPECT_FALSE(SolveBoxLcp({0.0}, {1.0}, {-1.0}, {1.0}).solved);
}

}  // namespace
}  // namespace kanesim::sim
