// The difference step and the accuracy linearize reports (linearize/linearize.cpp,
// eqs. 5-9), against closed forms at every allowed --step (0, 0.1]:
//
// Inverted pendulum (point mass at L above the hinge, q = pi/2 + 2 pi k):
//   A = [[0, 1], [g / L, 0]],  lambda = +-sqrt(g / L) = +-3.7436 for L = 0.7          (1)
// Hanging pendulum (tests/linearize/models/pendulum.mech, l = 0.7):
//   A = [[0, 1], [-g / l, 0]], lambda = +-i sqrt(g / l)                                (2)
//
// Wrong if a step too small to survive rounding were used as asked (at --step 1e-16 every
// difference rounded to zero: "A to 0.0e+00 relative", eigenvalues 0, "marginal"), or if the
// accuracy reported were ever smaller than the error against the closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <string>

#include "linearize/linearize.h"
#include "runtime/program/program.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81, kL = 0.7;

const char* kInverted = R"(
model Inverted
  parameter Real L = 0.7;
  parameter Real q0 = pi / 2;
  World world(g = {0, -9.81, 0});
  Revolute hinge(axis = {0, 0, 1}, q(start = q0), u(start = 0));
  Body bob(m = 1.3, r_CM = {L, 0, 0}, I = zeros(3, 3));
equation
  connect(world.frame_b, hinge.frame_a);
  connect(hinge.frame_b, bob.frame_a);
end Inverted;
)";

// Every decade of the allowed range, and its ends.
std::vector<double> AllowedSteps() {
  std::vector<double> steps;
  for (int e = -16; e <= -1; ++e) steps.push_back(std::pow(10.0, e));
  steps.push_back(0.1);
  steps.push_back(std::numeric_limits<double>::min());  // 2.2e-308: the smallest step the CLI reads
  return steps;
}

// Linearizes at `step`; checks the claim against `A_exact` and the eigenvalues against
// `lambda` (the one with the larger real part, then imaginary part); returns the model.
lin::LinearModel CheckAt(const rt::Program& p, double step, const Eigen::Matrix2d& A_exact, std::complex<double> lambda) {
  lin::LinearizeOptions o;
  o.step = step;
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(p, lin::StartPoint(p), o, &m);
  EXPECT_TRUE(s.ok()) << step << ": " << s.message;
  if (!s.ok()) return m;
  lin::ComputeModes(&m);
  const double scale = std::max(1.0, m.A.cwiseAbs().maxCoeff());
  const double actual = (m.A - A_exact).cwiseAbs().maxCoeff() / scale;
  // The claim holds: the accuracy reported is no smaller than the error.
  EXPECT_LE(actual, m.error_A) << "step " << step << ": A is off by " << actual << " relative, reported "
                               << m.error_A;
  // And the signal is there: the eigenvalues to 1e-5 relative at every step.
  EXPECT_LE(m.error_A, 1e-5) << step;
  EXPECT_EQ(m.modes.size(), 2u);
  if (m.modes.size() != 2) return m;
  std::complex<double> top = m.modes[0].lambda;
  for (const lin::Mode& md : m.modes)
    if (md.lambda.real() > top.real() || (md.lambda.real() == top.real() && md.lambda.imag() > top.imag()))
      top = md.lambda;
  EXPECT_LE(std::abs(top - lambda), 1e-5 * std::abs(lambda)) << "step " << step << ": " << top;
  return m;
}

TEST(LinearizeStep, InvertedPendulumAtEveryAllowedStep) {
  auto l = LoadModel(kInverted, {}, {}, true);
  ASSERT_TRUE(l && l->prog);
  Eigen::Matrix2d A;
  A << 0, 1, kG / kL, 0;  // (1)
  const double floor_q = std::ldexp(std::numeric_limits<double>::epsilon(), 22) * (M_PI / 2);
  for (double step : AllowedSteps()) {
    const lin::LinearModel m = CheckAt(*l->prog, step, A, std::sqrt(kG / kL));
    // Widened exactly when the coordinate's step is below its floor (eq. 8), and said.
    const bool q_widened = std::any_of(m.widened.begin(), m.widened.end(),
                                       [](const lin::WidenedStep& w) { return w.name == "hinge.q"; });
    EXPECT_EQ(q_widened, step < floor_q) << step;
    for (const lin::WidenedStep& w : m.widened) {
      EXPECT_EQ(w.requested, step) << w.name;
      EXPECT_GT(w.used, step) << w.name;
    }
    for (const lin::Mode& md : m.modes) EXPECT_NE(md.lambda, 0.0) << step;  // never "marginal"
  }
}

// The floor scales with the largest variable: 1000 turns further on (q0 = 6284.76 rad) a
// step of 1e-8 keeps only 1e-4 of its change after rounding; both columns are widened and
// the eigenvalues stay.
TEST(LinearizeStep, FloorScalesWithTheCoordinate) {
  auto l = LoadModel(kInverted, {{"q0", "pi / 2 + 2000 * pi"}}, {}, true);
  ASSERT_TRUE(l && l->prog);
  Eigen::Matrix2d A;
  A << 0, 1, kG / kL, 0;
  for (double step : {1e-16, 1e-8, 1e-6, 1e-3}) {
    const lin::LinearModel m = CheckAt(*l->prog, step, A, std::sqrt(kG / kL));
    const bool q_widened = std::any_of(m.widened.begin(), m.widened.end(),
                                       [](const lin::WidenedStep& w) { return w.name == "hinge.q"; });
    EXPECT_EQ(q_widened, step < 1e-5) << step;  // floor 2^22 eps 6284.76 = 5.9e-6
    EXPECT_EQ(m.widened.size(), step < 1e-5 ? 2u : 0u) << step;
  }
}

// The hanging pendulum (2), with a joint-force input and an output: the claim holds for A
// and for B, C, D (B = [0; 1 / (m l^2)], C of q = [1, 0]) at every allowed step.
TEST(LinearizeStep, HangingPendulumClaimsHoldForEveryMatrix) {
  auto l = LoadModel(kRoot + "/tests/linearize/models/pendulum.mech");
  ASSERT_TRUE(l && l->prog);
  Eigen::Matrix2d A;
  A << 0, 1, -kG / kL, 0;
  for (double step : AllowedSteps()) {
    CheckAt(*l->prog, step, A, std::complex<double>(0, std::sqrt(kG / kL)));
    lin::LinearizeOptions o;
    o.step = step;
    o.inputs = {"hinge.tau"};
    o.outputs = {"hinge.q"};
    lin::LinearModel m;
    ASSERT_TRUE(lin::Linearize(*l->prog, lin::StartPoint(*l->prog), o, &m).ok());
    const double b_error = std::max(std::abs(m.B(0, 0)), std::abs(m.B(1, 0) - 1.0 / (2 * kL * kL)));
    const double c_error = std::max(std::abs(m.C(0, 0) - 1.0), std::abs(m.C(0, 1)));
    const double scale = std::max({1.0, m.B.cwiseAbs().maxCoeff(), m.C.cwiseAbs().maxCoeff()});
    EXPECT_LE(std::max(b_error, c_error) / scale, m.error_BCD) << step;
  }
}

}  // namespace
}  // namespace kanesim::test
