// The compiled program (immutable after Compile) and the per-thread workspace.
//
// Notation (docs/notation.md): bodies L = 0..K-1 in spanning-tree order (a parent before
// its children), ground is body -1. Every quantity is resolved in the world frame W
// unless its name says otherwise. "full" arrays hold all joint coordinates/speeds in tree
// order including prescribed ones; the integrator's y holds only the free ones.
// Per body, linear before angular: a twist is [v; w], a wrench [force; torque].
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "runtime/program/compile_options.h"
#include "flat/mechanism.h"
#include "runtime/program/partition_qr.h"
#include "runtime/program/small_qr.h"
#include "runtime/program/tape.h"

namespace kanesim::rt {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// The cross-product matrix: Skew(v) w = v x w.
inline Mat3 Skew(const Vec3& v) {
  Mat3 K;
  K << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return K;
}

// A number the runtime reads: a folded constant, or a root of the force tape.
struct Scalar {
  double value = 0.0;  // used when root < 0
  int root = -1;       // index into Program::force_tape roots
};

// One articulated joint of the spanning tree; it moves child body `child` relative to
// `parent` (-1 = ground). The child body's frame IS the child-side joint frame.
struct TreeJoint {
  // The fields every right-hand side reads come first (one or two cache lines per joint).
  flat::JointType type = flat::JointType::Revolute;
  flat::RotationCoords rotation = flat::RotationCoords::Quaternion;
  bool inverted = false;  // frame_b is on the parent side: the child moves by X_ab^-1
  // Constants of the hot path, set by PrepareJointConstants (runtime/kinematics/joint_kinematics.h)
  // once the axes and R_PJ are known:
  bool single_axis = false;     // Revolute or Prismatic in tree direction: H = [0; axis] or [axis; 0], no bias
  bool R_PJ_identity = false;   // R_PJ == 1 exactly: R_WJ = R_WP, no product
  int axis_index = -1;          // 0, 1, 2 when axis is exactly +x, +y, +z: a rotation about it turns two columns
  int parent = -1, child = -1;
  int nq = 0, nu = 0;
  int q0 = 0, u0 = 0;  // offsets in the full q / u arrays
  Vec3 p_PJ = Vec3::Zero();    // parent-side joint frame origin in the parent body frame
  Vec3 axis_P = Vec3::UnitZ();  // R_PJ axis: the axis in the parent body's frame (W for a root joint)
  Mat3 R_PJ = Mat3::Identity();
  Vec3 axis = Vec3::UnitZ();   // unit; Revolute/Prismatic/Cylindrical axis, Universal n1, Planar normal
  Mat3 K_axis = Mat3::Zero();   // [axis]x: rotation by a about axis = 1 + sin(a) K + (1 - cos(a)) K^2
  Mat3 K2_axis = Mat3::Zero();  // [axis]x^2
  Vec3 axis2 = Vec3::UnitX();  // unit; Universal n2 (intermediate frame), Planar e1
  Vec3 axis3 = Vec3::UnitY();  // Planar e2 = axis x e1
  // Cardan/Euler joints: which branch between two singular values of the middle angle the
  // motion started in (Cardan: floor((q2 + pi/2) / pi), Euler: floor(q2 / pi)); leaving it
  // means the motion went through gimbal lock. A whole number kept as a double, so that
  // no angle (however large) is ever converted to an int.   filled by BuildStateLayout
  double chart0 = 0.0;
  double mu = 0.0;             // Coulomb friction coefficient (0: none), runtime/kane/friction.cpp
  double mu_radius = 1.0;      // Revolute: pin radius (friction torque = radius x force)
  double mu_v = 1e-3;          // regularization speed scale of tanh(u / mu_v)
  double mu_s = 0.0;           // static coefficient (friction_exact)
  bool friction_exact = false; // exact stick-slip as events (sim/stick_slip.h), not tanh
  double friction_c = 0.0;     // constant Coulomb friction (N m or N), added to mu r N
  double friction_c_s = 0.0;   // its static value (friction_exact), added to mu_s r N
  // End stops (Revolute, Prismatic): q in [q_min, q_max]; -inf / +inf: none on that side.
  double q_min = -std::numeric_limits<double>::infinity();
  double q_max = std::numeric_limits<double>::infinity();
  double restitution = 0.0;    // Newton's coefficient at an impact on a stop, 0..1
  std::string name;
  flat::SourceLoc loc;
  int flat_index = -1;
};

struct TreeBody {
  std::string name;  // first flat body merged into it, else its reference frame's name
  int joint = -1;    // the tree joint whose child it is (== body index)
  double mass = 0.0;
  Vec3 p_BBcm = Vec3::Zero();       // mass centre in the body frame
  Mat3 I_BBcm_B = Mat3::Zero();     // central inertia, body frame
  bool I_diagonal = false;          // I_BBcm_B is diagonal (principal axes along the body's): R I R^T is cheaper
  // Free speed indices of the joints root..L (the pattern of tau for this body). Filled by
  // the compiler only for the bodies that closed loops' frames and contacts sit on (their
  // constraint rows need it at run time); for a chain, every body's list would take
  // O(N^2) memory. PathSpeeds(p, L) computes it for any body.
  std::vector<int> path_speeds;
};


// Where a flat frame sits: in body `body` (-1 = ground) at pose X_BF.
struct FramePlace {
  int body = -2;  // -2: frame not connected to anything the program simulates
  Vec3 p_BF = Vec3::Zero();
  Mat3 R_BF = Mat3::Identity();
};

struct LineForceModel {
  std::string name;
  int frame_a = -1, frame_b = -1;
  Scalar k, d, s0;
};

struct WrenchModel {
  std::string name;
  int frame = -1;
  Scalar force[3], torque[3];
  bool in_world = true;
};

// Flat body as a user sees it, for its signals (`rod1.r[2]`).
struct BodySignalSource {
  std::string name;
  int frame = -1;        // flat frame it is attached to
  Vec3 p_FBcm = Vec3::Zero();
};

// One scalar position constraint of a loop closure (runtime/constraints/constraints.h), between the
// cut joint's frame a (on body A) and frame b (on body B):
//   Translation:  phi = d_W . (p_Wb - p_Wa),    d_W = R_Wa d_a   (a direction fixed in a)
//   Alignment:    phi = e_W . n_W - offset,      e_W = R_Wa e_a, n_W = R_Wb n_b
// Rolling contacts (non-holonomic, runtime/constraints/contacts.cpp): rows on the velocity of the
// body's material point P at the contact,  d . v_P = 0:
//   ContactNormal   d = n (plane normal); also a position constraint n . (P - p0) = 0
//   ContactTangent  d = t1 or t2 (fixed in W): velocity only, never a position constraint
//   ContactLateral  d = n x e_W (knife edge, e the blade): velocity only
// Joint couplings (holonomic, on coordinates): phi = q_f - ratio q_l - offset.
enum class RowKind : std::uint8_t { Translation, Alignment, ContactNormal, ContactTangent, ContactLateral, Coupling };
struct ConstraintRow {
  int loop = -1;                // index into Program::loops (-1 for a contact or coupling row)
  int contact = -1;             // index into Program::contacts (-1 for a loop or coupling row)
  int coupling = -1;            // index into Program::couplings (-1 for a loop or contact row)
  RowKind kind = RowKind::Translation;
  Vec3 d_a = Vec3::UnitX();     // Translation: d; Alignment: e (fixed in frame a, in a's axes)
  Vec3 n_b = Vec3::UnitZ();     // Alignment: n (fixed in frame b, in b's axes)
  Vec3 d_aB = Vec3::UnitX();    // loop rows: d_a in the axes of frame a's body (R_BF d_a; W's for the world)
  Vec3 n_bB = Vec3::UnitZ();    // loop rows: n_b in the axes of frame b's body
  double offset = 0.0;          // Alignment: e . n at a consistent configuration
  std::string what;             // "translation along x", "tilt about e1" (for messages)
};

// A cut joint: the loop closure it stands for (its constrained directions, the
// complement of its motion subspace, become rows row0 .. row0 + nrows - 1).
struct LoopClosure {
  std::string name;
  flat::SourceLoc loc;
  int flat_index = -1;
  int frame_a = -1, frame_b = -1;  // flat frames
  int row0 = 0, nrows = 0;
};

// A rolling contact of a body against a fixed plane (flat::Contact).
struct ContactModel {
  std::string name;
  flat::SourceLoc loc;
  flat::ContactType type = flat::ContactType::RollingDisk;
  int frame = -1;              // flat frame: disk/sphere centre, knife-edge contact point
  int body = -1;               // tree body of that frame
  Vec3 axis_F = Vec3::UnitZ(); // disk axis / blade direction in the frame's axes (unit)
  double radius = 0.0;
  Vec3 n_W = Vec3::UnitY();    // plane normal (unit), world
  Vec3 p0_W = Vec3::Zero();    // a point of the plane, world
  Vec3 t1_W = Vec3::UnitX(), t2_W = Vec3::UnitZ();  // tangent basis of the plane, t1 x t2 = n
  int row0 = 0, nrows = 0;
};

// An exact coupling of two one-coordinate joints (flat::JointCoupling): the row
// phi = q_f - ratio q_l - offset (runtime/constraints/constraints.cpp eq. 11).
struct CouplingModel {
  std::string name;
  flat::SourceLoc loc;
  int leader = -1, follower = -1;  // tree joints (Revolute or Prismatic, q index == u index)
  double ratio = 1.0, offset = 0.0;
  int row = -1;                    // its row in Program::rows
};

// Unilateral contact of a frame's origin O with the fixed plane n . x = d (flat::Contact of
// type Plane, stdlib PlaneContact): gap g = n . p_WO - d >= 0. Not a constraint row: the
// integrators' events handle it (sim/end_stops.h; runtime/engine/plane_contacts.cpp).
struct PlaneContactModel {
  std::string name;
  flat::SourceLoc loc;
  int frame = -1;              // flat frame whose origin touches the plane
  int body = -1;               // tree body of that frame (path_speeds filled)
  Vec3 n_W = Vec3::UnitY();    // unit normal, world; the free side is n . x > d
  double d = 0.0;              // plane offset (m)
  double restitution = 0.0;    // Newton's coefficient, 0..1
};

// The sparse K-vector system: unknowns and equations per body L in blocks of 12:
// x = [a_cm (3), alpha (3), udot_free_j (nf), s_j (6 - nf)], rows = [kinematic (6), Newton-Euler (6)].
struct SparsePattern;  // defined in kane_sparse.cpp
struct SparseSymbolic;  // KLU symbolic analysis, shared by all workspaces of a program
void DestroySparseSymbolic(SparseSymbolic* s);
struct TreeLayout;  // the recursive path's per-joint blocks, defined in kane_tree.h

// "[k+1]": a 1-based index suffix as the language writes it. Built by appending because
// GCC 12 at -O3 reports a false -Wrestrict for "literal" + std::string&&.
inline std::string Index1(int k) {
  std::string s = "[";
  s.append(std::to_string(k + 1)).append("]");
  return s;
}

// A when clause (flat::WhenClause; compiler/whens.cpp, docs/events.md).
struct WhenReinit {
  int state = -1;      // its index in y = [q_free; u_free]
  bool speed = false;  // a free speed (set through the mass matrix), else a coordinate
  int root = -1;       // its value: a root of Program::event_tape
  std::string name;    // "j.u", "ball.q[3]"
};
struct WhenModel {
  std::vector<int> indicators;  // roots of Program::event_tape; it fires where one crosses zero upwards
  std::vector<WhenReinit> reinits;
  bool terminate = false;
  std::string message;  // terminate's
  std::string name;     // for the events log: "when (file.mech:12)"
};

struct Program {
  std::shared_ptr<const flat::Mechanism> mech;  // kept for Rebind and names
  std::vector<double> param_values;
  CompileOptions options;

  std::vector<TreeBody> bodies;   // K
  std::vector<TreeJoint> joints;  // K (joint L moves body L)
  std::vector<int> joint_of_flat; // flat joint index -> tree joint, -1 for welds
  std::vector<FramePlace> frames; // one per flat frame
  int world_frame = -1;
  Vec3 gravity_W = Vec3::Zero();
  bool has_gravity = false;

  int nq_all = 0, nu_all = 0;  // full coordinates / speeds
  int nq = 0, nu = 0;          // free
  std::vector<int> q_free;     // full index of free coordinate i
  std::vector<int> u_free;     // full index of free speed i
  std::vector<int> u_free_of;  // full speed index -> free index or -1 (prescribed)
  std::vector<int> joint_of_speed;  // full speed index -> tree joint
  std::vector<int> q_prescribed;       // full q indices that are prescribed (q index == scalar u)
  std::vector<int> prescribed_u;       // matching full u indices
  Tape prescribed_tape;                // roots aligned with q_prescribed; time only
  std::vector<double> y0;              // initial state

  std::vector<Scalar> joint_tau;       // per full speed (value 0 when none)
  std::vector<LineForceModel> line_forces;
  std::vector<WrenchModel> wrenches;
  Tape force_tape;                     // joint tau, wrench and line force expressions
  Tape output_tape;                    // declared outputs (roots aligned with mech->outputs)
  std::vector<int> state_refs_forces;  // mech state refs the force tape reads
  std::vector<int> state_refs_outputs; // mech state refs the output tape reads
  std::vector<WhenModel> whens;        // when clauses; empty: none (no event machinery for them)
  Tape event_tape;                     // their indicators and reinit values
  std::vector<int> state_refs_events;  // mech state refs the event tape reads
  std::vector<BodySignalSource> body_signals;

  SolverPath solver = SolverPath::Dense;
  Integrator integrator = Integrator::CvodeAdams;
  std::string solver_reason, integrator_reason;
  std::vector<std::string> notes;
  int grubler_dof = 0;

  // Closed loops (runtime/constraints/constraints.h). Empty for trees.
  std::vector<LoopClosure> loops;       // one per cut joint
  std::vector<ContactModel> contacts;   // rolling contacts and knife edges
  std::vector<CouplingModel> couplings; // joint couplings, one row each
  std::vector<ConstraintRow> rows;      // n_c constraints: loops' rows, then contacts', then couplings'
  int loop_rank = 0;                    // rank of the constraint Jacobian (free speeds) at the assembled start
  double loop_length = 1.0;             // length scale of the position tolerance (m)
  int dof = 0;                          // nu - loop_rank
  bool reduce_by_passes = false;        // reduced equations by velocity passes (constraints.h PassesCheaper)
  std::vector<int> redundant_rows;      // rows pivoted QR of A^T leaves out at the assembled start  (n_c - rank)
  // The rows the reduced path's projection and equations use (rows of ws.A, in order):
  // every row during assembly, then the independent ones (redundant rows left out: they
  // hold with the others), unless the minimum-norm share of the multipliers is needed
  // (--reactions min-norm, friction reading an indeterminate normal force).
  std::vector<int> active_rows;
  std::vector<int> active_of_row;       // row -> its index in active_rows, or -1
  // Statically indeterminate constraint-force components (the multipliers' null space
  // moves them), decided at the assembled start by FindIndeterminateReactions:
  std::vector<std::uint8_t> reaction_indeterminate;  // per flat joint, bit k: reaction component k (0-2 force, 3-5 torque)
  std::vector<std::uint8_t> contact_indeterminate;   // per contact, bit k: 0 normal, 1 longitudinal, 2 lateral force
  std::vector<int> friction_indeterminate;  // tree joints whose Coulomb friction reads an indeterminate normal force
  std::vector<int> friction_joints;     // tree joints with Coulomb friction (runtime/kane/friction.cpp)
  std::vector<int> stop_joints;         // tree joints with an end stop (q_min or q_max); empty: no events
  std::vector<PlaneContactModel> plane_contacts;  // stdlib PlaneContact; empty: no events
  // Start speeds given non-zero that the assembly's velocity projection changed (warning
  // W315, compiler/compiler.h StartSpeedsWarning): the message ("" when none) and the place of the
  // constraint with the largest start residual.
  std::string start_speeds_changed;
  flat::SourceLoc start_speeds_loc;
  // Joints that cannot move because both their frames are on one rigid body (the world,
  // or bodies merged by welds and fixed elements; warning W316, compiler/compiler.h
  // LockedJointWarnings): they add neither a speed nor a constraint row.
  struct LockedJoint {
    std::string name;
    flat::SourceLoc loc;
    std::string body;                                          // "the world" or "body 'rod'"
    std::vector<std::pair<flat::SourceLoc, std::string>> by;  // the welds that lock it
  };
  std::vector<LockedJoint> locked_joints;

  std::shared_ptr<const SparsePattern> sparse;            // pattern (sparse path only)
  std::shared_ptr<SparseSymbolic> sparse_symbolic;        // shared across Rebind
  std::shared_ptr<const TreeLayout> tree;                 // per-joint blocks (recursive path only)
};

// Free speed indices of the joints root..L of body L, in that order (the pattern of its
// tangent basis; allocates, so not for the hot path).
std::vector<int> PathSpeeds(const Program& p, int body);

// Per-thread mutable data, allocated once by MakeWorkspace. Nothing here is resized by
// Derivative or EvalSignals.
struct SparseNumeric;  // KLU numeric factorization, one per workspace
void DestroySparseNumeric(SparseNumeric* s);
struct SparseNumericDeleter {
  void operator()(SparseNumeric* s) const { DestroySparseNumeric(s); }
};

// The model's inputs as functions of time (runtime/runtime.h "inputs"): a table
// (sim/input_table.h), or constants that a caller changes between steps.
class InputSource {
 public:
  virtual ~InputSource() = default;
  // u (NumInputs) and du/dt at t; 0, or -1 with *error (a time outside a table).
  virtual int Values(double t, double* u, double* du_dt, std::string* error) const = 0;
};

struct Workspace {
  double t = 0.0;                   // time of the last evaluation  ()  filled by UnpackState
  bool step_projection = false;     // the solver projects its steps (runtime/runtime.h SetStepProjection)
  const double* added_forces = nullptr;  // DerivativeWithForces' forces on the free speeds (nu), else null
  const double* added_plane_forces = nullptr;  // DerivativeWithPlaneForces' normal forces (one per plane contact), else null
  bool newton_to_round_off = false;  // position Newton to round-off below a pivot ratio of 0.5 for every block size (the branch monitor's bridge)
  Eigen::VectorXd q, u;             // full coordinates, speeds  (nq_all), (nu_all)  filled by UnpackState
  Eigen::VectorXd udot;             // full accelerations; prescribed ones from the jet (nu_all)  filled by UnpackState/Solve*
  Eigen::VectorXd qdot;             // full coordinate rates  (nq_all)  filled by KinematicDifferentials/UnpackState

  std::vector<Mat3> R_WB;           // body orientation  (K)  filled by PositionKinematics
  std::vector<Vec3> p_WB;           // body frame origin = child joint point o_L  (K)  filled by PositionKinematics
  std::vector<Vec3> p_WBcm;         // mass centre  (K)  filled by PositionKinematics
  std::vector<Mat3> I_W;            // central inertia resolved in W  (K)  filled by PositionKinematics
  std::vector<Mat3> R_ab;           // joint relative rotation  (K)  filled by PositionKinematics (not for revolute joints about a coordinate axis)
  std::vector<Vec3> p_ab;           // joint relative position, in a  (K)  filled by PositionKinematics (the same)
  Eigen::Matrix<double, 6, Eigen::Dynamic> H_W;  // twist per full speed at o_L: tangent generators  (6 x nu_all)  filled by VelocityKinematics
  std::vector<Vec3> w_WB;           // angular velocity  (K)  filled by VelocityKinematics
  std::vector<Vec3> v_WBo;          // velocity of body origin  (K)  filled by VelocityKinematics
  std::vector<Vec3> v_WBcm;         // velocity of mass centre  (K)  filled by VelocityKinematics
  std::vector<Vec3> w_rel, v_rel;   // joint relative twist at o_L, seen from the parent  (K)  filled by VelocityKinematics
  std::vector<Vec3> alpha_rel, a_rel;  // its derivative in the parent with udot = 0  (K)  filled by VelocityKinematics (0 for single_axis joints)
  std::vector<Vec3> alpha_bias;     // angular acceleration with free udot = 0  (K)  filled by BiasAccelerations
  std::vector<Vec3> a_bias_o;       // origin acceleration with free udot = 0  (K)  filled by BiasAccelerations
  std::vector<Vec3> a_bias_cm;      // mass-centre acceleration with free udot = 0  (K)  filled by BiasAccelerations

  std::vector<double> state_values;  // mech state refs in use  (mech.state_refs)  filled by EvalStateRefs
  std::vector<double> force_regs;    // force tape registers  filled by EvalForceTape
  std::vector<double> output_regs;   // output tape registers  filled by EvalSignals
  std::vector<double> event_regs;    // event tape registers  filled by EvalEventTape
  std::vector<double> jet_regs;      // prescribed tape jets (3 per register)  filled by UnpackState

  std::vector<Vec3> F_W;            // applied force at the mass centre  (K)  filled by AppliedForces
  std::vector<Vec3> T_W;            // applied torque about the mass centre  (K)  filled by AppliedForces
  Eigen::VectorXd Q;                // joint generalized forces  (nu_all)  filled by AppliedForces

  // Dense path.
  Eigen::MatrixXd M;                // mass matrix tau^T Mb tau, lower triangle  (nu x nu)  filled by SolveDense
  Eigen::VectorXd f;                // right side tau^T (F - M a_bias)  (nu)  filled by SolveDense
  // Factorizations sized once (emplaced: Eigen leaves their status uninitialized, so
  // they are never copied).
  std::optional<Eigen::LLT<Eigen::MatrixXd>> llt;    // Cholesky of M  filled by SolveDense
  std::optional<Eigen::LDLT<Eigen::MatrixXd>> ldlt;  // fallback  filled by SolveDense
  std::vector<Mat6> Ic;             // composite spatial inertia of the subtree about o_L  (K)  filled by SolveDense, MassMatrix
  Eigen::MatrixXd M_full;           // mass matrix on any path, lower triangle  (nu x nu)  filled by MassMatrix
  std::vector<Vec6> Wc;             // composite wrench of the subtree about o_L  (K)  filled by SolveDense

  // Sparse path.
  std::vector<double> Ax;           // CSC values  (nnz)  filled by SolveSparse
  std::vector<double> x;            // right side, then solution  (12 K)  filled by SolveSparse
  std::vector<double> b, r;         // right side kept, residual for refinement  (12 K)  filled by SolveSparse
  std::vector<Vec6> lambda_W;       // joint reaction wrench on the child at o_L  (K)  filled by SolveSparse
  std::vector<Eigen::Matrix<double, 6, 6>> D_W;  // complement basis per joint (first 6-nf cols)  (K)  filled by FactorSparse
  std::vector<Vec6> row_J;          // per kept constraint row, its two body Jacobians (as RowJacobians)  (2 m)  filled by FactorSparse
  std::vector<int> sparse_rows;     // multiplier -> constraint row: SparsePattern::kept_rows, a loop's re-chosen among its rows  (m)  filled by FactorSparse
  bool sparse_ready = false;        // the factorization is of the current positions  set by FactorSparse, cleared by UnpackState
  double sparse_rcond = 0.0;        // KLU's pivot-ratio estimate of the last factorization  filled by FactorSparse
  std::unique_ptr<SparseNumeric, SparseNumericDeleter> klu;

  // Recursive path (runtime/kane/kane_tree.cpp).
  std::vector<Mat6> tree_Ia;        // children's shares moved to o_L (those not handed on in registers, see SolveTree), for a general joint then body L's inertia added: articulated inertia; B and the upper triangles of A, C only (kBlocks in kane_tree.cpp)  (K)  filled by SolveTree
  std::vector<Vec6> tree_pa;        // the same for the bias wrenches: articulated bias wrench  (K)  filled by SolveTree
  std::vector<Vec6> tree_A;         // udot-dependent acceleration [a_o; alpha] of body L  (K)  filled by SolveTree
  Eigen::VectorXd tree_U;           // U_L = Ia_L S_L, then X_LP^T U_L for a non-root joint; 6 x nf column-major at 6 f0  (6 nu)  filled by SolveTree
  Eigen::VectorXd tree_Dinv;        // D_L^-1 = (S_L^T U_L)^-1, nf x nf at d0  (sum nf^2)  filled by SolveTree
  Eigen::VectorXd tree_u;           // Q_L - S_L^T pa_L at f0  (nu)  filled by SolveTree
  std::vector<std::array<double, 12>> tree_plane;  // planar recursion (SolveTreePlanar): a child's share (Ia 6, pa 3 in plane coordinates) in 0..8, A of body L in 9..11  (K)  filled by SolveTreePlanar

  // Closed loops (runtime/constraints/constraints.cpp); sized n_c = p.rows.size(), nu = p.nu.
  Eigen::VectorXd phi;              // position residuals  (n_c)  filled by ProjectState
  Eigen::VectorXd phi_drift;        // phi of the integrator's state before projection  (n_c)  filled by EvalSignals
  Eigen::VectorXd psi;              // velocity residuals A u + b  (n_c)  filled by ProjectState
  Eigen::VectorXd cbias;            // acceleration residuals with free udot = 0  (n_c)  filled by SolveConstrained
  Eigen::MatrixXd A;                // constraint Jacobian on the free speeds, active rows  (n_a x nu)  filled by ConstraintJacobian
  Eigen::MatrixXd A_dep;            // columns of A for the dependent speeds  (n_a x rank)  filled by ProjectState
  PartitionQR qr_A;                 // partition choice (pivoting QR of A, Eigen's rule on A's profile)  filled by ProjectState
  SmallQR qr_dep;                   // A_dep = Q R  filled by ProjectState
  std::vector<int> dep, ind;        // free speed indices: dependent (rank), independent (nu - rank)  filled by ProjectState
  bool partition_valid = false;     // dep/ind chosen  set by ProjectState
  bool dep_banded = false;          // dep is in the banded order (BandedOrder), not the pivoting one  set by FactorDependent
  std::vector<int> col_rows;        // per free speed: first and last active row it can move (structural), 2 s and 2 s + 1, for the banded order of the dependent speeds  (2 nu)  filled by InitConstraintWorkspace
  std::vector<int> order_scratch;   // the pivoting order of the dependent speeds, then column extents of the symbolic QR  (3 rank)  filled by FactorDependent
  long partition_changes = 0;       // how often the partition was re-chosen  filled by ProjectState
  bool hold_partition = false;      // keep dep/ind even where degraded (difference-quotient Jacobians: HoldPartition)  set by HoldPartition
  double turn_checked = INFINITY;   // the kept block's pivot ratio when pivoting last found no block twice as good (a turning-point check; INFINITY: none since the partition was chosen or recovered)  set by FactorDependent
  Eigen::VectorXd active_rhs;       // right side v of SolveDependent: a per-row vector on the active rows  (n_a)  filled by its callers
  Eigen::VectorXd dep_solution;     // x = A_dep^+ v of SolveDependent; x(0:rank) on the dependent speeds  (n_a)  filled by SolveDependent's callers
  Eigen::VectorXd lambda_active;    // constraint multipliers on the active rows, Q [w; 0]  (n_a)  filled by LoopMultipliers
  Eigen::VectorXd vcol;             // a column of the constraint Jacobian, every row  (n_c)  filled by ConstraintColumn's callers
  Eigen::VectorXd du_full;          // a step in full speeds  (nu_all)  filled by ProjectState
  Eigen::MatrixXd beta;             // constrained basis in free-speed space  (nu x nind)  filled by SolveConstrained
  Eigen::MatrixXd MB;               // M beta  (nu x nind)  filled by SolveConstrained
  Eigen::MatrixXd Mr;               // beta^T M beta, lower triangle  (nind x nind)  filled by SolveConstrained
  Eigen::VectorXd fr, udot_p;       // reduced right side (nind), particular udot (nu)  filled by SolveConstrained
  std::optional<Eigen::LLT<Eigen::MatrixXd>> llt_r;  // Cholesky of Mr  filled by SolveConstrained
  Eigen::Matrix<double, 6, Eigen::Dynamic> beta_twists;  // twist of body L at o_L for u = beta column c, at column L nind + c  (6 x K nind)  filled by SolveConstrained (ReducedByPasses)
  std::vector<Vec6> accel_p;        // acceleration [a_o; alpha] of body L from udot_p alone  (K)  filled by SolveConstrained (ReducedByPasses)

  // Constraint forces on request (runtime/constraints/reactions.cpp); not touched by Derivative.
  Eigen::VectorXd lambda_c;         // loop multipliers, A^T lambda = M udot - f  (n_c)  filled by LoopMultipliers
  Eigen::VectorXd g_dep;            // (M udot - f) at the dependent speeds  (n_c)  filled by LoopMultipliers
  std::vector<Vec6> reaction_W;     // wrench of the parent side on subtree L at o_L  (K)  filled by JointReactions
  std::vector<double> friction_tau; // friction force per friction joint, last converged  (nfric)  filled by SolveWithFriction
  std::vector<double> friction_Q0;  // the joint's applied force without friction  (nfric)  filled by SolveWithFriction
  long friction_iterations = 0;     // fixed-point iterations so far  filled by SolveWithFriction
  long derivatives = 0;                   // Derivative's evaluations so far (rt::Counts)
  long inverse_mass_factorizations = 0;  // InverseMassColumns' factorizations so far (rt::Counts)
  Eigen::LLT<Eigen::MatrixXd> inverse_mass_llt;  // InverseMassColumns' last factor of M  filled by InverseMassColumns
  std::vector<double> inverse_mass_at;            // its (t, q), empty: none
  // Columns of M^-1 solved from that factor, column k at k nu  (nu x nu)  filled by InverseMassColumns
  std::vector<double> inverse_mass_cols;
  std::vector<char> inverse_mass_known;  // column k of inverse_mass_cols solved for this factor  (nu)
  std::vector<double> inverse_mass_M;     // the M factored, column-major  (nu x nu)  filled by InverseMassColumns
  // The law per friction joint (SetFrictionMode): 0 tanh(u / v), +1 / -1 sliding that way,
  // 2 the force friction_fixed (stuck)  (nfric)  set by sim/stick_slip.cpp
  std::vector<int> friction_mode;
  std::vector<double> friction_fixed;  // mode 2's force  (nfric)
  std::vector<double> friction_N;      // normal force N of the last solve  (nfric)  filled by SolveWithFriction
  // Held contacts' reactions, read by EvalSignals only (runtime/runtime.h SetHeldLoads): generalized
  // forces on the free speeds (nu; empty: none), plane contacts' normal forces, held speeds' indices.
  std::vector<double> held_F;
  std::vector<std::pair<int, double>> held_planes;
  std::vector<int> held_speeds;

  std::string error;                // why the last call failed  filled by Derivative/EvalSignals
  std::vector<double> inputs;       // the model's inputs at t  (mech.inputs)  filled by UnpackState (input_source) or SetInputValues
  std::vector<double> input_rates;  // their time derivatives, for prescribed motions' jets  (mech.inputs)  filled likewise
  const InputSource* input_source = nullptr;  // inputs as functions of time; null: the constants in `inputs`
};

}  // namespace kanesim::rt
