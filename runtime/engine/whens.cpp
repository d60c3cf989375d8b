// When clauses (runtime/runtime.h EvalEventTape): their indicators and reinit values are
// one tape, evaluated on the kinematics of (t, y) as the outputs are.
#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

int EvalEventTape(const Program& p, Workspace& ws, double t, const double* y) {
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  if (int s = ProjectState(p, ws); s != 0) return s;  // closed loops: on the constraint manifold
  const Tape& tape = p.event_tape;
  double* r = ws.event_regs.data();
  if (tape.time_reg >= 0) r[tape.time_reg] = t;
  EvalStateRefs(p, ws, p.state_refs_events);
  for (const auto& [ref, reg] : tape.state_regs) r[reg] = ws.state_values[static_cast<size_t>(ref)];
  tape.Eval(r);
  return 0;
}

double EventRoot(const Program& p, const Workspace& ws, int root) {
  return ws.event_regs[static_cast<size_t>(p.event_tape.roots[static_cast<size_t>(root)])];
}

std::vector<std::string> StateNames(const Program& p) {
  std::vector<std::string> q(static_cast<size_t>(p.nq_all)), u(static_cast<size_t>(p.nu_all));
  for (const TreeJoint& j : p.joints) {
    for (int k = 0; k < j.nq; ++k) q[static_cast<size_t>(j.q0 + k)] = j.name + ".q" + (j.nq > 1 ? Index1(k) : "");
    for (int k = 0; k < j.nu; ++k) u[static_cast<size_t>(j.u0 + k)] = j.name + ".u" + (j.nu > 1 ? Index1(k) : "");
  }
  std::vector<std::string> out;
  for (int i : p.q_free) out.push_back(q[static_cast<size_t>(i)]);
  for (int i : p.u_free) out.push_back(u[static_cast<size_t>(i)]);
  return out;
}

}  // namespace kanesim::rt
