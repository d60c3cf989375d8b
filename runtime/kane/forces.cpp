// Applied forces, reduced per body to a force at the mass centre and a torque about it
// (the resultant and moment of Lesser eq. 23), and joint generalized forces Q.
#include <cmath>

#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"

namespace kanesim::rt {

namespace {

double Value(const Scalar& s, const Workspace& ws, const Tape& tape) {
  return s.root < 0 ? s.value : ws.force_regs[static_cast<size_t>(tape.roots[static_cast<size_t>(s.root)])];
}

// Adds force f applied at world point x on body B (ground absorbs it).
void AddForceAt(const Workspace& ws, int body, const Vec3& x, const Vec3& f, Vec3* F, Vec3* T) {
  if (body < 0) return;
  const auto B = static_cast<size_t>(body);
  F[B] += f;
  T[B] += (x - ws.p_WBcm[B]).cross(f);
}

}  // namespace

// Line force between frame origins A and B (flat::LineForce):
//   s = |p_B - p_A|,  e = (p_B - p_A) / s,  sdot = e . (v_B - v_A)
//   f = k (s - s0) + d sdot   (tension),  force +f e on A, -f e on B.
int EvalForceTape(const Program& p, Workspace& ws) {
  const Tape& tape = p.force_tape;
  if (tape.roots.empty()) return 0;
  double* r = ws.force_regs.data();
  if (tape.time_reg >= 0) r[tape.time_reg] = ws.t;
  for (const auto& [in, reg] : tape.input_regs) r[reg] = ws.inputs[static_cast<size_t>(in)];
  if (!p.state_refs_forces.empty()) {
    EvalStateRefs(p, ws, p.state_refs_forces);
    for (const auto& [ref, reg] : tape.state_regs) r[reg] = ws.state_values[static_cast<size_t>(ref)];
  }
  tape.Eval(r);
  for (size_t i = 0; i < tape.roots.size(); ++i)
    if (!std::isfinite(r[tape.roots[i]])) {
      ws.error = "NaN from expression: " + tape.labels[i] + " = " + tape.texts[i] + " at time " + std::to_string(ws.t);
      return 1;  // recoverable, as a NaN acceleration (engine.cpp NotFinite)
    }
  return 0;
}

double ForceValue(const Program& p, const Workspace& ws, const Scalar& s) { return Value(s, ws, p.force_tape); }

int AppliedForces(const Program& p, Workspace& ws) {
  if (int s = EvalForceTape(p, ws); s != 0) return s;
  const Tape& tape = p.force_tape;
  const size_t K = p.bodies.size();
  Vec3* F = ws.F_W.data();
  Vec3* T = ws.T_W.data();
  for (size_t L = 0; L < K; ++L) {
    F[L] = p.bodies[L].mass * p.gravity_W;
    T[L].setZero();
  }
  for (const LineForceModel& l : p.line_forces) {
    Vec3 pa, pb, va, vb, w;
    Mat3 R;
    FramePose(p, ws, l.frame_a, &pa, &R);
    FramePose(p, ws, l.frame_b, &pb, &R);
    FrameMotion(p, ws, l.frame_a, &va, &w);
    FrameMotion(p, ws, l.frame_b, &vb, &w);
    const Vec3 dp = pb - pa;
    const double s = dp.norm();
    if (s == 0.0) continue;  // direction undefined: no force along a zero-length line
    const Vec3 e = dp / s;
    const double f = Value(l.k, ws, tape) * (s - Value(l.s0, ws, tape)) + Value(l.d, ws, tape) * e.dot(vb - va);
    AddForceAt(ws, p.frames[static_cast<size_t>(l.frame_a)].body, pa, f * e, F, T);
    AddForceAt(ws, p.frames[static_cast<size_t>(l.frame_b)].body, pb, -f * e, F, T);
  }
  for (const WrenchModel& wr : p.wrenches) {
    const int body = p.frames[static_cast<size_t>(wr.frame)].body;
    if (body < 0) continue;
    Vec3 x;
    Mat3 R_WF;
    FramePose(p, ws, wr.frame, &x, &R_WF);
    Vec3 f(Value(wr.force[0], ws, tape), Value(wr.force[1], ws, tape), Value(wr.force[2], ws, tape));
    Vec3 t(Value(wr.torque[0], ws, tape), Value(wr.torque[1], ws, tape), Value(wr.torque[2], ws, tape));
    if (!wr.in_world) {
      f = R_WF * f;
      t = R_WF * t;
    }
    AddForceAt(ws, body, x, f, F, T);
    T[static_cast<size_t>(body)] += t;
  }
  for (int r = 0; r < p.nu_all; ++r) ws.Q[r] = Value(p.joint_tau[static_cast<size_t>(r)], ws, tape);
  return 0;
}

}  // namespace kanesim::rt
