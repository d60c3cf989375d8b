// Stiff springs: models/stiff_spring.mech, two 1 kg bodies tied by a 1e8 N/m spring (and a
// 1e4 N.s/m damper) beside a 1 N/m one: eigenvalues ~ -5e3 +- 1.3e4 i and ~ +-0.7 i, a
// stiffness ratio of ~2e4. What must hold: IDA (BDF) completes 10 s at rtol 1e-6 in few
// steps (measured 130; bound kMaxIdaSteps) and matches the exact solution (the exponential
// of the linear 4x4 system, by eigendecomposition) within 1e-4. An explicit method needs
// h < ~2.8 / 1.4e4 on this scene: ~1e5 steps (bench/stress_long.sh measures ARKODE).
// If it failed: IDA's Jacobian or step control mishandles a stiff scene.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <regex>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

constexpr long kMaxIdaSteps = 2000;
constexpr double kQTol = 1e-4;

// y = [q_a, q_b, u_a, u_b] with q_b relative: M = [[2, 1], [1, 1]], K = diag(1, 1e8),
// D = diag(0, 1e4); y' = A y, A = [[0, I], [-M^-1 K, -M^-1 D]]; y(T) = V exp(Lambda T) V^-1 y0.
Eigen::Vector4d Exact(double T) {
  Eigen::Matrix2d M{{2, 1}, {1, 1}}, K{{1, 0}, {0, 1e8}}, D{{0, 0}, {0, 1e4}};
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  A.block<2, 2>(0, 2).setIdentity();
  A.block<2, 2>(2, 0) = -M.inverse() * K;
  A.block<2, 2>(2, 2) = -M.inverse() * D;
  Eigen::EigenSolver<Eigen::Matrix4d> es(A);
  Eigen::Matrix4cd V = es.eigenvectors();
  Eigen::Vector4cd expL = (es.eigenvalues() * T).array().exp();
  Eigen::Vector4cd y0(1, 0, 0, 0);
  Eigen::Vector4cd y = V * expL.asDiagonal() * V.inverse() * y0;
  return y.real();
}

TEST(StressStiff, IdaCopesWithA1e8Spring) {
  RunResult r = RunKanesim("tests/stress/models/stiff_spring.mech",
                           {"--integrator", "ida", "--rtol", "1e-6", "--stop-time", "10", "--interval", "1", "--stats"});
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.stderr_text, m, std::regex(R"(steps\s+(\d+))"))) << r.stderr_text;
  const long steps = std::stol(m[1]);
  EXPECT_LE(steps, kMaxIdaSteps) << "IDA took " << steps << " steps on a stiff scene it should step over";
  const std::vector<double>& last = r.RowAt(10.0);
  const Eigen::Vector4d want = Exact(10.0);
  const double ea = std::fabs(last[static_cast<size_t>(r.Index("pa.q"))] - want[0]);
  const double eb = std::fabs(last[static_cast<size_t>(r.Index("pb.q"))] - want[1]);
  EXPECT_LE(ea, kQTol);
  EXPECT_LE(eb, kQTol);
  std::printf("stiff spring 1e8, IDA rtol 1e-6, 10 s: %ld steps, |dq_a| = %.2g, |dq_b| = %.2g\n", steps, ea, eb);
}

}  // namespace
}  // namespace kanesim::stress
