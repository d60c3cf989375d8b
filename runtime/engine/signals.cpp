// Output signals: names, plans (only what a selection needs is computed), evaluation.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include "runtime/runtime.h"
#include "runtime/engine/output_rows.h"
#include "runtime/constraints/constraints.h"
#include "runtime/constraints/contacts.h"
#include "runtime/constraints/reactions.h"
#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"

namespace kanesim::rt {

enum class SignalKind : std::uint8_t {
  JointQ,           // a = full q index
  JointU,           // a = full u index
  JointA,           // a = full u index: its acceleration udot (the free ones solved, prescribed from the jet)
  Output,           // a = output tape root
  KineticEnergy,
  PotentialEnergy,  // gravity + line-force springs
  BodyPosition,     // a = body_signals index, k: mass centre in W
  BodyVelocity,     // mass-centre velocity in W
  BodyAngVel,       // angular velocity in W
  BodyAccel,        // mass-centre acceleration in W
  BodyAngAccel,     // angular acceleration in W
  BodyRotation,     // R_WF of the body's frame, k = 3 i + j
  FramePosition,    // a = flat frame, k: its origin in W
  FrameRotation,    // a = flat frame, k = 3 i + j of R_WF
  FrameVelocity,    // a = flat frame, k: its origin's velocity in W
  FrameAngVel,      // a = flat frame, k: its angular velocity in W
  Drive,            // a = full u index of a prescribed coordinate: force that drives it
  Reaction,         // a = flat joint, k = 0..2 force, 3..5 torque on frame_b's side, frame_b axes
  ConstraintPower,  // power of all ideal constraint forces (0 on admissible motions)
  Contact,          // a = contact; k = 0..2 point, 3 normal, 4 longitudinal, 5 lateral force,
                    // 6 |phi| normal, 7 max |A u + b| of its rows
  LoopResidual,     // a = loop; k = 0: max |phi| of its rows, 1: max |A u + b|, 2: max |phi| before projection
};

struct SignalItem {
  SignalKind kind;
  int a = 0, k = 0;
  bool nan = false;  // statically indeterminate and written as NaN (IndeterminateReactions::NaN)
};

struct SignalPlan {
  std::vector<SignalItem> items;
  bool velocity = false;  // VelocityKinematics needed
  bool outputs = false;   // output tape needed
  bool forces = false;    // force tape needed (spring energy with expression stiffness)
  bool dynamics = false;  // full accelerations needed (drive forces)
  bool drift = false;     // loop residuals of the integrator's state, before projection
  bool reactions = false; // joint reaction wrenches (and loop multipliers) needed
};

namespace {

std::string Idx(int k) { return Index1(k); }

std::string Idx2(int k) { return "[" + std::to_string(k / 3 + 1) + "," + std::to_string(k % 3 + 1) + "]"; }

// The names a frame's R, v and w are listed under: its canonical name and the names the
// model itself declares for it (a `Frame tool0`, a connector `off.frame_b` of a component
// of the model: at most one dot), not the stdlib's inner connectors (rod1.tip.frame_b).
std::vector<std::string> FrameSignalNames(const flat::Frame& f) {
  std::vector<std::string> names{f.name};
  for (const std::string& a : f.aliases)
    if (a != f.name && std::count(a.begin(), a.end(), '.') <= 1) names.push_back(a);
  return names;
}

// "<frame>.r[k]", ".v[k]", ".w[k]" or ".R[i,j]" of any name of a frame: the item, or false.
bool FrameSignalByAlias(const Program& p, const std::string& n, SignalItem* out) {
  const size_t dot = n.rfind('.');
  if (dot == std::string::npos || dot == 0) return false;
  const std::string tail = n.substr(dot + 1);
  SignalItem it{SignalKind::FramePosition, -1, 0};
  auto digit = [](char c) { return c >= '1' && c <= '3'; };
  if (tail.size() == 4 && tail[1] == '[' && digit(tail[2]) && tail[3] == ']' &&
      (tail[0] == 'r' || tail[0] == 'v' || tail[0] == 'w')) {
    it.kind = tail[0] == 'r' ? SignalKind::FramePosition : tail[0] == 'v' ? SignalKind::FrameVelocity : SignalKind::FrameAngVel;
    it.k = tail[2] - '1';
  } else if (tail.size() == 6 && tail[0] == 'R' && tail[1] == '[' && digit(tail[2]) && tail[3] == ',' && digit(tail[4]) &&
             tail[5] == ']') {
    it.kind = SignalKind::FrameRotation;
    it.k = 3 * (tail[2] - '1') + (tail[4] - '1');
  } else {
    return false;
  }
  const int f = p.mech->FindFrame(n.substr(0, dot));
  if (f < 0 || p.frames[static_cast<size_t>(f)].body < -1) return false;
  it.a = f;
  *out = it;
  return true;
}

// Every signal with its name, in the order AvailableSignals lists them.
std::vector<std::pair<std::string, SignalItem>> AllSignals(const Program& p) {
  std::vector<std::pair<std::string, SignalItem>> s;
  for (const TreeJoint& j : p.joints) {
    for (int k = 0; k < j.nq; ++k) s.push_back({j.name + ".q" + (j.nq > 1 ? Idx(k) : ""), {SignalKind::JointQ, j.q0 + k, 0}});
    for (int k = 0; k < j.nu; ++k) s.push_back({j.name + ".u" + (j.nu > 1 ? Idx(k) : ""), {SignalKind::JointU, j.u0 + k, 0}});
    for (int k = 0; k < j.nu; ++k) s.push_back({j.name + ".a" + (j.nu > 1 ? Idx(k) : ""), {SignalKind::JointA, j.u0 + k, 0}});
    for (int k = 0; k < j.nu; ++k)
      if (p.u_free_of[static_cast<size_t>(j.u0 + k)] < 0)
        s.push_back({j.name + ".drive" + (j.nu > 1 ? Idx(k) : ""), {SignalKind::Drive, j.u0 + k, 0}});
  }
  auto reactions = [&s](const std::string& name, int flat_joint) {
    for (int k = 0; k < 3; ++k) s.push_back({name + ".reaction_force" + Idx(k), {SignalKind::Reaction, flat_joint, k}});
    for (int k = 0; k < 3; ++k) s.push_back({name + ".reaction_torque" + Idx(k), {SignalKind::Reaction, flat_joint, 3 + k}});
  };
  for (const TreeJoint& j : p.joints) reactions(j.name, j.flat_index);
  for (const LoopClosure& l : p.loops) reactions(l.name, l.flat_index);
  s.push_back({"constraint_power", {SignalKind::ConstraintPower, 0, 0}});
  for (size_t c = 0; c < p.contacts.size(); ++c) {
    const int a = static_cast<int>(c);
    const std::string& n = p.contacts[c].name;
    for (int k = 0; k < 3; ++k) s.push_back({n + ".point" + Idx(k), {SignalKind::Contact, a, k}});
    s.push_back({n + ".normal_force", {SignalKind::Contact, a, 3}});
    s.push_back({n + ".longitudinal_force", {SignalKind::Contact, a, 4}});
    s.push_back({n + ".lateral_force", {SignalKind::Contact, a, 5}});
    s.push_back({n + ".constraint_residual", {SignalKind::Contact, a, 6}});
    s.push_back({n + ".constraint_residual_velocity", {SignalKind::Contact, a, 7}});
  }
  for (size_t l = 0; l < p.loops.size(); ++l) {
    const int a = static_cast<int>(l);
    s.push_back({p.loops[l].name + ".constraint_residual", {SignalKind::LoopResidual, a, 0}});
    s.push_back({p.loops[l].name + ".constraint_residual_velocity", {SignalKind::LoopResidual, a, 1}});
    s.push_back({p.loops[l].name + ".constraint_drift", {SignalKind::LoopResidual, a, 2}});
  }
  const auto& outs = p.mech->outputs;
  for (size_t i = 0; i < outs.size(); ++i) s.push_back({outs[i].name, {SignalKind::Output, static_cast<int>(i), 0}});
  s.push_back({"kinetic_energy", {SignalKind::KineticEnergy, 0, 0}});
  s.push_back({"potential_energy", {SignalKind::PotentialEnergy, 0, 0}});
  for (size_t i = 0; i < p.body_signals.size(); ++i) {
    const BodySignalSource& b = p.body_signals[i];
    if (p.frames[static_cast<size_t>(b.frame)].body < -1) continue;
    const int a = static_cast<int>(i);
    for (int k = 0; k < 3; ++k) s.push_back({b.name + ".r" + Idx(k), {SignalKind::BodyPosition, a, k}});
    for (int k = 0; k < 3; ++k) s.push_back({b.name + ".v" + Idx(k), {SignalKind::BodyVelocity, a, k}});
    for (int k = 0; k < 3; ++k) s.push_back({b.name + ".w" + Idx(k), {SignalKind::BodyAngVel, a, k}});
    for (int k = 0; k < 3; ++k) s.push_back({b.name + ".a" + Idx(k), {SignalKind::BodyAccel, a, k}});
    for (int k = 0; k < 3; ++k) s.push_back({b.name + ".alpha" + Idx(k), {SignalKind::BodyAngAccel, a, k}});
    for (int k = 0; k < 9; ++k) s.push_back({b.name + ".R" + Idx2(k), {SignalKind::BodyRotation, a, k}});
  }
  for (size_t f = 0; f < p.frames.size(); ++f) {
    if (p.frames[f].body < -1) continue;
    for (int k = 0; k < 3; ++k)
      s.push_back({p.mech->frames[f].name + ".r" + Idx(k), {SignalKind::FramePosition, static_cast<int>(f), k}});
  }
  // Frames as signals (issue 40), after the older ones so that their order is kept.
  for (size_t f = 0; f < p.frames.size(); ++f) {
    if (p.frames[f].body < -1) continue;
    const int a = static_cast<int>(f);
    const std::vector<std::string> names = FrameSignalNames(p.mech->frames[f]);
    for (size_t i = 0; i < names.size(); ++i) {
      const std::string& n = names[i];
      if (i > 0)
        for (int k = 0; k < 3; ++k) s.push_back({n + ".r" + Idx(k), {SignalKind::FramePosition, a, k}});
      for (int k = 0; k < 9; ++k) s.push_back({n + ".R" + Idx2(k), {SignalKind::FrameRotation, a, k}});
      for (int k = 0; k < 3; ++k) s.push_back({n + ".v" + Idx(k), {SignalKind::FrameVelocity, a, k}});
      for (int k = 0; k < 3; ++k) s.push_back({n + ".w" + Idx(k), {SignalKind::FrameAngVel, a, k}});
    }
  }
  return s;
}

// Reaction and contact-force components that redundant constraints leave undetermined
// (Program::reaction_indeterminate, ::contact_indeterminate).
bool Indeterminate(const Program& p, const SignalItem& it) {
  if (it.kind == SignalKind::Reaction && !p.reaction_indeterminate.empty())
    return ((p.reaction_indeterminate[static_cast<size_t>(it.a)] >> it.k) & 1u) != 0;
  if (it.kind == SignalKind::Contact && it.k >= 3 && it.k <= 5 && !p.contact_indeterminate.empty())
    return ((p.contact_indeterminate[static_cast<size_t>(it.a)] >> (it.k - 3)) & 1u) != 0;
  return false;
}

double SpringEnergy(const Program& p, const Workspace& ws) {
  double e = 0.0;
  for (const LineForceModel& l : p.line_forces) {
    Vec3 pa, pb;
    Mat3 R;
    FramePose(p, ws, l.frame_a, &pa, &R);
    FramePose(p, ws, l.frame_b, &pb, &R);
    const double x = (pb - pa).norm() - ForceValue(p, ws, l.s0);
    e += 0.5 * ForceValue(p, ws, l.k) * x * x;
  }
  return e;
}

// The acceleration of a body signal's mass centre, or its body's angular acceleration, in
// W (after BiasAccelerations with the free udot included). For the point C of body B at
// rho = p_WC - p_WBo, rigid-body kinematics gives
//   a_C = a_Bo + alpha_B x rho + w_B x (w_B x rho),                                  (1)
// the same relation as BiasStep's eq. (7) for the merged body's own mass centre.
Vec3 BodySignalAcceleration(const Program& p, const Workspace& ws, const SignalItem& it) {
  const BodySignalSource& b = p.body_signals[static_cast<size_t>(it.a)];
  const int body = p.frames[static_cast<size_t>(b.frame)].body;
  if (body < 0) return Vec3::Zero();
  const auto B = static_cast<size_t>(body);
  if (it.kind == SignalKind::BodyAngAccel) return ws.alpha_bias[B];
  Vec3 pos;
  Mat3 R;
  FramePose(p, ws, b.frame, &pos, &R);
  const Vec3 rho = pos + R * b.p_FBcm - ws.p_WB[B];
  return ws.a_bias_o[B] + ws.alpha_bias[B].cross(rho) + ws.w_WB[B].cross(ws.w_WB[B].cross(rho));  // (1)
}

}  // namespace

std::vector<std::string> AvailableSignals(const Program& p) {
  std::vector<std::string> names;
  for (auto& [n, item] : AllSignals(p)) names.push_back(n);
  return names;
}

// AllSignals' JointQ, JointU and Output entries, in its order, without naming the rest.
std::vector<std::string> DefaultSignals(const Program& p) {
  std::vector<std::string> names;
  for (const TreeJoint& j : p.joints) {
    for (int k = 0; k < j.nq; ++k) names.push_back(j.name + ".q" + (j.nq > 1 ? Idx(k) : ""));
    for (int k = 0; k < j.nu; ++k) names.push_back(j.name + ".u" + (j.nu > 1 ? Idx(k) : ""));
  }
  for (const auto& o : p.mech->outputs) names.push_back(o.name);
  return names;
}

namespace {

// "[k]" with 1 <= k <= n: k - 1, or -1.
int BracketIndex(std::string_view s, int n) {
  if (s.size() < 3 || s.front() != '[' || s.back() != ']') return -1;
  int k = 0;
  for (const char c : s.substr(1, s.size() - 2)) {
    if (c < '0' || c > '9' || k > n) return -1;
    k = 10 * k + (c - '0');
  }
  return k >= 1 && k <= n ? k - 1 : -1;
}

// The item AllSignals would find first for n, for the names a run plans on every start
// (a joint's q or u, an output, the energies) without naming every signal: false if n is
// another kind. Undotted names in AllSignals' order: constraint_power, the outputs, the
// energies. The suffix ".q", ".q[k]", ".u", ".u[k]" after the last dot is no other
// kind's before the outputs, so the first joint of that name is the first match.
bool QuickSignal(const Program& p, std::string_view n, SignalItem* out) {
  const size_t dot = n.rfind('.');
  if (dot == std::string_view::npos) {
    if (n == "constraint_power") return false;
    const auto& outs = p.mech->outputs;
    for (size_t i = 0; i < outs.size(); ++i)
      if (outs[i].name == n) {
        *out = {SignalKind::Output, static_cast<int>(i), 0};
        return true;
      }
    if (n != "kinetic_energy" && n != "potential_energy") return false;
    *out = {n == "kinetic_energy" ? SignalKind::KineticEnergy : SignalKind::PotentialEnergy, 0, 0};
    return true;
  }
  if (dot + 1 >= n.size()) return false;
  const std::string_view joint = n.substr(0, dot), tail = n.substr(dot + 1);
  const char c = tail.front();
  if (c != 'q' && c != 'u') return false;
  for (const TreeJoint& j : p.joints) {
    if (j.name != joint) continue;
    const int count = c == 'q' ? j.nq : j.nu;
    const int k = tail.size() == 1 ? (count == 1 ? 0 : -1) : (count > 1 ? BracketIndex(tail.substr(1), count) : -1);
    if (k < 0) return false;
    *out = {c == 'q' ? SignalKind::JointQ : SignalKind::JointU, (c == 'q' ? j.q0 : j.u0) + k, 0};
    return true;
  }
  return false;
}

}  // namespace

std::shared_ptr<const SignalPlan> PlanSignals(const Program& p, const std::vector<std::string>& names,
                                              std::string* error) {
  std::vector<std::pair<std::string, SignalItem>> all;  // named only when a name needs it
  auto plan = std::make_shared<SignalPlan>();
  for (const std::string& n : names) {
    SignalItem quick{SignalKind::JointQ, 0, 0};
    const SignalItem* found = QuickSignal(p, n, &quick) ? &quick : nullptr;
    if (!found && all.empty()) all = AllSignals(p);
    for (size_t i = 0; !found && i < all.size(); ++i)
      if (all[i].first == n) found = &all[i].second;
    SignalItem alias{SignalKind::FramePosition, -1, 0};
    if (!found && FrameSignalByAlias(p, n, &alias)) found = &alias;  // any name of a frame
    if (!found) {
      if (error) *error = "unknown signal '" + n + "'";
      return nullptr;
    }
    SignalItem it = *found;
    it.nan = p.options.indeterminate == IndeterminateReactions::NaN && Indeterminate(p, it);
    plan->items.push_back(it);
    switch (it.kind) {
      case SignalKind::Output: plan->outputs = plan->velocity = true; break;
      case SignalKind::KineticEnergy:
      case SignalKind::BodyVelocity:
      case SignalKind::BodyAngVel:
      case SignalKind::FrameVelocity:
      case SignalKind::FrameAngVel: plan->velocity = true; break;
      case SignalKind::PotentialEnergy:
        if (!p.force_tape.roots.empty()) plan->forces = plan->velocity = true;
        break;
      case SignalKind::Drive:
      case SignalKind::JointA:
      case SignalKind::BodyAccel:
      case SignalKind::BodyAngAccel: plan->dynamics = plan->velocity = true; break;
      case SignalKind::Reaction:
      case SignalKind::ConstraintPower: plan->reactions = plan->dynamics = plan->velocity = true; break;
      case SignalKind::Contact:
        if (it.k >= 3 && it.k <= 5) plan->reactions = plan->dynamics = plan->velocity = true;
        break;
      case SignalKind::LoopResidual: plan->drift = plan->drift || it.k == 2; break;
      default: break;
    }
  }
  return plan;
}

// The generalized force a prescription must supply along its speed r so that Kane's
// equation for r holds (Lesser eq. 25 with r not free):
//   drive_r = sum_L tau_{L,r}^T ( Mb_L A_L + [0; w_L x I_L w_L] - [F_L; T_L] ) - Q_r.
double DriveForce(const Program& p, const Workspace& ws, int r) {
  double d = -ws.Q[r];
  for (size_t L = 0; L < p.bodies.size(); ++L) {
    const Vec6 t = TangentColumn(p, ws, static_cast<int>(L), r);
    if (t.squaredNorm() == 0.0) continue;
    const Vec3 f = p.bodies[L].mass * ws.a_bias_cm[L] - ws.F_W[L];
    const Vec3 m = ws.I_W[L] * ws.alpha_bias[L] + ws.w_WB[L].cross(ws.I_W[L] * ws.w_WB[L]) - ws.T_W[L];
    d += t.head<3>().dot(f) + t.tail<3>().dot(m);
  }
  return d;
}

// With closed loops the prescribed speed r also moves the dependent speeds: along the
// admissible direction beta_r = e_r - sum_k x_k e_dep(k), x = A_dep^+ A_r (Lesser
// eq. 51 for a prescribed speed), on which the loop forces do no work:
//   drive_r = G_r - sum_k x_k G_dep(k),   G_s = DriveForce of speed s on the tree.
double LoopDriveForce(const Program& p, Workspace& ws, int r) {
  double d = DriveForce(p, ws, r);
  if (p.rows.empty() || p.loop_rank == 0) return d;
  if (p.solver == SolverPath::Sparse) {
    // The multipliers are known (kane_sparse.cpp eq. 4): G_r = drive_r + (A^T lambda)_r.
    ConstraintColumn(p, ws, r, &ws.vcol);
    return d - ws.vcol.dot(ws.lambda_c);
  }
  ConstraintColumn(p, ws, r, &ws.vcol);
  GatherActive(p, ws.vcol, &ws.active_rhs);
  SolveDependent(ws, ws.active_rhs, &ws.dep_solution);
  for (int k = 0; k < p.loop_rank; ++k)
    d -= ws.dep_solution[k] * DriveForce(p, ws, p.u_free[static_cast<size_t>(ws.dep[static_cast<size_t>(k)])]);
  return d;
}

std::vector<std::string> IndeterminateSignals(const Program& p, const std::vector<std::string>& names) {
  std::vector<std::string> out;
  if (p.redundant_rows.empty()) return out;
  const auto all = AllSignals(p);
  for (const std::string& n : names)
    for (const auto& [name, item] : all)
      if (name == n && Indeterminate(p, item)) out.push_back(n);
  return out;
}

namespace {
// SetHeldLoads' reactions among the applied forces (after AppliedForces): a stop's on its
// speed, a plane's at its contact point (a force on the body, so that the joint reactions
// above it carry it as the plane's, not as a joint's own force).
void AddHeldLoads(const Program& p, Workspace& ws) {
  for (size_t i = 0; i < ws.held_F.size(); ++i) ws.Q[p.u_free[i]] += ws.held_F[i];
  for (const auto& [i, lambda] : ws.held_planes) {
    const PlaneContactModel& c = p.plane_contacts[static_cast<size_t>(i)];
    Vec3 x;
    Mat3 R;
    FramePose(p, ws, c.frame, &x, &R);
    const auto B = static_cast<size_t>(c.body);
    ws.F_W[B] += lambda * c.n_W;
    ws.T_W[B] += (x - ws.p_WBcm[B]).cross(lambda * c.n_W);
  }
}

int EvalSignalsBy(const Program& p, const SignalPlan& plan, Workspace& ws, double t, const double* y, double* out,
                  bool near_change_point) {
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  PositionKinematics(p, ws);
  if (plan.velocity || !p.rows.empty()) VelocityKinematics(p, ws);
  // Closed loops: outputs are evaluated on the constraint manifold, as the right-hand side.
  if (plan.drift) {
    ConstraintResiduals(p, ws);
    ws.phi_drift = ws.phi;
  }
  // Near a change point, the projection of least kinetic energy with a truncated
  // pseudo-inverse instead (runtime/engine/output_rows.h).
  if (near_change_point) {
    if (int s = ProjectRowNearChangePoint(p, ws, plan.dynamics); s != 0) return s;
  } else if (int s = ProjectState(p, ws); s != 0) {
    return s;
  }
  if (plan.dynamics) {
    // The accelerations: the right-hand side's stages, then the body accelerations.
    BiasAccelerations(p, ws);
    if (int s = AppliedForces(p, ws); s != 0) return s;
    AddHeldLoads(p, ws);
    if (int s = SolveAccelerations(p, ws); s != 0) return s;
    for (int k : ws.held_speeds) ws.udot[p.u_free[static_cast<size_t>(k)]] = 0.0;  // held exactly
    BiasAccelerations(p, ws, /*include_free=*/true);
    if (plan.reactions) {
      LoopMultipliers(p, ws);
      JointReactions(p, ws);
    }
  }
  if (plan.forces)
    if (int s = EvalForceTape(p, ws); s != 0) return s;
  if (plan.outputs && !p.output_tape.roots.empty()) {
    const Tape& tape = p.output_tape;
    double* r = ws.output_regs.data();
    if (tape.time_reg >= 0) r[tape.time_reg] = t;
    for (const auto& [in, reg] : tape.input_regs) r[reg] = ws.inputs[static_cast<size_t>(in)];
    EvalStateRefs(p, ws, p.state_refs_outputs);
    for (const auto& [ref, reg] : tape.state_regs) r[reg] = ws.state_values[static_cast<size_t>(ref)];
    tape.Eval(r);
  }
  for (size_t i = 0; i < plan.items.size(); ++i) {
    const SignalItem& it = plan.items[i];
    if (it.nan) {
      out[i] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    double v = 0.0;
    switch (it.kind) {
      case SignalKind::JointQ: v = ws.q[it.a]; break;
      case SignalKind::JointU: v = ws.u[it.a]; break;
      case SignalKind::JointA: v = ws.udot[it.a]; break;
      case SignalKind::Output: {
        v = ws.output_regs[static_cast<size_t>(p.output_tape.roots[static_cast<size_t>(it.a)])];
        if (!std::isfinite(v)) {
          ws.error = "NaN from expression: " + p.output_tape.labels[static_cast<size_t>(it.a)] + " = " +
                     p.output_tape.texts[static_cast<size_t>(it.a)] + " at time " + std::to_string(t);
          return -1;
        }
        break;
      }
      case SignalKind::KineticEnergy:
        // T = sum_L 1/2 m_L |v_Lcm|^2 + 1/2 w_L . I_L w_L
        for (size_t L = 0; L < p.bodies.size(); ++L)
          v += 0.5 * p.bodies[L].mass * ws.v_WBcm[L].squaredNorm() + 0.5 * ws.w_WB[L].dot(ws.I_W[L] * ws.w_WB[L]);
        break;
      case SignalKind::PotentialEnergy:
        // V = -sum_L m_L g . p_WLcm + sum_springs 1/2 k (s - s0)^2
        for (size_t L = 0; L < p.bodies.size(); ++L) v -= p.bodies[L].mass * p.gravity_W.dot(ws.p_WBcm[L]);
        v += SpringEnergy(p, ws);
        break;
      case SignalKind::BodyPosition:
      case SignalKind::BodyVelocity:
      case SignalKind::BodyAngVel:
      case SignalKind::BodyRotation: {
        const BodySignalSource& b = p.body_signals[static_cast<size_t>(it.a)];
        Vec3 pos, vel, w;
        Mat3 R;
        FramePose(p, ws, b.frame, &pos, &R);
        const Vec3 r_cm = R * b.p_FBcm;
        if (it.kind == SignalKind::BodyPosition) v = (pos + r_cm)[it.k];
        if (it.kind == SignalKind::BodyRotation) v = R(it.k / 3, it.k % 3);
        if (it.kind == SignalKind::BodyVelocity || it.kind == SignalKind::BodyAngVel) {
          FrameMotion(p, ws, b.frame, &vel, &w);
          v = it.kind == SignalKind::BodyAngVel ? w[it.k] : (vel + w.cross(r_cm))[it.k];
        }
        break;
      }
      case SignalKind::BodyAccel:
      case SignalKind::BodyAngAccel: v = BodySignalAcceleration(p, ws, it)[it.k]; break;
      case SignalKind::Drive: v = LoopDriveForce(p, ws, it.a); break;
      case SignalKind::Reaction: v = JointReactionInFrameB(p, ws, it.a)[it.k]; break;
      case SignalKind::ConstraintPower: v = ConstraintPower(p, ws); break;
      case SignalKind::Contact: {
        const ContactModel& c = p.contacts[static_cast<size_t>(it.a)];
        if (it.k >= 6) {
          if (it.k == 7) ConstraintJacobian(p, ws);
          const Eigen::VectorXd& r = it.k == 6 ? ws.phi : ws.psi;
          v = it.k == 6 ? std::fabs(r[c.row0]) : r.segment(c.row0, c.nrows).cwiseAbs().maxCoeff();
          break;
        }
        if (it.k < 3) {
          v = ContactAt(p, ws, c).P[it.k];
          break;
        }
        ContactPoint cp;
        const Vec3 F = ContactForce(p, ws, it.a, &cp);
        Vec3 lon, lat;
        ContactDirections(c, cp, &lon, &lat);
        v = F.dot(it.k == 3 ? c.n_W : it.k == 4 ? lon : lat);
        break;
      }
      case SignalKind::LoopResidual: {
        const LoopClosure& l = p.loops[static_cast<size_t>(it.a)];
        const Eigen::VectorXd& r = it.k == 0 ? ws.phi : it.k == 1 ? ws.psi : ws.phi_drift;
        if (it.k == 1) ConstraintJacobian(p, ws);  // psi of the projected speeds
        v = l.nrows > 0 ? r.segment(l.row0, l.nrows).cwiseAbs().maxCoeff() : 0.0;
        break;
      }
      case SignalKind::FramePosition:
      case SignalKind::FrameRotation: {
        Vec3 pos;
        Mat3 R;
        FramePose(p, ws, it.a, &pos, &R);
        v = it.kind == SignalKind::FramePosition ? pos[it.k] : R(it.k / 3, it.k % 3);
        break;
      }
      case SignalKind::FrameVelocity:
      case SignalKind::FrameAngVel: {
        Vec3 vel, w;
        FrameMotion(p, ws, it.a, &vel, &w);
        v = it.kind == SignalKind::FrameVelocity ? vel[it.k] : w[it.k];
        break;
      }
    }
    out[i] = v;
  }
  return 0;
}
}  // namespace

int EvalSignals(const Program& p, const SignalPlan& plan, Workspace& ws, double t, const double* y, double* out) {
  return EvalSignalsBy(p, plan, ws, t, y, out, false);
}

bool RowNearChangePoint(const Program& p, Workspace& ws, double t, const double* y) {
  if (p.loops.empty() || p.loop_rank == 0) return false;
  if (UnpackState(p, ws, t, y) != 0) return false;
  PositionKinematics(p, ws);
  return RowNearChangePoint(p, ws);
}

// Below this rtol the move is measured in units of this one: the integrator's own y is
// off the manifold by some 1e3 units of rtol 1e-12 anywhere.
constexpr double kMoveFloor = 1e-8;

double SpeedMove(const Program& p, const Workspace& ws, const double* y, double rtol, double atol) {
  double m = 0.0;
  for (int s = 0; s < p.nu; ++s) {
    const double raw = y[p.nq + s];
    m = std::max(m, std::abs(ws.u[p.u_free[static_cast<size_t>(s)]] - raw) / (atol + std::max(rtol, kMoveFloor) * std::abs(raw)));
  }
  return m;
}

int EvalSignalsNearChangePoint(const Program& p, const SignalPlan& plan, Workspace& ws, double t, const double* y,
                               double* out) {
  return EvalSignalsBy(p, plan, ws, t, y, out, true);
}

}  // namespace kanesim::rt
