// df/dy by difference quotients grouped by the block structure of options.coupling, shared
// by IDA (Newton matrix cj I - df/dy) and CVODE-BDF (CVODE forms I - gamma df/dy itself).
//
// Curtis-Powell-Reid grouping: columns whose row sets do not overlap are perturbed in one
// evaluation of f, so a Jacobian costs (size of the largest group) evaluations rather than
// n. The increment per column follows the solver's own DQ rule, w the error weights
// (1/w_j = rtol |y_j| + atol), u the unit round-off:
//   IDA:   max(sqrt(u) max(|y_j|, |h y'_j|), 1/w_j), with the sign of h y'_j;
//   CVODE: max(sqrt(u) |y_j|, 1000 |h| u n |f|_w / w_j), |f|_w the WRMS norm of f(t, y)
//          (1 / w_j if f = 0).
// (CVODE-BDF with IDA's rule, measured: the same outcomes, 7 % more evaluations on the
// chain of 40 at rtol 1e-10; docs/benchmarks.md "CVODE-BDF's Jacobian".)
// Closed loops on the reduced form: the partition of the last evaluation (at y) is held
// for the perturbed ones (GuardedRhs::JacobianHold), and the states f does not read under
// it (OdeSystem::ProjectedStates: the dependent speeds and coordinates) are not perturbed:
// their columns are known, df/dy = pdiag on the diagonal and zero elsewhere
// (docs/constraints.md, "Singular configurations"). On the chain of 40 equal-link
// parallelograms (162 states) a Jacobian so costs 2 evaluations instead of 162.
#pragma once

#include <sundials/sundials_matrix.h>
#include <sundials/sundials_types.h>

#include <vector>

#include "sim/stepper.h"

namespace kanesim::sim::detail {

class DqJacobian {
 public:
  enum class Increment { kIda, kCvode };
  // Groups from coupling (per state: its group; empty or of the wrong size: one group).
  void Build(int n, const std::vector<int>& coupling, Increment rule);
  // kCvode's increments at least 1/w (OdeSystem::IteratedRhs). Before Form.
  void SetIncrementFloor(bool on) { floor_ = on; }
  // Where df/dy is held: sparse, in the CSC block pattern (Nonzeros() entries); else dense,
  // column-major n x n. Before Form.
  void SetLayout(bool sparse);
  // Evaluations of f per Jacobian without known columns (the largest group).
  int Colours() const { return static_cast<int>(colors_.size()); }
  // Entries of the block pattern.
  sunindextype Nonzeros() const { return nnz_; }
  // df/dy at (t, y) into the held copy; f0 = f(t, y), the last evaluation of rhs (its
  // discrete choices held for the perturbed ones), yp: y' for the increments' scale and
  // sign (IDA's y', CVODE's f0), h the current step, w the error weights. Returns f's
  // status (> 0: the solver retries with a smaller step).
  int Form(GuardedRhs& rhs, double t, const double* y, const double* yp, const double* f0, double h, const double* w);
  // Evaluations of f spent by Form so far.
  long Evaluations() const { return evals_; }
  // J = cj I - df/dy in J's format (IDA's Newton matrix; sparse: CSC on the block pattern).
  void WriteNewton(double cj, SUNMatrix J) const;
  // J = df/dy, dense (CVODE's Jacobian).
  void WriteDfdy(SUNMatrix J) const;

 private:
  void WritePattern(SUNMatrix J) const;
  bool sparse_ = false;
  int n_ = 0;
  // Groups -> members (ascending), the colours (colour k = the k-th member of every group)
  // and the CSC pattern (column j holds the rows of its group from col_start_[j] on).
  std::vector<int> group_;
  std::vector<std::vector<int>> members_, colors_;
  std::vector<sunindextype> col_start_;
  sunindextype nnz_ = 0;
  std::vector<double> dfdy_;  // df/dy in the pattern (sparse) or column-major (dense)
  std::vector<int> projected_;
  std::vector<char> skip_;
  std::vector<double> f1_, y1_, inc_;
  long evals_ = 0;
  Increment rule_ = Increment::kIda;
  bool floor_ = false;  // SetIncrementFloor
};

}  // namespace kanesim::sim::detail
