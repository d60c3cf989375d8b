#include "flat/mechanism.h"

#include <cmath>
#include <sstream>
#include <unordered_map>

#include "flat/param_eval.h"

namespace kanesim::flat {

const char* JointTypeName(JointType t) {
  switch (t) {
#define KANESIM_X(name, spelling, nq, nu) \
  case JointType::name:                   \
    return spelling;
    KANESIM_JOINT_TYPES(KANESIM_X)
#undef KANESIM_X
  }
  return "?";
}

bool JointTypeFromName(const std::string& s, JointType* out) {
#define KANESIM_X(name, spelling, nq, nu) \
  if (s == spelling) {                    \
    *out = JointType::name;               \
    return true;                          \
  }
  KANESIM_JOINT_TYPES(KANESIM_X)
#undef KANESIM_X
  return false;
}

const char* RotationCoordsName(RotationCoords c) {
  switch (c) {
    case RotationCoords::Quaternion: return "quaternion";
    case RotationCoords::CardanXYZ: return "cardan_xyz";
    case RotationCoords::EulerZYZ: return "euler_zyz";
  }
  return "?";
}

bool RotationCoordsFromName(const std::string& s, RotationCoords* out) {
  if (s == "quaternion") *out = RotationCoords::Quaternion;
  else if (s == "cardan_xyz") *out = RotationCoords::CardanXYZ;
  else if (s == "euler_zyz") *out = RotationCoords::EulerZYZ;
  else return false;
  return true;
}

static int BaseNq(JointType t) {
  switch (t) {
#define KANESIM_X(name, spelling, nq, nu) \
  case JointType::name:                   \
    return nq;
    KANESIM_JOINT_TYPES(KANESIM_X)
#undef KANESIM_X
  }
  return 0;
}

static int BaseNu(JointType t) {
  switch (t) {
#define KANESIM_X(name, spelling, nq, nu) \
  case JointType::name:                   \
    return nu;
    KANESIM_JOINT_TYPES(KANESIM_X)
#undef KANESIM_X
  }
  return 0;
}

int Joint::nq() const {
  int n = BaseNq(type);
  // Three angles instead of a four-number quaternion.
  if ((type == JointType::Spherical || type == JointType::Free) &&
      rotation != RotationCoords::Quaternion)
    n -= 1;
  return n;
}

int Joint::nu() const { return BaseNu(type); }

std::int32_t Mechanism::AddStateRef(const StateRef& r) {
  for (size_t i = 0; i < state_refs.size(); ++i)
    if (state_refs[i] == r) return static_cast<std::int32_t>(i);
  state_refs.push_back(r);
  return static_cast<std::int32_t>(state_refs.size() - 1);
}

int Mechanism::FindFrame(const std::string& name) const {
  for (size_t i = 0; i < frames.size(); ++i)
    for (const auto& a : frames[i].aliases)
      if (a == name) return static_cast<int>(i);
  return -1;
}

int Mechanism::FindJoint(const std::string& name) const {
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return static_cast<int>(i);
  return -1;
}

int Mechanism::FindParam(std::string_view name) const {
  for (size_t i = 0; i < params.size(); ++i)
    if (ParamName(i) == name) return static_cast<int>(i);
  return -1;
}

Param& Mechanism::AddParam(std::string_view name) {
  return AddParamWith([&](std::string& out) { out.append(name); });
}

std::string Mechanism::StateRefName(const StateRef& r) const {
  std::ostringstream os;
  auto frame_name = [&](int f) {
    return (f >= 0 && static_cast<size_t>(f) < frames.size()) ? frames[static_cast<size_t>(f)].name
                                                               : std::string("frame?");
  };
  switch (r.kind) {
    case StateKind::JointQ:
    case StateKind::JointU: {
      const Joint* j = (r.target >= 0 && static_cast<size_t>(r.target) < joints.size())
                           ? &joints[static_cast<size_t>(r.target)]
                           : nullptr;
      os << (j ? j->name : std::string("joint?"))
         << (r.kind == StateKind::JointQ ? ".q" : ".u");
      int n = j ? (r.kind == StateKind::JointQ ? j->nq() : j->nu()) : 1;
      if (n > 1) os << "[" << (r.k + 1) << "]";
      break;
    }
    case StateKind::FramePosition: os << frame_name(r.target) << ".r[" << (r.k + 1) << "]"; break;
    case StateKind::FrameVelocity: os << frame_name(r.target) << ".v[" << (r.k + 1) << "]"; break;
    case StateKind::FrameAngVel: os << frame_name(r.target) << ".w[" << (r.k + 1) << "]"; break;
    case StateKind::FrameRotation:
      os << frame_name(r.target) << ".R[" << (r.k / 3 + 1) << "," << (r.k % 3 + 1) << "]";
      break;
  }
  return os.str();
}

// Post-order over the sub-DAG of `id` only (a hash map, not an array the size of the
// pool, so that calling it once per parameter stays linear overall).
double EvalParamExpr(const Mechanism& m, const std::vector<double>& pv, ExprId id) {
  if (id < 0) return 0.0;
  std::unordered_map<ExprId, double> val;
  std::vector<ExprId> stack{id};
  while (!stack.empty()) {
    const ExprId e = stack.back();
    if (val.count(e)) {
      stack.pop_back();
      continue;
    }
    const ExprNode& n = m.exprs[e];
    bool ready = true;
    for (ExprId c : {n.a, n.b, n.c})
      if (c >= 0 && !val.count(c)) {
        stack.push_back(c);
        ready = false;
      }
    if (!ready) continue;
    stack.pop_back();
    double r = 0.0;
    switch (n.op) {
      case Op::Const: r = n.value; break;
      case Op::Param:
        r = (n.index >= 0 && static_cast<size_t>(n.index) < pv.size()) ? pv[static_cast<size_t>(n.index)]
                                                                      : std::nan("");
        break;
      case Op::Time:
      case Op::State:
      case Op::Input: r = std::nan(""); break;
      default:
        r = ApplyOp(n.op, n.a >= 0 ? val[n.a] : 0.0, n.b >= 0 ? val[n.b] : 0.0, n.c >= 0 ? val[n.c] : 0.0);
    }
    val[e] = r;
  }
  return val[id];
}

// One evaluator for all parameters: a node shared by several bindings is evaluated once.
std::vector<double> EvaluateParams(const Mechanism& m) { return EvaluateParams(m, {}); }

std::vector<double> EvaluateParams(const Mechanism& m, const std::map<size_t, double>& overrides) {
  std::vector<double> pv(m.params.size(), 0.0);
  ParamEvaluator eval(m.exprs, pv);
  for (size_t i = 0; i < m.params.size(); ++i) {
    const Param& p = m.params[i];
    if (auto it = overrides.find(i); it != overrides.end())
      pv[i] = it->second;
    else
      pv[i] = (p.binding == kNoExpr || p.user_set) ? p.value : eval.Eval(p.binding);
  }
  return pv;
}

std::vector<double> ElaboratedParamValues(const Mechanism& m) {
  std::vector<double> pv;
  pv.reserve(m.params.size());
  for (const Param& p : m.params) pv.push_back(p.value);
  return pv;
}

static std::string LocStr(const SourceLoc& l) {
  std::ostringstream os;
  os << l.file << ":" << l.line << ":" << l.col;
  return os.str();
}

namespace {

// The mechanism's names for ExprPool::ToString, looked up as each leaf is printed.
class MechanismNames : public ExprNames {
 public:
  explicit MechanismNames(const Mechanism& m) : m_(m) {}
  bool Param(int i, std::string* out) const override {
    if (i < 0 || static_cast<size_t>(i) >= m_.params.size()) return false;
    out->append(m_.ParamName(static_cast<size_t>(i)));
    return true;
  }
  bool State(int i, std::string* out) const override {
    if (i < 0 || static_cast<size_t>(i) >= m_.state_refs.size()) return false;
    out->append(m_.StateRefName(m_.state_refs[static_cast<size_t>(i)]));
    return true;
  }

 private:
  const Mechanism& m_;
};

}  // namespace

std::string Mechanism::ExprText(ExprId id) const { return exprs.ToString(id, MechanismNames(*this)); }

std::string DumpFlat(const Mechanism& m) {
  std::vector<std::string> pn, sn;
  for (size_t i = 0; i < m.params.size(); ++i) pn.emplace_back(m.ParamName(i));
  for (const auto& s : m.state_refs) sn.push_back(m.StateRefName(s));
  auto E = [&](ExprId e) { return m.exprs.ToString(e, &pn, &sn); };
  // Appends instead of "{" + std::string&&: GCC 12 -O3 reports a false -Wrestrict there.
  auto V = [&](const Vec3E& v) {
    std::string s = "{";
    s.append(E(v[0])).append(", ").append(E(v[1])).append(", ").append(E(v[2])).append("}");
    return s;
  };
  auto F = [&](int f) {
    return (f >= 0 && static_cast<size_t>(f) < m.frames.size()) ? m.frames[static_cast<size_t>(f)].name
                                                               : std::string("<unconnected>");
  };
  std::ostringstream os;
  os << "flat mechanism " << m.model_name << "\n";
  os << "parameters (" << m.params.size() << "):\n";
  for (size_t i = 0; i < m.params.size(); ++i) {
    const Param& p = m.params[i];
    os << "  " << (p.is_constant ? "constant " : "") << (p.structural ? "structural " : "") << pn[i]
       << " = ";
    if (p.type == ParamType::String)
      os << '"' << p.string_value << '"';
    else
      os << p.value;
    if (p.binding != kNoExpr) os << "  := " << E(p.binding);
    if (!p.unit.empty()) os << "  [" << p.unit << "]";
    os << "\n";
  }
  os << "frames (" << m.frames.size() << "):\n";
  for (const auto& f : m.frames) {
    os << "  " << f.name;
    if (f.aliases.size() > 1) {
      os << "  =";
      for (const auto& a : f.aliases)
        if (a != f.name) os << " " << a;
    }
    os << "\n";
  }
  for (const auto& w : m.worlds) os << "world frame " << F(w.frame) << " gravity " << V(w.gravity) << "\n";
  for (const auto& b : m.bodies) {
    os << "body " << b.name << " at " << F(b.frame) << " m=" << E(b.mass) << " r_cm=" << V(b.r_cm)
       << " I={";
    for (int i = 0; i < 9; ++i) os << (i ? ", " : "") << E(b.inertia[static_cast<size_t>(i)]);
    os << "}\n";
  }
  for (const auto& f : m.fixed) {
    os << "fixed " << f.name << " " << F(f.frame_a) << " -> " << F(f.frame_b) << " r=" << V(f.r)
       << " R={";
    for (int i = 0; i < 9; ++i) os << (i ? ", " : "") << E(f.R[static_cast<size_t>(i)]);
    os << "}\n";
  }
  for (const auto& j : m.joints) {
    os << "joint " << j.name << " " << JointTypeName(j.type);
    if (j.type == JointType::Spherical || j.type == JointType::Free)
      os << "(" << RotationCoordsName(j.rotation) << ")";
    os << " " << F(j.frame_a) << " -> " << F(j.frame_b) << " axis=" << V(j.axis);
    if (j.type == JointType::Universal || j.type == JointType::Planar) os << " axis2=" << V(j.axis2);
    if (j.cut) os << " cut";
    os << "\n";
    for (size_t k = 0; k < j.q_start.size(); ++k)
      if (j.q_start[k] != kNoExpr) os << "    q[" << k + 1 << "] start " << E(j.q_start[k]) << "\n";
    for (size_t k = 0; k < j.u_start.size(); ++k)
      if (j.u_start[k] != kNoExpr) os << "    u[" << k + 1 << "] start " << E(j.u_start[k]) << "\n";
    for (size_t k = 0; k < j.tau.size(); ++k)
      if (j.tau[k] != kNoExpr) os << "    tau[" << k + 1 << "] = " << E(j.tau[k]) << "\n";
    for (size_t k = 0; k < j.prescribed.size(); ++k)
      if (j.prescribed[k] != kNoExpr) os << "    q[" << k + 1 << "] := " << E(j.prescribed[k]) << "\n";
  }
  for (const auto& l : m.line_forces)
    os << "lineforce " << l.name << " " << F(l.frame_a) << " -- " << F(l.frame_b) << " k=" << E(l.k)
       << " d=" << E(l.d) << " s0=" << E(l.s0) << "\n";
  for (const auto& w : m.wrenches)
    os << "wrench " << w.name << " at " << F(w.frame) << (w.resolve_in_world ? " (world)" : " (frame)")
       << " f=" << V(w.force) << " t=" << V(w.torque) << "\n";
  for (const auto& c : m.contacts) {
    if (c.type == ContactType::Plane) {
      os << "contact " << c.name << " plane at " << F(c.frame) << " normal=" << V(c.plane_normal)
         << " d=" << E(c.offset) << " e=" << E(c.restitution) << "\n";
      continue;
    }
    os << "contact " << c.name << " "
       << (c.type == ContactType::RollingDisk     ? "rolling_disk"
           : c.type == ContactType::RollingSphere ? "rolling_sphere"
                                                  : "knife_edge")
       << " at " << F(c.frame)
       << " radius=" << E(c.radius) << " normal=" << V(c.plane_normal) << "\n";
  }
  for (const auto& in : m.inputs) os << "input " << in.name << "\n";
  for (const auto& c : m.couplings)
    os << "coupling " << c.name << " " << m.joints[static_cast<size_t>(c.follower)].name << ".q = " << E(c.ratio)
       << " * " << m.joints[static_cast<size_t>(c.leader)].name << ".q + " << E(c.offset) << "\n";
  for (const auto& o : m.outputs) os << "output " << o.name << " = " << E(o.expr) << "\n";
  for (const auto& w : m.whens) {
    os << "when";
    for (ExprId h : w.indicators) os << " [" << E(h) << " > 0]";
    os << "\n";
    for (const auto& r : w.reinits)
      os << "  reinit " << m.StateRefName(m.state_refs[static_cast<size_t>(r.state_ref)]) << " := " << E(r.value) << "\n";
    if (w.terminate) os << "  terminate \"" << w.message << "\"\n";
  }
  const auto& x = m.experiment;
  os << "experiment start=" << x.start_time << " stop=" << x.stop_time << " tol=" << x.tolerance
     << " interval=" << x.interval << "\n";
  (void)LocStr;
  return os.str();
}

const char* ShapeKindName(ShapeKind k) {
  switch (k) {
    case ShapeKind::Rod: return "rod";
    case ShapeKind::Box: return "box";
    case ShapeKind::Cylinder: return "cylinder";
    case ShapeKind::Sphere: return "sphere";
    case ShapeKind::Mesh: return "mesh";
  }
  return "?";
}

}  // namespace kanesim::flat
