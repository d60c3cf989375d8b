// When clauses (flat::WhenClause -> Program::whens; docs/events.md): the indicators and reinit
// values into the event tape, and what a reinit may set. A speed is set by an impulse through
// the mass matrix (sim/when_events.cpp; resting stops and plane contacts held by
// sim/end_stops.cpp; closed loops' and rolling contacts' rows by their reactions,
// rt::InverseMassColumn; Coulomb friction's impulses by sim/friction_impulse.cpp, the rows'
// impulses in the normal impulses); a coordinate is set as it is, which needs a tree and a
// coordinate that is not a quaternion's.
#include <algorithm>
#include <string>

#include "compiler/compile_internal.h"

namespace kanesim::rt {

namespace {

// Why the reinit of `ref` cannot be done in program p ("" when it can); *state its index in y.
std::string ReinitRefusal(const Program& p, const flat::StateRef& ref, int* state) {
  const bool speed = ref.kind == flat::StateKind::JointU;
  const int tj = ref.target >= 0 && static_cast<size_t>(ref.target) < p.joint_of_flat.size()
                     ? p.joint_of_flat[static_cast<size_t>(ref.target)]
                     : -1;
  if (tj < 0) return "the joint does not move (a weld, or a cut joint of a closed loop)";
  if (!p.rows.empty() && !speed)
    return "the mechanism has closed loops or rolling contacts, whose position constraints a jump of a coordinate "
           "would break (reinit a speed: the others follow through the rows)";
  const TreeJoint& j = p.joints[static_cast<size_t>(tj)];
  if (speed) {
    const int f = p.u_free_of[static_cast<size_t>(j.u0 + ref.k)];
    if (f < 0) return "the joint's motion is prescribed";
    *state = p.nq + f;
    return "";
  }
  if ((j.type == flat::JointType::Spherical || j.type == flat::JointType::Free) &&
      j.rotation == flat::RotationCoords::Quaternion && ref.k >= j.nq - 4)
    return "it is a quaternion component (unit norm); reinit the speeds instead";
  const auto it = std::find(p.q_free.begin(), p.q_free.end(), j.q0 + ref.k);
  if (it == p.q_free.end()) return "the joint's motion is prescribed";
  *state = static_cast<int>(it - p.q_free.begin());
  return "";
}

}  // namespace

void CompileWhens(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  if (m.whens.empty()) return;
  TapeBuilder tape = TapeBuilder::SharingFolds(folder);
  for (const flat::WhenClause& w : m.whens) {
    WhenModel out;
    const std::string& file = w.loc.file.str();
    out.name = "when (" + file.substr(file.find_last_of('/') + 1) + ":" + std::to_string(w.loc.line) + ")";
    for (flat::ExprId h : w.indicators) out.indicators.push_back(tape.AddRoot(h, out.name, m.ExprText(h)));
    for (const flat::Reinit& r : w.reinits) {
      const flat::StateRef& ref = m.state_refs[static_cast<size_t>(r.state_ref)];
      WhenReinit x;
      x.name = m.StateRefName(ref);
      x.speed = ref.kind == flat::StateKind::JointU;
      if (std::string why = ReinitRefusal(p, ref, &x.state); !why.empty()) {
        errors->push_back(Msg(flat::DiagCode::BadReinit, "cannot reinit '" + x.name + "': " + why, r.loc));
        continue;
      }
      x.root = tape.AddRoot(r.value, "reinit of " + x.name, m.ExprText(r.value));
      out.reinits.push_back(std::move(x));
    }
    out.terminate = w.terminate;
    out.message = w.message;
    p.whens.push_back(std::move(out));
  }
  p.event_tape = tape.Finish();
  for (const auto& [ref, reg] : p.event_tape.state_regs) {
    const flat::StateRef& r = m.state_refs[static_cast<size_t>(ref)];
    const bool joint = r.kind == flat::StateKind::JointQ || r.kind == flat::StateKind::JointU;
    const bool ok = joint ? r.target >= 0 && static_cast<size_t>(r.target) < p.joint_of_flat.size() &&
                                p.joint_of_flat[static_cast<size_t>(r.target)] >= 0
                          : r.target >= 0 && static_cast<size_t>(r.target) < p.frames.size() &&
                                p.frames[static_cast<size_t>(r.target)].body >= -1;
    if (!ok)
      errors->push_back(Msg(flat::DiagCode::NotSimulated, "'" + m.StateRefName(r) + "' is not a simulated quantity", {}));
    p.state_refs_events.push_back(ref);
  }
}

}  // namespace kanesim::rt
