// Matrix-free Newton-Krylov for IDA and CVODE-BDF (sim/newton_krylov.h).
#include "sim/newton_krylov.h"

#include <sunlinsol/sunlinsol_spgmr.h>

#include <algorithm>

namespace kanesim::sim::detail {
namespace {
// Auto goes matrix-free where (r + 1) kKrylovMinRatio <= n. Measured on the chains of
// equal-link parallelograms, multiplier form, 20 s, rtol 1e-8, r = 2, CPU (matrix-free
// against dense LU): N = 10 (n = 42) CVODE-BDF 1.47 s against 0.98 s, IDA 1.18 against
// 1.13; N = 20 (n = 82) 2.21 against 2.47, IDA 2.35 against 3.09; N = 40 (n = 162) 4.10
// against 14.1, IDA 5.44 against 23.9.
constexpr int kKrylovMinRatio = 20;
// Krylov dimension r + 1 + kKrylovMargin: room for the loops whose rows lose rank near a
// change point (r grows there). Measured on the chain of 40 at rtol 1e-10, 20 s: 8653 GMRES
// iterations in 13918 Newton iterations, 4 failed to converge (CVODE-BDF); IDA 17171 in
// 8039, 32 failed (its Newton iteration failed 11 and 32 times; main's dense LU: 505 Newton
// failures with IDA at this tolerance).
constexpr int kKrylovMargin = 3;
}  // namespace

bool UseKrylov(const IntegratorOptions& options, GuardedRhs& rhs, int* maxl, bool projected_bdf) {
  const int n = rhs.Size();
  const int r = rhs.NewtonRank();
  *maxl = std::clamp(r >= 0 ? r + 1 + kKrylovMargin : 5, 1, std::max(n, 1));
  switch (options.ida_linear_solver) {
    case IdaLinearSolver::Krylov: return true;
    case IdaLinearSolver::Auto: return projected_bdf || (r >= 0 && (r + 1) * kKrylovMinRatio <= n);
    default: return false;
  }
}

SUNLinearSolver MakeKrylovSolver(N_Vector y, int maxl, SUNContext ctx) {
  return SUNLinSol_SPGMR(y, SUN_PREC_NONE, maxl, ctx);
}

}  // namespace kanesim::sim::detail
