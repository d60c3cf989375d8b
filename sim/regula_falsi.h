// The zero of an event function between two instants, shared by DOP853 and the SUNDIALS
// steppers' graze search.
#ifndef KANESIM_SIM_REGULA_FALSI_H_
#define KANESIM_SIM_REGULA_FALSI_H_

#include <algorithm>
#include <cmath>

namespace kanesim::sim {

// g's zero in [a, b] with g(a) = ga > 0 >= g(b) = gb, by regula falsi with the
// Anderson-Bjorck weight: a secant step; when the same end is kept twice in a row its value
// is scaled by m = 1 - g(t) / g(end replaced) (by 1/2 when m <= 0, the Illinois weight), so
// the bracket shrinks superlinearly from both sides (Anderson & Bjorck, BIT 12 (1972)
// 503-508; Galdino 2011 compares the variants). Stops when the bracket is not wider than
// tol = `rel` times the larger |end| (or after 200 steps) and returns its right end, where
// g <= 0. `eval(t, &g)` returning false stops the search: *failed is set and the right end
// so far is returned.
//
// A secant point closer than tol / 2 to an end (or rounded onto it) is moved tol / 2 inside,
// doubled on each such move in a row (g's round-off may leave its sign wrong that close to
// the zero), as in Brent's zeroin and SUNDIALS' rootfinding. Without it, once the secant had
// found the zero to a few units of round-off its next points rounded onto the end already
// there (|g| of order 1e-17 a few ulp from the zero), the step fell back to bisection and the
// far end came in by halving. Measured on Talos (fixed base, 1 s, 626 crossings located):
// 14.5 evaluations a crossing with the halved weight and no move, 6.8 with the move, 5.4 with
// the move and this weight (docs/benchmarks/2026-11-29_root_finding.md).
template <class Eval>
double RegulaFalsiRoot(double a, double ga, double b, double gb, double rel, Eval&& eval, bool* failed) {
  *failed = false;
  int side = 0;        // which end was kept last time
  double reach = 0.5;  // a point this many tol from an end at least
  for (int it = 0; it < 200; ++it) {
    const double tol = rel * std::max(std::abs(a), std::abs(b));
    if (!(b - a > tol)) break;
    double t = b - gb * (b - a) / (gb - ga), gt = 0.0;
    if (std::isnan(t)) t = 0.5 * (a + b);
    t = std::clamp(t, a, b);  // rounded onto an end (or past it): moved inside below
    const double d = std::min(reach * tol, 0.5 * (b - a));
    if (t - a < d) {
      t = a + d, reach *= 2.0;
    } else if (b - t < d) {
      t = b - d, reach *= 2.0;
    } else {
      reach = 0.5;
    }
    if (!eval(t, &gt)) {
      *failed = true;
      return b;
    }
    if (gt > 0.0) {
      const double m = 1.0 - gt / ga;
      a = t, ga = gt;
      if (side == -1) gb *= m > 0.0 && m < 1.0 ? m : 0.5;
      side = -1;
    } else {
      const double m = gb < 0.0 ? 1.0 - gt / gb : 0.0;  // (gb = 0: the Illinois weight)
      b = t, gb = gt;
      if (side == 1) ga *= m > 0.0 && m < 1.0 ? m : 0.5;
      side = 1;
    }
  }
  return b;
}

}  // namespace kanesim::sim

#endif  // KANESIM_SIM_REGULA_FALSI_H_
