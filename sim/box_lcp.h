// A box-constrained linear complementarity problem with a symmetric positive definite matrix
// (the laws at rest of constant Coulomb friction: sim/stick_slip_laws.cpp). Given A (m x m,
// row-major), q and bounds lo <= hi (either may be infinite), find x with w = q + A x and,
// for every k,
//   lo_k < x_k < hi_k  and  w_k = 0,   or   x_k = lo_k  and  w_k >= 0,   or   x_k = hi_k  and  w_k <= 0.
// For A positive definite exactly one x solves it: it minimizes x^T A x / 2 + q^T x over the
// box (Cottle, Pang & Stone, "The Linear Complementarity Problem", 1992, ch. 3: a P-matrix
// gives every q one solution).
//
// Projected Gauss-Seidel (the minimization coordinate by coordinate, which converges for a
// positive definite A) gives a first guess of which bound each x_k is at; principal pivoting
// then solves exactly: the free x_k from their equations w_k = 0, the others at their
// bounds, and the first k (in index order) whose condition fails changes its state (Murty's
// least-index rule, finite for a P-matrix: Murty, "Note on a Bard-type scheme for solving
// the complementarity problem", Opsearch 11, 1974).
#pragma once

#include <vector>

namespace kanesim::sim {

enum class BoxState : signed char { kLower = -1, kFree = 0, kUpper = 1 };

struct BoxLcpResult {
  bool solved = false;
  std::vector<double> x, w;        // the solution and q + A x
  std::vector<BoxState> state;     // where each x_k is
  int pivots = 0;                  // principal pivots after the first guess
};

// tol: the conditions' relative tolerance (w against the scale of q and A x; x against its
// bounds). solved is false where the pivots ran out (not expected for a positive definite
// A) or a free block was singular (A not positive definite).
BoxLcpResult SolveBoxLcp(const std::vector<double>& A, const std::vector<double>& q, const std::vector<double>& lo,
                         const std::vector<double>& hi, double tol = 1e-12);

}  // namespace kanesim::sim
