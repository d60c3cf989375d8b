// Compile: flat mechanism -> Program. Everything decided before t = 0 is decided here:
// rigid groups (frames joined by Fixed elements and welds, merged into one body), the
// spanning tree by breadth-first search from ground (joints closing a loop become cut
// joints: position constraints, compile/loops.cpp), q/u allocation in tree order, the
// pattern of the tangent basis (each body's path of speeds), folded numbers, expression
// tapes, and the choice of solution path and integrator.
#include <algorithm>
#include <cmath>
#include <deque>
#include <sstream>

#include "compiler/compile_internal.h"
#include "flat/union_find.h"
#include "runtime/kinematics/joint_kinematics.h"
#include "runtime/kane/kane.h"
#include "compiler/compiler.h"

namespace kanesim::rt {

using flat::JointType;
using flat::kNoExpr;
using flat::UnionFind;

namespace {

// A rigid edge between two frames: X_ab = (p_ab, R_ab).
struct RigidEdge {
  int a, b;
  Vec3 p_ab;
  Mat3 R_ab;
  std::string what;        // "weld 'w'", "fixed element 'ft'" (for messages)
  flat::SourceLoc loc;
};

// Frames that a second rigid path places within this of the first agree (relative to the
// larger distance from the body's origin, at least 1 m; rotations absolute).
constexpr double kRigidLoopTol = 1e-9;

class Compiler {
 public:
  Compiler(const flat::Mechanism& m, const std::vector<double>& pv, CompileResult* out)
      : m_(m), pv_(pv), out_(out), folder_(m.exprs, pv) {}

  void Error(flat::DiagCode code, const std::string& msg, const flat::SourceLoc& loc,
             const std::string& hint = "") {
    CompileMessage e;
    e.code = code;
    e.message = msg;
    e.hint = hint;
    e.loc = loc;
    out_->errors.push_back(std::move(e));
  }

  // A numeric field that must fold to a constant (depends on parameters only).
  double Num(flat::ExprId id, double dflt, const std::string& what, const flat::SourceLoc& loc) {
    if (id == kNoExpr) return dflt;
    double v = 0.0;
    if (!folder_.Fold(id, &v)) {
      Error(flat::DiagCode::NotFixed, what + " must not depend on time or state", loc,
            "only forces, prescribed motions and outputs may use time and state");
      return dflt;
    }
    return v;
  }
  Vec3 Num3(const flat::Vec3E& e, const std::string& what, const flat::SourceLoc& loc) {
    return Vec3(Num(e[0], 0.0, what, loc), Num(e[1], 0.0, what, loc), Num(e[2], 0.0, what, loc));
  }
  Mat3 NumMat(const flat::Mat3E& e, bool identity_default, const std::string& what, const flat::SourceLoc& loc) {
    Mat3 R;
    for (int i = 0; i < 9; ++i)
      R(i / 3, i % 3) = Num(e[static_cast<size_t>(i)], identity_default && i % 4 == 0 ? 1.0 : 0.0, what, loc);
    return R;
  }

  bool Topology(Program& p);
  void CheckFixedPlacement(const RigidEdge& e);
  void CheckRigidLoop(const RigidEdge& e, const FramePlace& placed, const FramePlace& again);
  void MassProperties(Program& p);

  const flat::Mechanism& m_;
  const std::vector<double>& pv_;
  CompileResult* out_;
  TapeBuilder folder_;
  std::vector<int> group_of_frame_;  // union-find root
  std::vector<int> body_of_group_;   // indexed by root frame: tree body, -1 ground, -2 unreached
  std::vector<int> cut_joints_;      // flat joints that close a loop
};

bool Compiler::Topology(Program& p) {
  const size_t nf = m_.frames.size();
  if (m_.worlds.size() != 1) {
    Error(flat::DiagCode::WorldMissing, m_.worlds.empty() ? "the model has no world" : "the model has more than one world", {},
          "add exactly one `World world;` component");
    return false;
  }
  p.world_frame = m_.worlds[0].frame;
  if (p.world_frame < 0 || static_cast<size_t>(p.world_frame) >= nf) {
    Error(flat::DiagCode::WorldMissing, "the world has no frame", m_.worlds[0].loc);
    return false;
  }

  // Rigid edges: Fixed elements and welds.
  std::vector<RigidEdge> rigid;
  for (const auto& f : m_.fixed) {
    if (f.frame_a < 0 || f.frame_b < 0) {
      Error(flat::DiagCode::NotAttached, "fixed element '" + f.name + "' has an unconnected frame", f.loc);
      continue;
    }
    rigid.push_back({f.frame_a, f.frame_b, Num3(f.r, "fixed translation", f.loc),
                     NumMat(f.R, true, "fixed rotation", f.loc), "fixed element '" + f.name + "'", f.loc});
    CheckFixedPlacement(rigid.back());
  }
  bool ok = true;
  for (const auto& j : m_.joints) {
    if (j.frame_a < 0 || j.frame_b < 0) {
      Error(flat::DiagCode::NotAttached, "joint '" + j.name + "': " + (j.frame_a < 0 ? "frame_a" : "frame_b") + " is not connected",
            j.loc, "connect both frames of a joint");
      ok = false;
    } else if (j.type == JointType::Weld) {
      rigid.push_back({j.frame_a, j.frame_b, Vec3::Zero(), Mat3::Identity(), "weld '" + j.name + "'", j.loc});
    }
  }
  if (!ok) return false;
  UnionFind uf(nf);
  for (const auto& e : rigid) uf.Unite(e.a, e.b);
  group_of_frame_.resize(nf);
  for (size_t i = 0; i < nf; ++i) group_of_frame_[i] = uf.Find(static_cast<int>(i));

  // Spanning tree (Kruskal over rigid groups): joints in declaration order, a joint the
  // user marked `cut` last; a joint whose two groups are already connected closes a
  // loop. Then breadth-first from ground over the tree joints orders bodies and
  // orients each joint (parent side = the side nearer ground).
  const int ground = group_of_frame_[static_cast<size_t>(p.world_frame)];
  std::vector<int> order;
  for (int pass = 0; pass < 2; ++pass)
    for (size_t ji = 0; ji < m_.joints.size(); ++ji)
      if (m_.joints[ji].type != JointType::Weld && m_.joints[ji].cut == (pass == 1)) order.push_back(static_cast<int>(ji));
  UnionFind groups(nf);
  std::vector<char> used(m_.joints.size(), 0);
  std::vector<std::vector<int>> joints_at(nf);
  for (int ji : order) {
    const auto& j = m_.joints[static_cast<size_t>(ji)];
    const int ga = group_of_frame_[static_cast<size_t>(j.frame_a)];
    const int gb = group_of_frame_[static_cast<size_t>(j.frame_b)];
    if (groups.Find(ga) == groups.Find(gb)) {
      cut_joints_.push_back(ji);  // closes a loop: becomes constraints (compile/loops.cpp)
      continue;
    }
    groups.Unite(ga, gb);
    used[static_cast<size_t>(ji)] = 1;
    joints_at[static_cast<size_t>(ga)].push_back(ji);
    joints_at[static_cast<size_t>(gb)].push_back(ji);
  }
  body_of_group_.assign(nf, -2);
  body_of_group_[static_cast<size_t>(ground)] = -1;
  p.joint_of_flat.assign(m_.joints.size(), -1);
  std::vector<int> ref_frame_of_group(nf, -1);
  ref_frame_of_group[static_cast<size_t>(ground)] = p.world_frame;
  std::deque<int> queue{ground};
  std::vector<char> placed_joint(m_.joints.size(), 0);
  while (!queue.empty()) {
    int g = queue.front();
    queue.pop_front();
    for (int ji : joints_at[static_cast<size_t>(g)]) {
      if (placed_joint[static_cast<size_t>(ji)]) continue;
      placed_joint[static_cast<size_t>(ji)] = 1;
      const auto& fj = m_.joints[static_cast<size_t>(ji)];
      const int ga = group_of_frame_[static_cast<size_t>(fj.frame_a)];
      const bool inverted = ga != g;
      const int child_group = inverted ? ga : group_of_frame_[static_cast<size_t>(fj.frame_b)];
      TreeJoint tj;
      tj.name = fj.name;
      tj.loc = fj.loc;
      tj.flat_index = ji;
      tj.type = fj.type;
      tj.rotation = fj.rotation;
      tj.inverted = inverted;
      tj.parent = body_of_group_[static_cast<size_t>(g)];
      tj.child = static_cast<int>(p.bodies.size());
      tj.nq = fj.nq();
      tj.nu = fj.nu();
      body_of_group_[static_cast<size_t>(child_group)] = tj.child;
      ref_frame_of_group[static_cast<size_t>(child_group)] = inverted ? fj.frame_a : fj.frame_b;
      p.joint_of_flat[static_cast<size_t>(ji)] = tj.child;
      TreeBody tb;
      tb.joint = tj.child;
      tb.name = m_.frames[static_cast<size_t>(ref_frame_of_group[static_cast<size_t>(child_group)])].name;
      p.bodies.push_back(tb);
      p.joints.push_back(tj);
      queue.push_back(child_group);
    }
  }

  // Bodies not reached from ground.
  std::vector<char> reported(nf, 0);
  for (const auto& b : m_.bodies) {
    if (b.frame < 0) {
      Error(flat::DiagCode::NotAttached, "body '" + b.name + "' is not attached to a frame", b.loc);
      continue;
    }
    int g = group_of_frame_[static_cast<size_t>(b.frame)];
    if (body_of_group_[static_cast<size_t>(g)] == -2 && !reported[static_cast<size_t>(g)]) {
      reported[static_cast<size_t>(g)] = 1;
      Error(flat::DiagCode::NotConnectedToWorld, "body '" + b.name + "' is not connected to the world", b.loc,
            "connect it through a joint (a free joint for a floating body)");
    }
  }
  for (size_t ji = 0; ji < m_.joints.size(); ++ji) {
    const auto& j = m_.joints[ji];
    int g = group_of_frame_[static_cast<size_t>(j.frame_a)];
    if (j.type != JointType::Weld && used[ji] && !placed_joint[ji] && !reported[static_cast<size_t>(g)]) {
      reported[static_cast<size_t>(g)] = 1;
      Error(flat::DiagCode::NotConnectedToWorld, "joint '" + j.name + "' belongs to a mechanism not connected to the world", j.loc);
    }
  }

  // Frame poses in their body frame: breadth-first over rigid edges from each group's
  // reference frame, X_BF = X_BFa X_ab (or X_BFb X_ab^-1 against the edge).
  std::vector<std::vector<int>> edges_at(nf);
  for (size_t e = 0; e < rigid.size(); ++e) {
    edges_at[static_cast<size_t>(rigid[e].a)].push_back(static_cast<int>(e));
    edges_at[static_cast<size_t>(rigid[e].b)].push_back(static_cast<int>(e));
  }
  p.frames.assign(nf, FramePlace{});
  std::vector<char> placed(nf, 0);
  for (size_t g = 0; g < nf; ++g) {
    int ref = ref_frame_of_group[g];
    if (ref < 0) continue;
    const int body = body_of_group_[g];
    p.frames[static_cast<size_t>(ref)].body = body;
    placed[static_cast<size_t>(ref)] = 1;
    std::deque<int> fq{ref};
    while (!fq.empty()) {
      int f = fq.front();
      fq.pop_front();
      const FramePlace& X = p.frames[static_cast<size_t>(f)];
      for (int ei : edges_at[static_cast<size_t>(f)]) {
        const RigidEdge& e = rigid[static_cast<size_t>(ei)];
        int other = e.a == f ? e.b : e.a;
        FramePlace Y;
        Y.body = body;
        if (e.a == f) {
          Y.R_BF = X.R_BF * e.R_ab;
          Y.p_BF = X.p_BF + X.R_BF * e.p_ab;
        } else {
          Y.R_BF = X.R_BF * e.R_ab.transpose();
          Y.p_BF = X.p_BF - Y.R_BF * e.p_ab;
        }
        if (placed[static_cast<size_t>(other)]) {  // a rigid loop: both paths must place it alike
          CheckRigidLoop(e, p.frames[static_cast<size_t>(other)], Y);
          continue;
        }
        p.frames[static_cast<size_t>(other)] = Y;
        placed[static_cast<size_t>(other)] = 1;
        fq.push_back(other);
      }
    }
  }
  // Numbers out of range leave the structure sound: the later stages still report theirs.
  return std::all_of(out_->errors.begin(), out_->errors.end(),
                     [](const CompileMessage& e) { return e.code == flat::DiagCode::OutOfRange; });
}

// A fixed element's placement X_ab = (p_ab, R_ab) must be finite and R_ab a rotation
// (|R^T R - 1| within kRigidLoopTol entrywise, det R > 0): FixedRotation's R comes from
// its axis n, and a zero or non-finite n gives NaN; a user's own fixed primitive may give
// any matrix. Such a frame would otherwise carry NaN or a shear into every body pose.
void Compiler::CheckFixedPlacement(const RigidEdge& e) {
  const double off = (e.R_ab.transpose() * e.R_ab - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!e.p_ab.allFinite())
    Error(flat::DiagCode::Degenerate, e.what + ": its translation r is not finite", e.loc);
  else if (std::string why = LengthOutOfRange(e.what + ": its translation", e.p_ab); !why.empty())
    Error(flat::DiagCode::OutOfRange, why, e.loc, RangeHint());
  else if (!(off <= kRigidLoopTol) || !(e.R_ab.determinant() > 0.0))
    Error(flat::DiagCode::Degenerate,
          e.what + ": its rotation R is not a rotation" + (e.R_ab.allFinite() ? "" : " (not finite: a zero or non-finite axis n?)"),
          e.loc, "a FixedRotation turns about a non-zero, finite axis n");
}

// A frame reached again through rigid edge `e` (welds and fixed elements closing a loop
// among themselves, e.g. a body welded to the world twice): the second path must put it
// where the first did, else the welds hold the body in two places at once. Reported once
// per edge, at the edge that closes the loop.
void Compiler::CheckRigidLoop(const RigidEdge& e, const FramePlace& placed, const FramePlace& again) {
  const double scale = std::max({1.0, placed.p_BF.norm(), again.p_BF.norm()});
  const double dp = (placed.p_BF - again.p_BF).norm() / scale;
  const double dR = (placed.R_BF - again.R_BF).cwiseAbs().maxCoeff();
  if (dp <= kRigidLoopTol && dR <= kRigidLoopTol) return;
  for (const CompileMessage& m : out_->errors)
    if (m.code == flat::DiagCode::CannotAssemble && m.loc.line == e.loc.line && m.loc.col == e.loc.col &&
        m.loc.file.str() == e.loc.file.str())
      return;
  std::ostringstream msg;
  msg.precision(6);
  msg << e.what << " closes a rigid loop (welds and fixed elements only) that holds a frame in two places: "
      << (dp > kRigidLoopTol ? "positions " : "orientations ") << (dp > kRigidLoopTol ? dp * scale : dR) << " apart";
  Error(flat::DiagCode::CannotAssemble, msg.str(), e.loc,
        "a body fixed to another (or to the world) twice must be fixed at the same place both times; remove one "
        "of the welds or fixed elements");
}

// Merging rigid bodies (Kane & Levinson 1985 §3.6, parallel-axis theorem):
//   m = sum m_i,  c = sum m_i c_i / m,
//   I_c = sum [ R_i I_i R_i^T + m_i (|d_i|^2 1 - d_i d_i^T) ],  d_i = c_i - c,
// where c_i = p_BF + R_BF r_cm,i and R_i = R_BF for body i attached to frame F.
void Compiler::MassProperties(Program& p) {
  const size_t K = p.bodies.size();
  std::vector<double> msum(K, 0.0);
  std::vector<Vec3> mc(K, Vec3::Zero());
  std::vector<char> named(K, 0);
  struct Part {
    int body;
    double m;
    Vec3 c;
    Mat3 I;
  };
  std::vector<Part> parts;
  for (const auto& b : m_.bodies) {
    if (b.frame < 0) continue;
    const FramePlace& F = p.frames[static_cast<size_t>(b.frame)];
    BodySignalSource src;
    src.name = b.name;
    src.frame = b.frame;
    src.p_FBcm = Num3(b.r_cm, "body mass centre", b.loc);
    p.body_signals.push_back(src);
    const double mass = Num(b.mass, 0.0, "body mass", b.loc);
    if (mass < 0.0) Error(flat::DiagCode::Degenerate, "body '" + b.name + "' has negative mass", b.loc);
    if (!std::isfinite(mass) || !src.p_FBcm.allFinite())
      Error(flat::DiagCode::BadMassProperties, "body '" + b.name + "' has a non-finite " + (std::isfinite(mass) ? "centre of mass" : "mass"),
            b.loc);
    Mat3 I;
    if (std::string why = CheckInertia(NumMat(b.inertia, false, "body inertia", b.loc), &I); !why.empty())
      Error(flat::DiagCode::BadMassProperties, "body '" + b.name + "': " + why, b.loc,
            "a rigid body's central inertia is symmetric, its principal moments are >= 0 and the two smaller "
            "add up to at least the largest (docs/language.md \"Mass properties\")");
    const std::string of = "body '" + b.name + "': its ";
    for (const std::string& why : {OutOfRange(of + "mass", mass, kMinMass, kMaxMass, "kg"),
                                   OutOfRange(of + "inertia", I.cwiseAbs().maxCoeff(), kMinMass, kMaxMass, "kg m^2"),
                                   LengthOutOfRange(of + "centre-of-mass offset", src.p_FBcm)})
      if (!why.empty()) Error(flat::DiagCode::OutOfRange, why, b.loc, RangeHint());
    if (F.body < 0) continue;  // mass fixed to ground (or unreached: reported) costs nothing
    const auto L = static_cast<size_t>(F.body);
    if (!named[L]) {
      p.bodies[L].name = b.name;
      named[L] = 1;
    }
    Part part{F.body, mass, F.p_BF + F.R_BF * src.p_FBcm, F.R_BF * I * F.R_BF.transpose()};
    msum[L] += mass;
    mc[L] += mass * part.c;
    parts.push_back(part);
  }
  for (size_t L = 0; L < K; ++L) {
    p.bodies[L].mass = msum[L];
    p.bodies[L].p_BBcm = msum[L] > 0.0 ? Vec3(mc[L] / msum[L]) : Vec3::Zero();
  }
  for (const Part& part : parts) {
    TreeBody& B = p.bodies[static_cast<size_t>(part.body)];
    const Vec3 d = part.c - B.p_BBcm;
    B.I_BBcm_B += part.I + part.m * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  for (TreeBody& B : p.bodies) B.I_diagonal = B.I_BBcm_B.isDiagonal(0.0);
  int merged = 0;
  for (const auto& j : m_.joints) merged += j.type == JointType::Weld ? 1 : 0;
  if (merged > 0) p.notes.push_back(std::to_string(merged) + " weld joint(s) merged into rigid bodies");
}

}  // namespace

// Runs every compile stage; `reuse` (from Rebind) supplies the sparse symbolic analysis.
CompileResult CompileWithParams(std::shared_ptr<const flat::Mechanism> mech, std::vector<double> pv,
                                const CompileOptions& options, const Program* reuse) {
  CompileResult out;
  auto prog = std::make_shared<Program>();
  Program& p = *prog;
  p.mech = std::move(mech);
  p.param_values = std::move(pv);
  p.options = options;
  Compiler c(*p.mech, p.param_values, &out);
  if (!c.Topology(p)) return out;
  c.MassProperties(p);
  CompileJointsAndState(p, c.folder_, &out.errors);
  CompileLoops(p, c.cut_joints_, c.folder_, &out.errors);
  CompileContacts(p, c.folder_, &out.errors);
  CompileCouplings(p, c.folder_, &out.errors);
  CompilePlaneContacts(p, c.folder_, &out.errors);
  CompileForcesAndOutputs(p, c.folder_, &out.errors);
  CompileWhens(p, c.folder_, &out.errors);
  CheckMovesMass(p, &out.errors);
  if (!out.errors.empty()) return out;
  ChooseSolver(p);
  ChooseIntegrator(p);
  if (!p.rows.empty()) {
    AssembleLoops(p, &out.errors);
    if (out.errors.empty()) CheckAnyMassMoves(p, &out.errors);
    if (!out.errors.empty()) return out;
    ChooseLoopSolver(p);
  }
  if (reuse) p.sparse_symbolic = reuse->sparse_symbolic;
  if (p.solver == SolverPath::Recursive) BuildTree(p);
  std::string err;
  if (p.solver == SolverPath::Sparse && !BuildSparse(p, &err)) {
    CompileMessage e;
    e.code = flat::DiagCode::SparseAnalysis;
    e.message = "sparse analysis failed: " + err;
    out.errors.push_back(e);
    return out;
  }
  out.program = std::move(prog);
  return out;
}

CompileResult Compile(const flat::Mechanism& mech, const CompileOptions& options) {
  return Compile(std::make_shared<const flat::Mechanism>(mech), options);
}

CompileResult Compile(std::shared_ptr<const flat::Mechanism> mech, const CompileOptions& options) {
  std::vector<double> pv = flat::EvaluateParams(*mech);
  return CompileWithParams(std::move(mech), std::move(pv), options, nullptr);
}

namespace {

// A refusal of `count` values for the parameters of `mech`; empty when they match.
CompileResult WrongValueCount(const char* who, size_t count, const flat::Mechanism& mech) {
  CompileResult r;
  if (count != mech.params.size())
    r.errors.push_back(Msg(flat::DiagCode::RebindCount, std::string(who) + ": " + std::to_string(count) +
                                                            " parameter values for " +
                                                            std::to_string(mech.params.size()) + " parameters",
                           {}));
  return r;
}

}  // namespace

CompileResult Compile(std::shared_ptr<const flat::Mechanism> mech, std::vector<double> param_values,
                      const CompileOptions& options) {
  CompileResult wrong = WrongValueCount("Compile", param_values.size(), *mech);
  if (!wrong.errors.empty()) return wrong;
  return CompileWithParams(std::move(mech), std::move(param_values), options, nullptr);
}

CompileResult Rebind(const Program& program, const std::vector<double>& param_values) {
  CompileResult wrong = WrongValueCount("Rebind", param_values.size(), *program.mech);
  if (!wrong.errors.empty()) return wrong;
  return CompileWithParams(program.mech, param_values, program.options, &program);
}

}  // namespace kanesim::rt
