// The right-hand side as a list of named stages (MuJoCo's mj_forward shape), and the
// small public accessors of runtime/runtime.h.
#include "runtime/runtime.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "runtime/constraints/constraints.h"
#include "runtime/engine/branch_monitor_internal.h"  // AddPlaneForces
#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"

namespace kanesim::rt {

namespace {

// A NaN is recoverable (> 0), not fatal: a stage of a long step may probe past the point
// where the model turns NaN (sqrt(0.35 - time) evaluated at 0.4), and the solver must
// then retry shorter, keeping every row before that point; a NaN that persists ends the
// run there with this cause (sim/integrator.h, GuardedRhs).
int NotFinite(const Program& p, Workspace& ws, int free_speed) {
  const int r = p.u_free[static_cast<size_t>(free_speed)];
  const TreeJoint& j = p.joints[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(r)])];
  ws.error = "NaN in the equations of motion at time " + std::to_string(ws.t) + " (acceleration of joint '" +
             j.name + "' u[" + std::to_string(r - j.u0 + 1) + "])";
  return 1;
}

// Closed loops: the right-hand side is evaluated at the projection (q*, u*) of y onto
// the constraints, so the exact solution never leaves them; the integrator's own y
// would still wander off by its local errors. A relaxation term that vanishes on the
// manifold pulls it back (docs/constraints.md, "drift"):
//   ydot = f(q*, u*) + k_drift (y* - y)                                             (1)
// with k_drift (1/s) slow enough to add no stiffness to an explicit or Adams method.
constexpr double kDriftRate = 10.0;

void PullToManifold(const Program& p, const Workspace& ws, const double* y, double* ydot) {
  for (int i = 0; i < p.nq; ++i) ydot[i] += kDriftRate * (ws.q[p.q_free[static_cast<size_t>(i)]] - y[i]);
  for (int i = 0; i < p.nu; ++i)
    ydot[p.nq + i] += kDriftRate * (ws.u[p.u_free[static_cast<size_t>(i)]] - y[p.nq + i]);
}

}  // namespace

namespace {
int SolvePath(const Program& p, Workspace& ws) {
  if (!p.rows.empty() && p.solver != SolverPath::Sparse) return SolveConstrained(p, ws);
  switch (p.solver) {
    case SolverPath::Sparse: return SolveSparse(p, ws);
    case SolverPath::Recursive: return SolveTree(p, ws);
    default: return SolveDense(p, ws);
  }
}
}  // namespace

int SolveAccelerations(const Program& p, Workspace& ws) {
  if (p.friction_joints.empty()) return SolvePath(p, ws);
  return SolveWithFriction(p, ws, SolvePath);
}

// ydot = [qdot_free; udot_free]:
//   positions -> velocities (tangent generators) -> [closed loops: projection onto the
//   constraints] -> qdot = N(q) u -> bias accelerations -> applied forces -> Kane's
//   equations M udot = f (dense, sparse, recursive, or reduced on the constrained basis).
int Derivative(const Program& p, Workspace& ws, double t, const double* y, double* ydot) {
  ++ws.derivatives;
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  const bool step_projection = ws.step_projection && StepProjectionAvailable(p);
  if (p.rows.empty() || step_projection) {
    // A tree, or a solver that projects its steps: q and u are taken as they are, and the
    // kinematics is one pass. (Hairer, Lubich & Wanner, sec. IV.4, algorithm 4.2: the
    // ODE of the reduced equations, the accepted step projected by ProjectOntoConstraints.)
    MotionKinematics(p, ws);
    if (int s = KinematicDifferentials(p, ws); s != 0) return s;
    if (int s = FactorConstraintsAsIs(p, ws); s != 0) return s;
  } else {
    PositionKinematics(p, ws);
    VelocityKinematics(p, ws);
    if (int s = ProjectState(p, ws); s != 0) return s;
    if (int s = KinematicDifferentials(p, ws); s != 0) return s;
    BiasAccelerations(p, ws);
  }
  if (int s = AppliedForces(p, ws); s != 0) return s;
  if (ws.added_forces)
    for (int i = 0; i < p.nu; ++i) ws.Q[p.u_free[static_cast<size_t>(i)]] += ws.added_forces[i];
  if (ws.added_plane_forces) AddPlaneForces(p, ws, ws.added_plane_forces);
  if (int s = SolveAccelerations(p, ws); s != 0) return s;
  for (int i = 0; i < p.nq; ++i) ydot[i] = ws.qdot[p.q_free[static_cast<size_t>(i)]];
  for (int i = 0; i < p.nu; ++i) {
    const double a = ws.udot[p.u_free[static_cast<size_t>(i)]];
    if (!std::isfinite(a)) return NotFinite(p, ws, i);
    ydot[p.nq + i] = a;
  }
  if (!p.rows.empty() && !step_projection) PullToManifold(p, ws, y, ydot);
  return 0;
}

bool StepProjectionAvailable(const Program& p) { return !p.rows.empty() && p.solver != SolverPath::Sparse; }

void SetStepProjection(Workspace& ws, bool on) { ws.step_projection = on; }

void HoldPartition(Workspace& ws, bool on) { ws.hold_partition = on; }

bool ProjectedStates(const Program& p, const Workspace& ws, std::vector<int>* states, double* diag) {
  states->clear();
  *diag = -kDriftRate;
  if (p.rows.empty() || p.loop_rank == 0 || p.solver == SolverPath::Sparse || ws.step_projection || !ws.partition_valid)
    return false;
  std::vector<char> dep(static_cast<size_t>(p.nu), 0);
  for (int s : ws.dep) dep[static_cast<size_t>(s)] = 1;
  std::vector<int> q_free_of(static_cast<size_t>(p.nq_all), -1);
  for (int i = 0; i < p.nq; ++i) q_free_of[static_cast<size_t>(p.q_free[static_cast<size_t>(i)])] = i;
  for (const TreeJoint& j : p.joints) {
    if (j.nq != j.nu || j.nu == 0) continue;
    bool all = true;
    for (int k = 0; k < j.nu && all; ++k) {
      const int f = p.u_free_of[static_cast<size_t>(j.u0 + k)];
      all = f >= 0 && dep[static_cast<size_t>(f)] != 0 && q_free_of[static_cast<size_t>(j.q0 + k)] >= 0;
    }
    if (!all) continue;
    for (int k = 0; k < j.nq; ++k) states->push_back(q_free_of[static_cast<size_t>(j.q0 + k)]);
  }
  for (int s = 0; s < p.nu; ++s)
    if (dep[static_cast<size_t>(s)]) states->push_back(p.nq + s);
  std::sort(states->begin(), states->end());
  return true;
}

int ProjectOntoConstraints(const Program& p, Workspace& ws, double t, double* y) {
  if (p.rows.empty()) return 0;
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  if (int s = ProjectState(p, ws); s != 0) return s;
  PackState(p, ws, y);
  return 0;
}

int MassMatrix(const Program& p, Workspace& ws, double t, const double* y, double* M) {
  if (!p.rows.empty()) {
    ws.error = "the mass matrix of the free speeds is available for trees only (closed loops and contacts: TODO(#44))";
    return -1;
  }
  return UnconstrainedMassMatrix(p, ws, t, y, M);
}

int UnconstrainedMassMatrix(const Program& p, Workspace& ws, double t, const double* y, double* M) {
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  Eigen::Map<Eigen::MatrixXd> out(M, p.nu, p.nu);
  // Zeroed once: AssembleMass writes only the entries of joints on one path to the root.
  if (ws.M_full.rows() != p.nu) ws.M_full.setZero(p.nu, p.nu);
  AssembleMass(p, ws, &ws.M_full);
  out = ws.M_full.selfadjointView<Eigen::Lower>();
  return 0;
}

const std::string& ErrorMessage(const Workspace& ws) { return ws.error; }

std::unique_ptr<Workspace, void (*)(Workspace*)> MakeWorkspace(const Program& p) {
  std::unique_ptr<Workspace, void (*)(Workspace*)> w(new Workspace, [](Workspace* x) { delete x; });
  Workspace& ws = *w;
  const size_t K = p.bodies.size();
  ws.q = Eigen::VectorXd::Zero(p.nq_all);
  ws.u = Eigen::VectorXd::Zero(p.nu_all);
  ws.udot = Eigen::VectorXd::Zero(p.nu_all);
  ws.qdot = Eigen::VectorXd::Zero(p.nq_all);
  ws.R_WB.assign(K, Mat3::Identity());
  ws.R_ab.assign(K, Mat3::Identity());
  ws.I_W.assign(K, Mat3::Zero());
  for (auto* v : {&ws.p_WB, &ws.p_WBcm, &ws.p_ab, &ws.w_WB, &ws.v_WBo, &ws.v_WBcm, &ws.w_rel, &ws.v_rel,
                  &ws.alpha_rel, &ws.a_rel, &ws.alpha_bias, &ws.a_bias_o, &ws.a_bias_cm, &ws.F_W, &ws.T_W})
    v->assign(K, Vec3::Zero());
  ws.H_W = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, p.nu_all);
  ws.state_values.assign(p.mech->state_refs.size(), 0.0);
  ws.inputs.assign(p.mech->inputs.size(), 0.0);
  ws.input_rates.assign(p.mech->inputs.size(), 0.0);
  ws.force_regs = p.force_tape.init;
  ws.output_regs = p.output_tape.init;
  ws.event_regs = p.event_tape.init;
  ws.jet_regs.assign(3 * p.prescribed_tape.init.size(), 0.0);
  for (size_t i = 0; i < p.prescribed_tape.init.size(); ++i) ws.jet_regs[3 * i] = p.prescribed_tape.init[i];
  ws.Q = Eigen::VectorXd::Zero(p.nu_all);
  ws.Ic.assign(K, Mat6::Zero());  // every path: MassMatrix uses them
  if (p.solver == SolverPath::Dense) {
    ws.M = Eigen::MatrixXd::Zero(p.nu, p.nu);
    ws.f = Eigen::VectorXd::Zero(p.nu);
    ws.llt.emplace(p.nu);
    ws.ldlt.emplace(p.nu);
    ws.Wc.assign(K, Vec6::Zero());
  } else if (p.solver == SolverPath::Recursive) {
    InitTreeWorkspace(p, ws);
  } else {
    InitSparseWorkspace(p, ws);
  }
  InitConstraintWorkspace(p, ws);
  ws.friction_tau.assign(p.friction_joints.size(), 0.0);
  ws.friction_Q0.assign(p.friction_joints.size(), 0.0);
  ws.friction_mode.assign(p.friction_joints.size(), 0);
  ws.friction_fixed.assign(p.friction_joints.size(), 0.0);
  ws.friction_N.assign(p.friction_joints.size(), 0.0);
  ws.error.reserve(256);
  // Warm-up at the initial state: the sparse path's first KLU factorization allocates,
  // so it happens here and Derivative only refactors (an error here is reported by the
  // integrator's first call instead).
  if (p.solver == SolverPath::Sparse && StateSize(p) >= 0) {
    std::vector<double> y(p.y0), ydot(p.y0.size());
    Derivative(p, ws, StartTime(p), y.data(), ydot.data());
    ws.error.clear();
  }
  return w;
}

int StateSize(const Program& p) { return p.nq + p.nu; }
int NumQ(const Program& p) { return p.nq; }
int NumU(const Program& p) { return p.nu; }
int NumInputs(const Program& p) { return static_cast<int>(p.mech->inputs.size()); }
const std::string& InputName(const Program& p, int i) { return p.mech->inputs[static_cast<size_t>(i)].name; }
void SetInputSource(Workspace& ws, const InputSource* source) { ws.input_source = source; }
void SetInputValues(Workspace& ws, const double* u) {
  ws.input_source = nullptr;
  std::copy(u, u + ws.inputs.size(), ws.inputs.begin());
  std::fill(ws.input_rates.begin(), ws.input_rates.end(), 0.0);
}
double StartTime(const Program& p) { return p.mech->experiment.start_time; }

void InitialState(const Program& p, double* y) {
  for (size_t i = 0; i < p.y0.size(); ++i) y[i] = p.y0[i];
}

ProgramSummary Summarize(const Program& p) {
  ProgramSummary s;
  s.num_bodies = static_cast<int>(p.bodies.size());
  s.num_joints = static_cast<int>(p.joints.size());
  s.nq = p.nq;
  s.nu = p.nu;
  s.dof = p.rows.empty() ? p.nu : p.dof;
  for (const LoopClosure& l : p.loops) s.cut_joints.push_back(l.name);
  s.grubler_dof = p.grubler_dof;
  s.solver = p.solver;
  s.integrator = p.integrator;
  s.solver_reason = p.solver_reason;
  s.integrator_reason = p.integrator_reason;
  s.notes = p.notes;
  if (!p.rows.empty() && p.solver != SolverPath::Sparse) {
    const std::string limit = std::to_string(kPassesMaxDof) + " degrees of freedom";
    s.equations = p.reduce_by_passes
                      ? "by velocity passes: one per degree of freedom gives the bodies' partial twists on the "
                        "constrained basis (up to " + limit + ", where it is cheaper than the mass matrix)"
                      : "through the composite mass matrix, reduced on the constrained basis (above " + limit +
                            ", where it is cheaper than one velocity pass per degree of freedom)";
  }
  if (!p.q_prescribed.empty())
    s.notes.push_back(std::to_string(p.q_prescribed.size()) + " prescribed coordinate(s) removed from the state");
  return s;
}

}  // namespace kanesim::rt
