// Compile stage: plane contacts (stdlib PlaneContact). A unilateral contact is not a
// constraint row: the integrators' events handle it (sim/end_stops.h), impacts through the
// mass matrix with the constraint rows' reactions (closed loops, rolling contacts,
// couplings). Beside Coulomb friction that reads a normal force (mu), in a tree or beside
// constraint rows, a resting contact's force and an impact's impulse enter the joints'
// normal forces (sim/end_stops_friction.cpp; docs/stdlib.md "PlaneContact").
#include <cmath>

#include "compiler/compile_internal.h"
#include "runtime/kinematics/joint_kinematics.h"

namespace kanesim::rt {

void CompilePlaneContacts(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  auto num = [&](flat::ExprId id, double dflt, const flat::SourceLoc& loc) {
    double v = dflt;
    if (id != kNoExpr && !folder.Fold(id, &v))
      errors->push_back(Msg(flat::DiagCode::NotFixed, "contact geometry must not depend on time or state", loc));
    return v;
  };
  for (const flat::Contact& fc : m.contacts) {
    if (fc.type != flat::ContactType::Plane) continue;
    PlaneContactModel c;
    c.name = fc.name;
    c.loc = fc.loc;
    c.frame = fc.frame;
    if (fc.frame < 0 || p.frames[static_cast<size_t>(fc.frame)].body < -1) {
      errors->push_back(Msg(flat::DiagCode::BadContact, "contact '" + fc.name + "' is not connected to the mechanism", fc.loc));
      continue;
    }
    c.body = p.frames[static_cast<size_t>(fc.frame)].body;
    if (c.body < 0) {
      errors->push_back(Msg(flat::DiagCode::BadContact, "contact '" + fc.name + "' is attached to the ground", fc.loc,
                            "connect its frame to a moving body"));
      continue;
    }
    EnsurePathSpeeds(p, c.body);
    for (int k = 0; k < 3; ++k) c.n_W[k] = num(fc.plane_normal[static_cast<size_t>(k)], 0.0, fc.loc);
    c.d = num(fc.offset, 0.0, fc.loc);
    c.restitution = num(fc.restitution, 0.0, fc.loc);
    // n . x = d with n normalized: d is scaled with it.
    const double norm = c.n_W.norm();
    if (!NormalizeScaled(&c.n_W) || !std::isfinite(c.d)) {
      errors->push_back(Msg(flat::DiagCode::BadContact,
                            "contact '" + fc.name + "': its plane normal " + WhyNoDirection(c.n_W.data(), 3), fc.loc,
                            "a normal is a direction: any non-zero finite vector (it is normalized)"));
      continue;
    }
    c.d /= norm;
    if (!(c.restitution >= 0.0 && c.restitution <= 1.0)) {
      errors->push_back(Msg(flat::DiagCode::BadContact, "contact '" + fc.name + "': restitution must be in [0, 1]", fc.loc));
      continue;
    }
    p.plane_contacts.push_back(c);
  }
}

}  // namespace kanesim::rt
