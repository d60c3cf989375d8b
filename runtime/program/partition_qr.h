// The pivoting QR that chooses the independent-speed partition of closed loops
// (runtime/constraints/constraints.cpp, FactorDependent): Householder QR of the active rows'
// Jacobian A (n_a x nu) with column pivoting, by the rule of Eigen's ColPivHouseholderQR
// (Eigen 3.4): at step k the remaining column with the largest norm (the first of equal
// ones), its column norms downdated after each step as LAPACK's xGEQPF does (LAWN 176),
// and recomputed from the column's remaining rows when the downdate has lost too much.
//
// What it adds: A of a chain of loops is block-banded (a speed moves the rows of one or
// two loops), so a step touches only the columns whose non-zero rows meet the reflector's,
// and only those rows (each column's set of rows that may be non-zero; a set, not a band:
// the pivots jump along the chain, and a reflector joins row k to the pivot's rows). The
// trailing block fills in as the steps go (the chain of 40 at its change points: dense
// after ~20 of 80 steps), so once a reflector has more than a quarter of the rows left,
// the remaining steps are Eigen's own calls (makeHouseholderInPlace,
// applyHouseholderOnTheLeft, norm()) on the dense block, as its computeInPlace makes them. What it
// skips are exact zeros, and the sums it keeps are added in Eigen's order (its redux and
// matrix-vector kernels with SSE2 packets of two doubles, partition_qr.cpp), so every
// number the choice compares is Eigen's to the bit: the same columns, ties (equal links
// make equal norms) included. tests/constraints/partition_qr_test.cpp checks the pivots and
// |R(k, k)| bit for bit against Eigen's; scripts/same_change_points.py the rows of the
// change-point runs (docs/benchmarks.md, "Chains: several loops singular at once").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace kanesim::rt {

class PartitionQR {
 public:
  void Resize(Eigen::Index m, Eigen::Index n);
  // Factors A (the size given to Resize) for its first `steps` pivots (all min(m, n) when
  // steps < 0). Pivot k's column is Indices()[k] for k < the steps done: later steps never
  // move the columns already chosen, so the first `steps` entries are those of the full
  // factorization.
  void Compute(const Eigen::MatrixXd& A, Eigen::Index steps = -1);
  // Column permutation as Eigen's colsPermutation().indices(): entry k is the column of A
  // pivoted at step k (the entries past the steps done are not final).
  const std::vector<int>& Indices() const { return perm_; }
  // |R(k, k)| of a step done.
  double DiagAbs(Eigen::Index k) const;
  // Eigen's rank() with its default threshold (eps * min(m, n) times the largest pivot),
  // and its nonzeroPivots(); meaningful after a full Compute.
  Eigen::Index Rank() const;
  Eigen::Index NonzeroPivots() const { return nonzero_pivots_; }

 private:
  void DenseStep(Eigen::Index k);  // step k after the swap, by Eigen's own calls
  Eigen::MatrixXd qr_;                   // working copy of A, R above the diagonal, reflectors below
  Eigen::VectorXd norm_upd_, norm_dir_;  // Eigen's m_colNormsUpdated / m_colNormsDirect
  std::vector<int> perm_;
  // The rows where each column may be non-zero, a bit per row (words_ words per column),
  // and the current reflector's; the reflector times tau.
  std::vector<uint64_t> rows_, vrows_;
  Eigen::Index words_ = 0;
  std::vector<double> v_;
  Eigen::VectorXd temp_;  // Eigen's m_temp: the reflector's row workspace
  Eigen::Index steps_ = 0, nonzero_pivots_ = 0;
  double max_pivot_ = 0.0;
};

}  // namespace kanesim::rt
