// Linear models of a compiled mechanism about an operating point (issue 23,
// docs/linearize.md):
//
//   x' = A x + B w,   y = C x + D w                                         (1)
//
// where
//   x  the independent coordinates and independent speeds, as deviations from the
//      operating point: x = [xi_I; u_I - u_I0]. xi are chart coordinates of the
//      configuration, one per free speed (a scalar joint coordinate: its deviation; a
//      quaternion: the rotation vector of the body-fixed perturbation, Q = Q0 Exp(xi));
//      holonomic constraints (loop closures, a contact's normal row) remove some of them
//      (the dependent ones follow by Newton on phi(q) = 0), velocity constraints A u + b =
//      0 (loops and rolling rows) remove speeds: a rolling system keeps more coordinates
//      than speeds.
//   w  inputs: the model's own inputs (`input Real u;`, at their values at the operating
//      point), then generalized forces added to a joint's speeds ("hinge.tau",
//      "free.tau[4]") or real parameters ("k", "world.g[2]"; parameters bound to it follow).
//   y  output signals (any name of rt::AvailableSignals).
//
// Derivatives are central differences with Richardson extrapolation over the steps h,
// h/2, h/4, divided by the steps actually taken (as rounded); the achieved accuracy
// reported is the difference of the last two extrapolations plus a bound on the rounding
// error, and a step too small to survive rounding is widened to a floor (linearize.cpp,
// eqs. 7-9). The same code serves the reduced and the multiplier form (both go through
// rt::Derivative on consistent states).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "runtime/runtime.h"

namespace kanesim::lin {

// 0 ok; 1 bad input (unknown input or output name, an operating point that violates the
// constraints); 2 numerical (singular configuration, no equilibrium found, a failing
// evaluation). The CLI uses it as the exit code.
struct Status {
  Status() = default;
  Status(int c, std::string m, std::string h = {}, flat::SourceLoc w = {})
      : code(c), message(std::move(m)), hint(std::move(h)), where(std::move(w)) {}
  int code = 0;
  std::string message;
  std::string hint;                  // what to do about it (may be empty)
  flat::SourceLoc where;             // the loop or contact concerned (line 0: none)
  bool ok() const { return code == 0; }
};

struct LinearizeOptions {
  double step = 1e-3;                // base step h, times the scale of each variable (1 for coordinates)
  // The model's inputs at the operating point (rt::InputName order; one value each when the
  // model has inputs): held at these values, and each is a column of B and D.
  std::vector<double> input_values;
  std::vector<std::string> inputs;   // joint force "J.tau" / "J.tau[k]", or a real parameter name
  std::vector<std::string> outputs;  // signal names
};

// An operating point: time and the integrator's state y = [q_free; u_free] (consistent
// with the constraints).
struct OperatingPoint {
  double t = 0.0;
  std::vector<double> y;
};

// The model's start values (rt::InitialState at rt::StartTime).
OperatingPoint StartPoint(const rt::Program& program);

// The state of the motion from the start values at time t (integrated with rtol 1e-10,
// then projected onto the constraints), the model's inputs from `inputs` (needed when it
// has some). Status 2 when the run fails before t.
Status PointAtTime(const rt::Program& program, double t, OperatingPoint* out, const rt::InputSource* inputs = nullptr);

// `program` with real parameter `name` set to `value` (parameters bound to it follow).
// Status 1 for an unknown, structural or constant parameter, or a value Rebind refuses.
Status RebindParameter(const rt::Program& program, const std::string& name, double value,
                       std::shared_ptr<const rt::Program>* out);

// One mode: eigenvalue lambda = sigma + i omega, with natural frequency |lambda|,
// damped frequency |omega| / 2 pi, damping ratio -sigma / |lambda| and the coordinate
// states that dominate its shape (|v_i| >= 0.1 max, largest first).
struct Mode {
  std::complex<double> lambda;
  double omega_n = 0.0, freq_hz = 0.0, zeta = 0.0;
  std::vector<std::pair<std::string, double>> dominant;  // (state name, |v_i| / max |v|)
  Eigen::VectorXcd shape;                                // eigenvector, largest entry 1
};

// A column whose step was below the rounding floor (linearize.cpp, eq. 8) and was widened.
struct WidenedStep {
  std::string name;       // the state or input
  double requested = 0;   // the step asked for (--step, scaled by the variable's size for a speed or parameter)
  double used = 0;        // the floor used instead
};

struct LinearModel {
  std::vector<std::string> states;   // names: "hinge.q", "free.rot[2]", ..., then "hinge.u", ...
  int n_coords = 0;                  // the first n_coords states are coordinates, the rest speeds
  std::vector<std::string> inputs, outputs;
  Eigen::MatrixXd A, B, C, D;        // (n x n), (n x m), (p x n), (p x m)
  double h = 0.0;                    // base step used
  double error_A = 0.0;              // achieved accuracy, eq. (9): max (|A_R(h/2) - A_R(h)| + rounding) / max(1, max |A|)
  double error_BCD = 0.0;            // the same for B, C, D together
  std::vector<WidenedStep> widened;  // columns differenced with a wider step than asked (eq. 8)
  // Filled by ComputeModes:
  std::vector<Mode> modes;           // sorted by |lambda|, then by imaginary part descending
  std::vector<std::string> ignorable;  // coordinates no other state reads; each gives a zero eigenvalue
  // Rows the operating point adds (hybrid.h): "j1 on q_min", "floor on the plane", "j2 stuck";
  // their coordinates and speeds are not states.
  std::vector<std::string> held;
  std::vector<double> x0_rates;      // f(0): zero at an equilibrium; steady rates of ignorable coordinates
  // Whether the operating point is an equilibrium or a steady motion: A at x = tau f(0)
  // (the motion a moment later, tau so that it moves 0.05) against A at 0, on three fixed
  // directions v: max |(A(tau f0) - A(0)) v| / max(1, |A(0) v|); 0 at an equilibrium. Above 1e-6 the
  // eigenvalues are those of a frozen instant of a changing motion (not stability
  // exponents): not an equilibrium, or coordinates that do not follow the motion's
  // symmetry (a spinning quaternion joint; docs/linearize.md "Steady motions").
  double unsteady = 0.0;
};

// Linearizes `program` about `op`: A, B, C, D and the accuracy; the modes are left to
// ComputeModes (an eigendecomposition, O(n^3)). On failure the status says why.
Status Linearize(const rt::Program& program, const OperatingPoint& op, const LinearizeOptions& options,
                 LinearModel* out);

// One evaluation at step s: F(s), and the step actually taken (eq. 5's h+ or -h-: the
// perturbed variable's value minus its value at s = 0, as rounded).
using StepEval = std::function<Status(double s, Eigen::VectorXd* f, double* taken)>;

// dF/ds at s = 0: central differences over the steps h, h/2, h/4 with Richardson
// extrapolation (linearize.cpp, eqs. 5-7); *err = |R(h/2) - R(h)|, without the rounding
// term. The columns of A, B, C, D, and the FMU's directional derivatives (fmi/instance.h).
Status Richardson(const StepEval& F, double h, Eigen::VectorXd* d, Eigen::VectorXd* err);

// Eigenvalues and modes of model->A (fills model->modes and model->ignorable).
void ComputeModes(LinearModel* model);

struct EquilibriumResult {
  OperatingPoint point;
  int iterations = 0;                // Newton iterations
  long relaxation_steps = 0;         // steps of the relaxation when Newton stalled (equilibrium.cpp Relax)
  double residual = 0.0;             // max |u'_I| at the point found (acceleration units)
  std::vector<std::pair<std::string, double>> moved;  // (coordinate, change) beyond 1e-9
};

// Static equilibrium from `start`: Newton on the independent accelerations u'_I(xi_I) =
// 0 with every free speed zero (a pseudo-inverse step: directions without stiffness
// stay where they are); when Newton stalls, a relaxation toward a potential minimum, then
// Newton again. Status 2 when no equilibrium is found.
// `input_values`: the model's inputs, held (LinearizeOptions::input_values).
Status FindEquilibrium(const rt::Program& program, const OperatingPoint& start, EquilibriumResult* out,
                       const std::vector<double>& input_values = {});

}  // namespace kanesim::lin
