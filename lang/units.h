// Units of measure: Modelica's unit strings ("N.m/rad", "kg.m2", "m/s2", "1") parsed into
// exponents of the seven SI base units and the radian, with a scale factor to the coherent
// SI unit (mm: 1e-3, deg: pi/180). The radian counts as 1 when dimensions are compared
// (Modelica's SIunits: "rad" and "1" agree) but is kept for display, so that "N.m/rad"
// stays readable. The grammar is the Modelica specification's (section 19.1):
//
//   unit_expression := unit_numerator [ "/" unit_denominator ]
//   unit_numerator  := "1" | unit_factors | "(" unit_expression ")"
//   unit_factors    := unit_factor { "." unit_factor }
//   unit_factor     := unit_operand [ ["+" | "-"] integer ]
//   unit_operand    := [ prefix ] symbol
//
// accepting also a chain of "/" (left to right) and parentheses around a denominator.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace kanesim::lang {

struct Unit {
  // Base quantities, in this order: m, kg, s, A, K, mol, cd, rad.
  static constexpr int kBase = 8;
  static constexpr int kRad = 7;
  // Twice the exponent of each base unit: sqrt halves exponents, so halves are kept exact.
  std::array<std::int16_t, kBase> twice{};
  double scale = 1;  // value in this unit times scale = value in the coherent SI unit

  static Unit One() { return Unit{}; }
  Unit operator*(const Unit& o) const;
  Unit operator/(const Unit& o) const;
  Unit Pow(int num, int den) const;  // this^(num/den); den 1 or 2
  // Same dimension ignoring the radian (Modelica's rule: rad = 1).
  bool SameDimension(const Unit& o) const;
  // Same dimension and scale: values in the two units are the same numbers.
  bool Agrees(const Unit& o) const;
  bool Dimensionless() const;  // ignoring the radian
  // "kg.m2/s2", "rad/s", "1"; a scale other than 1 is written in front: "0.001 m".
  std::string ToString() const;
};

// The unit of coordinate k of a joint of kind `kind` ("revolute", "free"...; flat/mechanism.h):
// "rad", "m", or "1" for a quaternion's component; its speed's unit with `speed` ("rad/s",
// "m/s"). "" for a kind without coordinates. One table for the unit check and the CSV header.
std::string JointCoordinateUnit(std::string_view kind, bool quaternion, int k, bool speed);

// Parses `text` into *out. False with *error (what was expected, and where) when the text is
// not a unit expression. An empty text is not a unit: callers treat "" as "no unit".
bool ParseUnit(std::string_view text, Unit* out, std::string* error);

}  // namespace kanesim::lang
