// The flat mechanism: what elaboration hands to the compiler. No language is left in it
// (no classes, modifiers, imports or connect statements), only frames, primitives and
// scalar expressions over parameters, time and state. See docs/notation.md and
// DESIGN.md ("Pipeline and layout").
//
// Conventions (used by every consumer; do not change one side alone):
// - Vectors are resolved in the frame the field's comment names; indices in names are
//   1-based like the language (`j.q[1]`), indices in code 0-based.
// - A joint moves frame_b relative to frame_a. Its relative pose is p_ab (origin of b
//   from origin of a, resolved in a) and R_ab (columns: b's axes resolved in a).
// - Generalized speeds: for 1-dof joints and Cylindrical/Universal/Planar, u = dq/dt.
//   For Spherical and the rotational part of FreeMotion, u is the angular velocity of b
//   relative to a resolved in b (body-fixed); the translational part of FreeMotion is
//   u = d(p_ab)/dt resolved in a. Coordinates are [translation..., rotation...].
// - Every numeric field is an ExprId so that numeric parameters can change (sweeps)
//   without elaborating again; the compiler folds them with the parameter values.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "flat/expr.h"
#include "flat/file_name.h"

namespace kanesim::flat {

struct SourceLoc {
  FileName file;     // path as given, or "<stdlib>/Joints.mech" for the standard library
  int line = 0;      // 1-based; 0 = unknown
  int col = 0;       // 1-based
};

using Vec3E = std::array<ExprId, 3>;
using Mat3E = std::array<ExprId, 9>;  // row-major

// The one table of joint types: X(name, stdlib spelling, default nq, nu).
#define KANESIM_JOINT_TYPES(X)              \
  X(Revolute, "revolute", 1, 1)             \
  X(Prismatic, "prismatic", 1, 1)           \
  X(Cylindrical, "cylindrical", 2, 2)       \
  X(Universal, "universal", 2, 2)           \
  X(Spherical, "spherical", 4, 3)           \
  X(Planar, "planar", 3, 3)                 \
  X(Free, "free", 7, 6)                     \
  X(Weld, "weld", 0, 0)

enum class JointType : std::uint8_t {
#define KANESIM_X(name, spelling, nq, nu) name,
  KANESIM_JOINT_TYPES(KANESIM_X)
#undef KANESIM_X
};
const char* JointTypeName(JointType t);
bool JointTypeFromName(const std::string& s, JointType* out);

// How rotations of Spherical and Free joints are parameterized.
enum class RotationCoords : std::uint8_t {
  Quaternion,  // q = [w, x, y, z] of R_ab, unit norm (4 coordinates)
  CardanXYZ,   // R_ab = Rx(q1) Ry(q2) Rz(q3); singular at |q2| = pi/2
  EulerZYZ,    // R_ab = Rz(q1) Ry(q2) Rz(q3); singular at q2 = 0, pi
};
const char* RotationCoordsName(RotationCoords c);
bool RotationCoordsFromName(const std::string& s, RotationCoords* out);

enum class ParamType : std::uint8_t { Real, Integer, Boolean, String };

struct Param {
  // User-provided: params.emplace_back() then runs the member initializers only instead of
  // zeroing the struct first (value-initialization of an implicit constructor).
  Param() {}  // NOLINT(modernize-use-equals-default)
  // Its name (dotted, scalarized: "links[2].L", "world.g[2]") is Mechanism::ParamName(i):
  // one text of all the names (a model has thousands of parameters; a string each cost an
  // allocation and a page in ten of the front end's).
  std::uint32_t name_at = 0, name_size = 0;
  ParamType type = ParamType::Real;
  double value = 0.0;        // evaluated value (Integer/Boolean as 0/1/n)
  std::string string_value;  // String parameters only
  ExprId binding = kNoExpr;  // expression over earlier params; kNoExpr = literal leaf
  std::string unit;          // declared, or inferred by the unit check (lang/elab_units.h); ""
  double min = -1e300, max = 1e300;
  bool is_constant = false;  // `constant`: never changed by --set or a sweep
  bool structural = false;   // sizes an array, gates a component or an if/for: changing
                             // it needs elaboration again
  bool user_set = false;     // value came from --set
  SourceLoc loc;
};

struct Frame {
  std::string name;                  // canonical (first declared) name, e.g. "rod1.frame_b"
  std::vector<std::string> aliases;  // every connected connector name, name included
  SourceLoc loc;
};

struct World {
  std::int32_t frame = -1;
  Vec3E gravity{kNoExpr, kNoExpr, kNoExpr};  // resolved in world
  SourceLoc loc;
};

// Rigid mass properties attached to a frame F.
struct Body {
  std::string name;
  std::int32_t frame = -1;
  ExprId mass = kNoExpr;
  Vec3E r_cm{};  // p_FCm, resolved in F
  Mat3E inertia{};  // central inertia about Cm, resolved in F (row-major, symmetric)
  SourceLoc loc;
};

// Rigid connection: frame_b = frame_a displaced by r and rotated by R.
struct Fixed {
  std::string name;
  std::int32_t frame_a = -1, frame_b = -1;
  Vec3E r{};  // p_ab resolved in a
  Mat3E R{};  // R_ab, row-major
  SourceLoc loc;
};

struct Joint {
  std::string name;  // "shoulder", "j[3]"
  JointType type = JointType::Revolute;
  RotationCoords rotation = RotationCoords::Quaternion;  // Spherical / Free only
  std::int32_t frame_a = -1, frame_b = -1;
  Vec3E axis{};   // resolved in a: Revolute/Prismatic/Cylindrical axis, Universal first
                  // axis, Planar normal. Normalized by the compiler.
  Vec3E axis2{};  // Universal second axis (in the intermediate frame), Planar in-plane x.
  std::vector<ExprId> q_start;  // nq entries (kNoExpr = 0 / identity)
  std::vector<ExprId> u_start;  // nu entries
  std::vector<bool> q_start_fixed;  // `fixed = true` on the start value (assembly holds it)
  std::vector<ExprId> tau;        // nu entries: applied generalized force, kNoExpr = none
  std::vector<ExprId> prescribed; // nq entries: q_k(time) when rheonomic, else kNoExpr
  bool cut = false;               // user asks this joint to be the loop cut
  // Coulomb friction on a Prismatic or Revolute joint, regularized over a speed scale
  // (runtime/kane/friction.cpp):  tau_f = -mu N tanh(u / v)  (Revolute: times the pin radius),
  // N = the joint's reaction force across its axis. kNoExpr: no friction. Set from the
  // stdlib joints' `mu`, `friction_v`, `friction_radius` when mu is not zero.
  ExprId friction_mu = kNoExpr, friction_radius = kNoExpr, friction_v = kNoExpr;
  // Exact Coulomb stick-slip instead (stdlib `friction_exact`, `mu_s`; sim/stick_slip.h):
  // -mu N sign(u) sliding, stuck while the force needed stays within mu_s N.
  bool friction_exact = false;
  ExprId friction_mu_s = kNoExpr;
  // A constant Coulomb friction torque (Revolute) or force (Prismatic) added to mu N r
  // (stdlib `friction_torque` / `friction_force`, static `..._s`; URDF <dynamics friction>):
  // kNoExpr = none. Its sliding and static bounds add to mu r N's and mu_s r N's.
  ExprId friction_c = kNoExpr, friction_c_s = kNoExpr;
  // End stops of a Revolute or Prismatic joint (stdlib `q_min`, `q_max`, `restitution`):
  // kNoExpr = no stop on that side (the stdlib parameter left unbound); restitution is
  // set only when a stop is.
  ExprId q_min = kNoExpr, q_max = kNoExpr, restitution = kNoExpr;
  SourceLoc loc;
  int nq() const;
  int nu() const;
};

// Translational spring/damper along the line between two frame origins:
// tension f = k (s - s0) + d ds/dt, pulling the frames together when positive.
struct LineForce {
  std::string name;
  std::int32_t frame_a = -1, frame_b = -1;
  ExprId k = kNoExpr, d = kNoExpr, s0 = kNoExpr;
  SourceLoc loc;
};

// Force and torque applied at a frame's origin.
struct Wrench {
  std::string name;
  std::int32_t frame = -1;
  Vec3E force{kNoExpr, kNoExpr, kNoExpr};
  Vec3E torque{kNoExpr, kNoExpr, kNoExpr};
  bool resolve_in_world = true;  // false: components are in the frame's own axes
  SourceLoc loc;
};

// Plane: unilateral contact of the frame's origin with the plane n . x = d (stdlib PlaneContact;
// events, not constraint rows: sim/end_stops.h). The others are velocity constraints.
enum class ContactType : std::uint8_t { RollingDisk, RollingSphere, KnifeEdge, Plane };

// Contact against a fixed plane (simulated by the constraints issue #4; Plane by issue 41).
struct Contact {
  std::string name;
  ContactType type = ContactType::RollingDisk;
  std::int32_t frame = -1;  // disk/sphere centre, or knife-edge contact point
  Vec3E axis{};             // disk axis / knife-edge direction, resolved in frame
  ExprId radius = kNoExpr;
  Vec3E plane_point{};      // resolved in world
  Vec3E plane_normal{};     // resolved in world
  ExprId offset = kNoExpr;       // Plane: d of the plane n . x = d (n normalized by the compiler)
  ExprId restitution = kNoExpr;  // Plane: Newton's coefficient at an impact, 0..1
  SourceLoc loc;
};

// An exact holonomic coupling of two one-coordinate joints (stdlib JointCoupling; a gear
// pair, a URDF <mimic>): q_follower = ratio q_leader + offset, kept as a constraint row
// (runtime/constraints/constraints.cpp eq. 11), the follower's speed a dependent one.
struct JointCoupling {
  std::string name;
  std::int32_t leader = -1, follower = -1;  // indices into joints (Revolute or Prismatic)
  ExprId ratio = kNoExpr, offset = kNoExpr;
  SourceLoc loc;
};

// How a body looks (the stdlib shapes, annotated __kanesim(primitive = "shape", kind = ...);
// lang/elab_shapes.cpp): for drawing (`kanesim view`, `run --animation`) and for `kanesim
// check`'s report of mesh bodies. It carries no physics: its Body does.
enum class ShapeKind : std::uint8_t { Rod, Box, Cylinder, Sphere, Mesh };
const char* ShapeKindName(ShapeKind k);

struct Shape {
  std::string name;          // the shape component: "crank", "links[2]"
  ShapeKind kind = ShapeKind::Box;
  std::int32_t body = -1;    // index into bodies: the shape's own Body, drawn in its frame (-1: none)
  // Rod {L, 0, 0}, Box {lx, ly, lz}, Cylinder {length, radius, 0}, Sphere {radius, 0, 0},
  // Mesh {scale, 0, 0}: parameter expressions (m). Rod, Box and Cylinder span x = 0 .. length
  // of the body frame; Sphere is centred on it; a mesh is in its file's frame.
  Vec3E size{kNoExpr, kNoExpr, kNoExpr};
  std::string mesh_file;     // Mesh: the path read (resolved against the .mech file)
  std::string color;         // "#rrggbb" (sRGB), or "" for the next colour of the drawing's palette
  bool visual = true;        // false: not drawn
  SourceLoc loc;
};

struct Output {
  std::string name;
  ExprId expr = kNoExpr;
  std::string unit;  // declared or inferred by the unit check (lang/elab_units.h); "" unknown
  SourceLoc loc;
};

// A `when` clause (docs/events.md): it fires where one of its conditions becomes true.
// Each condition is written as an indicator h over time and state that is positive exactly
// where the condition holds (a > b: a - b; a < b: b - a; and: min; or: max; not: -h), so
// the clause fires where an h crosses zero upwards; change(c) adds -h as well.
struct Reinit {
  std::int32_t state_ref = -1;  // what is set: a joint's q[k] or u[k] (index into state_refs)
  ExprId value = kNoExpr;       // the new value, evaluated at the event's left limit
  SourceLoc loc;
};

struct WhenClause {
  std::vector<ExprId> indicators;  // one per upward crossing that fires the clause
  std::vector<Reinit> reinits;     // in the order written
  bool terminate = false;          // terminate("message"): the run ends at the event
  std::string message;
  SourceLoc loc;                   // the `when` keyword
};

// A top-level `input Real u;` (one per element of an array input, "u[2]"): a value given at
// run time (--input-file, the stepping API), read by Op::Input nodes.
struct Input {
  std::string name;
  SourceLoc loc;     // the declaration
  std::string unit;  // its unit attribute (input Real tau(unit = "N.m")), else inferred; ""
};

struct Experiment {
  double start_time = 0.0, stop_time = 1.0, tolerance = 1e-6, interval = 0.0;
  bool has_start = false, has_stop = false, has_tolerance = false, has_interval = false;
  // annotation(speeds(kind = "diagonal", order = {"j1", ...})): Lesser's diagonal speeds
  // (sim/diagonal_speeds.h) unless `--speeds` says otherwise; order: joint names.
  bool diagonal_speeds = false;
  std::vector<std::string> speed_order;
};

struct Mechanism {
  std::string model_name;
  std::string description;
  std::vector<std::string> source_files;  // every file read (model and stdlib)
  // Every data file the elaboration read, in first-read order, once each: meshes (tables
  // later). What the results depend on beyond the source: a sweep's settings record hashes
  // them (batch/settings_record.h).
  std::vector<std::string> data_files;

  ExprPool exprs;
  std::vector<Param> params;      // in dependency order: bindings refer to earlier ones
  std::string param_names;        // the parameters' names, one after another (ParamName)
  std::vector<StateRef> state_refs;

  std::vector<Frame> frames;
  std::vector<World> worlds;      // exactly one after a successful elaboration
  std::vector<Body> bodies;
  std::vector<Fixed> fixed;
  std::vector<Joint> joints;
  std::vector<LineForce> line_forces;
  std::vector<Wrench> wrenches;
  std::vector<Contact> contacts;
  std::vector<JointCoupling> couplings;
  std::vector<Output> outputs;
  std::vector<Input> inputs;      // in declaration order
  std::vector<Shape> shapes;      // drawing only; empty for a model of bare Bodies
  std::vector<WhenClause> whens;  // empty: no when clauses (no event machinery)
  Experiment experiment;

  // Index of the state reference, adding it once.
  std::int32_t AddStateRef(const StateRef& r);
  int FindFrame(const std::string& name) const;  // by any alias; -1 if none
  int FindJoint(const std::string& name) const;
  int FindParam(std::string_view name) const;
  // Parameter i's name, a view of param_names: valid until the next AddParam.
  std::string_view ParamName(size_t i) const {
    const Param& p = params[i];
    return std::string_view(param_names).substr(p.name_at, p.name_size);
  }
  // A new last parameter named `name`.
  Param& AddParam(std::string_view name);
  // A new last parameter whose name is written by write(std::string&) at the end of param_names.
  template <class Write>
  Param& AddParamWith(Write&& write) {
    Param& p = params.emplace_back();
    p.name_at = static_cast<std::uint32_t>(param_names.size());
    write(param_names);
    p.name_size = static_cast<std::uint32_t>(param_names.size() - p.name_at);
    return p;
  }
  std::string StateRefName(const StateRef& r) const;  // "j.q[1]", "rod.frame_b.r[2]"
  // An expression's text (ExprPool::ToString) with parameters and states by name.
  std::string ExprText(ExprId id) const;
};

// Evaluates all parameter bindings in order (values of leaves and of --set values are kept)
// and returns the values; `overrides` (index -> value) replace leaves or bindings, and the
// bindings after them see the new values (a sweep's scenario, a sensitivity's step).
std::vector<double> EvaluateParams(const Mechanism& m);
std::vector<double> EvaluateParams(const Mechanism& m, const std::map<size_t, double>& overrides);
// The values the elaboration left in the parameters (Param::value, --set values included):
// what EvaluateParams(m) gives, bit for bit, for a mechanism not changed since it was
// elaborated (the elaborator evaluated each binding over the same pool, reading the same
// earlier values), without evaluating them again.
std::vector<double> ElaboratedParamValues(const Mechanism& m);

// Evaluates an expression that depends only on parameters.
double EvalParamExpr(const Mechanism& m, const std::vector<double>& param_values, ExprId id);

// Text dump for `kanesim check --emit flat`.
std::string DumpFlat(const Mechanism& m);

}  // namespace kanesim::flat
