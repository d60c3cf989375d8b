// The unit check, the elaborator's phase that checks units of measure (docs/language.md,
// "Units"). It runs on the bound equations (lang/elab_connect.h), when every value a
// variable takes is one binding: its declaration or a modifier, a --set, or an equation
// `x = expr`. Each binding, start, min and max value is checked against the variable's
// declared unit (lang/units.h); each operator, function argument and if-branch inside them
// against its operands. The rules:
//   - a variable's unit is its `unit` attribute; without one it is inferred from its binding
//     when that has a unit, else from the first sum, comparison or equation side that gives
//     it one (a second, different one is an error, E238); else it is unknown and unchecked;
//   - a spring on flanges (TorsionSpring...) takes its c, d, phi_rel0 units from the joint
//     it is connected to; a joint's q and u (Free, Planar...) have one unit per element;
//   - `time` is in s; a frame's r in m, v in m/s, w in rad/s, R dimensionless;
//   - a number takes the unit of what it is added to, compared with or bound to (`x + 1`,
//     `q(start = 0.3)`); in a binding or modifier a number times or over a quantity is a
//     plain factor, unit 1 (L = 2 * mass is a mass); in an equation it may carry any unit
//     (-0.3 * j.u as a torque), so that product is left unchecked; numbers alone are
//     dimensionless;
//   - `time` and numbers alone (sin(time)) are not reported where they meet a unit;
//   - the radian counts as 1 in comparisons ("rad/s" agrees with "1/s"), the degree does not
//     (pi/180); N.m and J agree (same dimension and scale);
//   - sin, cos, tan, exp, log, sinh, cosh, tanh need a dimensionless argument (an angle in
//     rad is one); asin, acos, atan, atan2 give rad; sqrt halves exponents; der divides by s.
// Mismatches are E237 (both units, and notes naming the declarations that gave them);
// unit strings that do not parse are E236.
#pragma once

#include <memory>

#include "lang/elab_connect.h"
#include "lang/elab_emit.h"
#include "lang/elab_instantiate.h"

namespace kanesim::lang::elab {

class UnitChecker;

// The check rides on the emitter's walk over every variable (Emit's `visitor`): the
// instance tree is walked once, while its nodes are in the cache. Its messages are kept
// aside and reported by Finish only when the rest of elaboration found no error (a unit
// message on top of a missing name would repeat it).
class UnitCheck final : public VarVisitor {
 public:
  // `links` gives a spring on flanges the units of the joint it acts on (N.m/rad on a
  // revolute, N/m on a prismatic); a joint's q and u arrays are checked element by element
  // (lang/units.h, JointCoordinateUnit).
  UnitCheck(const InstanceTree& tree, const Links& links, const SourceManager* sources);
  ~UnitCheck();
  // Checks every value given to `var`.
  void Visit(Node* var) override;
  // Writes each output's unit (declared or inferred) to m->outputs[i].unit by name, and,
  // when diags has no error, the check's messages into diags.
  void Finish(const InstanceTree& tree, Diagnostics& diags, flat::Mechanism* m);

 private:
  Diagnostics found_;
  std::unique_ptr<UnitChecker> checker_;
};

}  // namespace kanesim::lang::elab
