// The zero of an event function between two instants, shared by DOP853 and the SUNDIALS
// steppers' graze search.
#ifndef KANESIM_SIM_ILLINOIS_H_
#define KANESIM_SIM_ILLINOIS_H_

#include <algorithm>
#include <cmath>

namespace kanesim::sim {

// g's zero in [a, b] with g(a) = ga > 0 >= g(b) = gb, by the Illinois variant of regula
// falsi: a secant step, and the end kept twice in a row has its value halved, so the
// bracket shrinks superlinearly from both sides. Stops when the bracket is narrower than
// `rel` times the larger |end| (or after 200 steps) and returns its right end, where g <= 0.
// `eval(t, &g)` returning false stops the search: *failed is set and the right end so far
// is returned.
template <class Eval>
double IllinoisRoot(double a, double ga, double b, double gb, double rel, Eval&& eval, bool* failed) {
  *failed = false;
  int side = 0;  // which end was kept last time
  for (int it = 0; it < 200 && b - a > rel * std::max(std::abs(a), std::abs(b)); ++it) {
    double t = b - gb * (b - a) / (gb - ga), gt = 0.0;
    if (!(t > a && t < b)) t = 0.5 * (a + b);
    if (!eval(t, &gt)) {
      *failed = true;
      return b;
    }
    if (gt > 0.0) {
      a = t, ga = gt;
      if (side == -1) gb *= 0.5;
      side = -1;
    } else {
      b = t, gb = gt;
      if (side == 1) ga *= 0.5;
      side = 1;
    }
  }
  return b;
}

}  // namespace kanesim::sim

#endif  // KANESIM_SIM_ILLINOIS_H_
