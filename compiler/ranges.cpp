// The ranges of user numbers the equations can use in double precision (docs/language.md
// "Ranges"). Kane's equations multiply them: the mass matrix has entries m |r|^2 and
// I_ij, the kinetic energy m |r|^2 w^2 / 2, so a mass or an inertia of 1e300, or a length
// of 1e300 (squared: 1e600) overflows to inf, and a length of 1e-300 (a rod's m L^2 / 12 =
// 1e-600) underflows to 0: the run then fails with "singular mass matrix", naming nothing.
// Non-zero values are held to
//   masses, inertia entries   [1e-100, 1e100]  (kg, kg m^2)
//   lengths (fixed element translations, mass-centre offsets)  [1e-50, 1e50]  (m)
// so that the products above stay within about 1e200 and above 1e-200, far from the
// limits of a double (1.8e308, 2.2e-308) with room for the factorization's own products.
#include <cmath>
#include <sstream>

#include "compiler/compile_internal.h"

namespace kanesim::rt {

namespace {

std::string Shortest(double x) {
  std::ostringstream os;
  os.precision(3);
  os << x;
  return os.str();
}

}  // namespace

std::string OutOfRange(const std::string& what, double x, double lo, double hi, const char* unit) {
  const double a = std::fabs(x);
  if (a == 0.0 || (a >= lo && a <= hi) || !std::isfinite(x)) return "";  // non-finite: K306/K308 say so
  return what + " " + Shortest(x) + " " + unit + " is out of range: a non-zero " + what.substr(what.rfind(' ') + 1) +
         " must be within [" + Shortest(lo) + ", " + Shortest(hi) + "] " + unit;
}

std::string LengthOutOfRange(const std::string& what, const Vec3& r) {
  const double n = r.cwiseAbs().maxCoeff();
  return OutOfRange(what, n, kMinLength, kMaxLength, "m");
}

const char* RangeHint() {
  return "kanesim computes in SI units in double precision, and Kane's equations multiply these numbers (m |r|^2 "
         "in the mass matrix): rescale the units so that they are of ordinary size (docs/language.md \"Ranges\")";
}

}  // namespace kanesim::rt
