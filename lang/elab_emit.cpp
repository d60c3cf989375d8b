// Emit: the instance tree's primitives become the flat mechanism, one function per
// primitive (lang/elab_emit.h). Flange connections turn rotational springs and dampers into
// generalized forces on joint coordinates.
#include <algorithm>
#include <initializer_list>
#include <numeric>
#include <utility>

#include "lang/elab_emit.h"

#include "lang/elab_connect.h"
#include "lang/elab_eval.h"
#include "lang/elab_instantiate.h"

namespace kanesim::lang::elab {

using flat::ExprId;
using flat::Op;

namespace {

// One emission: Run lists its stages; the springs the walk finds are kept here between them.
class Emitter {
 public:
  Emitter(InstanceTree& tree, const Connections& sets, const std::vector<PendingWhen>& whens, Evaluator& eval,
          const SourcePlaces& places, Diagnostics& diags, flat::Mechanism* m, VarVisitor* visitor)
      : tree_(tree), sets_(sets), whens_(whens), eval_(eval), places_(places), pool(m->exprs), diags_(diags), m_(m),
        visitor_(visitor) {}

  void Run(Node* root) {
    m_->joints = std::move(tree_.joints);
    tau_extra.resize(m_->joints.size());
    Inputs(root);
    Walk(root);
    LinkShapes(m_);
    SpringsOnFlanges();
    CouplingsOnFlanges();
    Outputs(root);
    EmitWhens(whens_, eval_, places_, diags_, m_);
    EveryParameter(root);
    RetargetFrameStates();
  }

 private:
  // The flat frame of primitive n's Frame `name`; warns when it is connected to nothing.
  int FrameOf(Node* n, const char* name) {
    Node* c = n->Child(name);
    if (!c || c->prim != Prim::Frame) {
      diags_.Error(DiagCode::BadPrimitive, n->cls ? n->cls->name_span : Span{},
                   "primitive '" + n->Path() + "' lacks the Frame '" + name + "'");
      return -1;
    }
    const size_t pid = static_cast<size_t>(c->prim_index);
    // A fixed frame's frame_b may end the chain: a named leaf frame (a robot's tool0).
    const bool leaf_ok = n->prim == Prim::World || (n->prim == Prim::Fixed && std::string(name) == "frame_b");
    if (sets_.frame_set_size[pid] == 1 && !leaf_ok) {
      auto& d = diags_.Warning(DiagCode::UnconnectedFrame, n->decl ? n->decl->name_span : Span{},
                               "'" + c->Path() + "' is not connected to anything");
      // A joint's frame_b goes to the body it moves (to the world it would lock the joint: W316).
      d.hint = std::string(name) == "frame_b" && n->prim == Prim::Joint
                   ? "connect it to the body the joint moves, e.g. connect(" + c->Path() + ", body.frame_a)"
                   : "connect it, e.g. connect(" + c->Path() + ", world.frame_b)";
    }
    return sets_.frame[pid];
  }

  // Primitive n's variable `name`, which must have `shape`. The value is the variable's
  // own (GetVar's): it lives as long as the instance tree.
  const Value& Field(Node* n, const char* name, std::initializer_list<int> shape) {
    Node* c = n->Child(name);
    if (!c || c->kind != Node::kVar) {
      diags_.Error(DiagCode::BadPrimitive, n->cls ? n->cls->name_span : Span{},
                   "primitive '" + n->Path() + "' lacks '" + name + "'");
      return invalid_;
    }
    const Value& v = eval_.GetVar(c, c->decl ? c->decl->name_span : Span{});
    if (v.valid && !std::equal(v.shape.begin(), v.shape.end(), shape.begin(), shape.end())) {
      diags_.Error(DiagCode::SizeMismatch, c->decl ? c->decl->name_span : Span{},
                   "'" + c->Path() + "' has the wrong size for its primitive");
      return invalid_;
    }
    return v;
  }

  // v as a 3-vector of expressions; zeros when invalid.
  flat::Vec3E AsVec3(const Value& v) {
    if (v.valid && v.elements.size() == 3) return {v.elements[0], v.elements[1], v.elements[2]};
    return {pool.Constant(0), pool.Constant(0), pool.Constant(0)};
  }

  // v as a 3x3 matrix of expressions; the identity when invalid.
  flat::Mat3E AsMat3(const Value& v) {
    flat::Mat3E out;
    for (size_t i = 0; i < 9; ++i)
      out[i] = v.valid && v.elements.size() == 9 ? v.elements[i] : pool.Constant(i % 4 == 0 ? 1 : 0);
    return out;
  }

  // v as one expression; zero when invalid.
  ExprId AsScalar(const Value& v) { return v.valid && v.elements.size() == 1 ? v.elements[0] : pool.Constant(0); }

  // Primitive n's Boolean `name`, evaluated now; `dflt` when absent.
  // Parameter `name` of n when it is a structural value other than zero (*e its expression);
  // false when absent, zero or not structural (that is reported).
  bool NonZeroStructural(Node* n, const char* name, ExprId* e) {
    Node* v = n->Child(name);
    if (!v || v->kind != Node::kVar) return false;
    const Value& val = eval_.GetVar(v, Span{});
    double x = 0;
    if (!val.valid || !eval_.Structural(val, v->decl ? v->decl->name_span : Span{}, &x, name) || x == 0) return false;
    *e = val.elements[0];
    return true;
  }

  bool Boolean(Node* n, const char* name, bool dflt) {
    Node* c = n->Child(name);
    if (!c) return dflt;
    const Value& v = eval_.GetVar(c, Span{});
    double x = dflt ? 1 : 0;
    if (v.valid && eval_.Structural(v, c->decl ? c->decl->name_span : Span{}, &x, name)) return x != 0;
    return dflt;
  }

  // A one-coordinate joint's end stops: `q_min` / `q_max` when bound (unbound: no stop, so a
  // joint without stops carries nothing), `restitution` with them.
  void EndStops(Node* n, flat::Joint* j) {
    Node* lo = n->Child("q_min");
    Node* hi = n->Child("q_max");
    const bool has_lo = lo && lo->kind == Node::kVar && Bound(lo);
    const bool has_hi = hi && hi->kind == Node::kVar && Bound(hi);
    if (has_lo) j->q_min = AsScalar(Field(n, "q_min", {}));
    if (has_hi) j->q_max = AsScalar(Field(n, "q_max", {}));
    if ((has_lo || has_hi) && n->Child("restitution")) j->restitution = AsScalar(Field(n, "restitution", {}));
  }

  // Whether a variable has any binding.
  static bool Bound(Node* var) {
    return var && (var->eq_binding || var->Modifiers().value || !var->eq_elem_binding.empty());
  }

  // Every enabled instance, depth first: each primitive becomes its flat element, each
  // variable is shown to the visitor (after its primitive, whose fields were just evaluated).
  void Walk(Node* n) {
    if (!n->enabled || diags_.Full()) return;
    if (n->kind == Node::kArray) {
      for (auto& e : n->elems) Walk(e.get());
      return;
    }
    if (n->kind == Node::kVar && visitor_) visitor_->Visit(n);
    if (n->kind != Node::kClass) return;
    // Where the primitive is declared (made only for the kinds that keep it); inside a
    // library component (a Rod's body and tip) the user's declaration of that component,
    // so that the compiler's messages point into the user's file.
    auto loc = [&] { return places_.Loc(places_.UserSpan(n)); };
    switch (n->prim) {
      case Prim::World: EmitWorld(n, loc()); break;
      case Prim::Body: EmitBody(n, loc()); break;
      case Prim::Fixed: EmitFixed(n, loc()); break;
      case Prim::Joint: EmitJoint(n); break;
      case Prim::LineForce: EmitLineForce(n, loc()); break;
      case Prim::Wrench: EmitWrench(n, loc()); break;
      case Prim::Contact: EmitContact(n, loc()); break;
      case Prim::RotSpring: springs.push_back(n); break;
      case Prim::Coupling: couplings.push_back(n); break;
      case Prim::Shape: EmitShape(n, eval_, places_, diags_, m_); break;
      default: break;
    }
    for (auto& c : n->children) Walk(c.get());
  }

  void EmitWorld(Node* n, const flat::SourceLoc& loc) {
    flat::World w;
    w.frame = FrameOf(n, "frame_b");
    w.gravity = AsVec3(Field(n, "g", {3}));
    w.loc = loc;
    m_->worlds.push_back(std::move(w));
  }

  void EmitBody(Node* n, const flat::SourceLoc& loc) {
    flat::Body b;
    b.name = n->Path();
    b.frame = FrameOf(n, "frame_a");
    b.mass = AsScalar(Field(n, "m", {}));
    b.r_cm = AsVec3(Field(n, "r_CM", {3}));
    b.inertia = AsMat3(Field(n, "I", {3, 3}));
    b.loc = loc;
    m_->bodies.push_back(std::move(b));
  }

  void EmitFixed(Node* n, const flat::SourceLoc& loc) {
    flat::Fixed f;
    f.name = n->Path();
    f.frame_a = FrameOf(n, "frame_a");
    f.frame_b = FrameOf(n, "frame_b");
    f.r = AsVec3(Field(n, "r", {3}));
    f.R = AsMat3(Field(n, "R", {3, 3}));
    f.loc = loc;
    m_->fixed.push_back(std::move(f));
  }

  void EmitJoint(Node* n) {
    flat::Joint& j = m_->joints[static_cast<size_t>(n->prim_index)];
    j.frame_a = FrameOf(n, "frame_a");
    j.frame_b = FrameOf(n, "frame_b");
    if (Node* c = n->Child("coordinates")) {
      const Value& v = eval_.GetVar(c, Span{});
      if (v.valid && v.type == VType::String && !v.strings.empty() &&
          !flat::RotationCoordsFromName(v.strings[0], &j.rotation)) {
        auto& d = diags_.Error(DiagCode::BadValue, c->Modifiers().value ? c->Modifiers().value->span : Span{},
                               "unknown coordinates \"" + v.strings[0] + "\" for joint '" + n->Path() + "'");
        std::string best = ClosestName(v.strings[0], {"quaternion", "cardan_xyz", "euler_zyz"});
        d.hint = "use \"quaternion\", \"cardan_xyz\" or \"euler_zyz\"" +
                 (best.empty() ? std::string() : " (did you mean \"" + best + "\"?)");
      }
    }
    const char* ax1 = nullptr;
    const char* ax2 = nullptr;
    switch (j.type) {
      case flat::JointType::Revolute:
      case flat::JointType::Prismatic:
      case flat::JointType::Cylindrical: ax1 = "axis"; break;
      case flat::JointType::Universal: ax1 = "axis_a"; ax2 = "axis_b"; break;
      case flat::JointType::Planar: ax1 = "n"; ax2 = "axis_x"; break;
      default: break;
    }
    j.axis = ax1 ? AsVec3(Field(n, ax1, {3})) : AsVec3(Value::Invalid());
    j.axis2 = ax2 ? AsVec3(Field(n, ax2, {3})) : AsVec3(Value::Invalid());
    j.cut = Boolean(n, "cut", false);
    // Coulomb friction from the joint's normal force (mu) and a constant one (friction_torque
    // or friction_force): only when one is not zero, so a scene without friction pays nothing
    // (zero vs not is a structural choice).
    ExprId mu_e = flat::kNoExpr, c_e = flat::kNoExpr;
    const char* c_name = j.type == flat::JointType::Revolute ? "friction_torque" : "friction_force";
    const bool has_mu = NonZeroStructural(n, "mu", &mu_e);
    const bool has_c = NonZeroStructural(n, c_name, &c_e);
    if (has_mu || has_c) {
      j.friction_mu = has_mu ? mu_e : pool.Constant(0.0);
      j.friction_c = c_e;
      j.friction_v = AsScalar(Field(n, "friction_v", {}));
      j.friction_radius =
          n->Child("friction_radius") ? AsScalar(Field(n, "friction_radius", {})) : pool.Constant(1.0);
      j.friction_exact = Boolean(n, "friction_exact", false);
      if (j.friction_exact && n->Child("mu_s")) j.friction_mu_s = AsScalar(Field(n, "mu_s", {}));
      const std::string c_s = std::string(c_name) + "_s";
      if (j.friction_exact && has_c && n->Child(c_s.c_str())) j.friction_c_s = AsScalar(Field(n, c_s.c_str(), {}));
    }
    EndStops(n, &j);
    int nq = j.nq(), nu = j.nu();
    j.q_start.assign(static_cast<size_t>(nq), flat::kNoExpr);
    j.u_start.assign(static_cast<size_t>(nu), flat::kNoExpr);
    j.q_start_fixed.assign(static_cast<size_t>(nq), false);
    j.tau.assign(static_cast<size_t>(nu), flat::kNoExpr);
    j.prescribed.assign(static_cast<size_t>(nq), flat::kNoExpr);
    Node* q = n->Child("q");
    Node* u = n->Child("u");
    Node* tau = n->Child("tau");
    auto size_of = [](Node* v) {
      size_t c = 1;
      for (int d : v->shape) c *= static_cast<size_t>(d < 0 ? 0 : d);
      return static_cast<int>(c);
    };
    if (nq > 0 && (!q || !u || !tau || size_of(q) != nq || size_of(u) != nu || size_of(tau) != nu)) {
      diags_.Error(DiagCode::BadPrimitive, n->cls ? n->cls->name_span : Span{},
                   "joint primitive '" + n->Path() + "' needs q[" + std::to_string(nq) + "], u[" +
                       std::to_string(nu) + "] and tau[" + std::to_string(nu) + "]");
      return;
    }
    if (nq == 0) return;
    StartOf(q, &j.q_start, &j.q_start_fixed);
    StartOf(u, &j.u_start, nullptr);
    if (Bound(tau)) {
      const Value& tv = eval_.GetVar(tau, Span{});
      if (tv.valid)
        for (size_t k = 0; k < j.tau.size() && k < tv.elements.size(); ++k) j.tau[k] = tv.elements[k];
    }
    EmitPrescribedMotion(n, j, q, u, nq);
  }

  // The `start` (and `fixed`) modifiers of a joint's q or u.
  void StartOf(Node* var, std::vector<ExprId>* out, std::vector<bool>* fixed) {
    const ModView mods = var->Modifiers();
    auto it = mods.sub.find("start");
    if (it != mods.sub.end() && it->second.value) {
      Span where;
      Value v = eval_.EvalModValue(*it->second.value, &where);
      if (v.valid) {
        if (v.shape.empty() && out->size() == 1) {
          (*out)[0] = v.elements[0];
        } else if (v.elements.size() == out->size() && v.shape.size() == 1) {
          for (size_t k = 0; k < out->size(); ++k) (*out)[k] = v.elements[k];
        } else {
          diags_.Error(DiagCode::SizeMismatch, where,
                       "start value of '" + var->Path() + "' needs " + std::to_string(out->size()) + " element(s)");
        }
        for (ExprId x : *out)
          if (x >= 0 && pool.DependsOnTimeOrState(x)) {
            diags_.Error(DiagCode::NotConstantExpr, where, "a start value must be a parameter expression");
            break;
          }
      }
    }
    if (fixed) {
      auto fit = mods.sub.find("fixed");
      if (fit != mods.sub.end() && fit->second.value) {
        Value fv = eval_.EvalModValue(*fit->second.value, nullptr);
        double x = 0;
        if (fv.valid && fv.shape.empty() && eval_.Structural(fv, fit->second.value->span, &x, "fixed"))
          fixed->assign(fixed->size(), x != 0);
      }
    }
  }

  // Prescribed motion: q = f(time).
  void EmitPrescribedMotion(Node* n, flat::Joint& j, Node* q, Node* u, int nq) {
    if (!Bound(q) && !Bound(u)) return;
    Node* which = Bound(q) ? q : u;
    if (which == u) {
      diags_.Error(DiagCode::BadEquation, u->eq_binding ? u->eq_binding->span : Span{},
                   "prescribe the coordinate q, not the speed u")
          .hint = "write '" + n->Path() + ".q = f(time)'; its speed and acceleration follow";
      return;
    }
    if ((j.type == flat::JointType::Spherical || j.type == flat::JointType::Free) &&
        j.rotation == flat::RotationCoords::Quaternion) {
      diags_.Error(DiagCode::BadEquation, q->eq_binding ? q->eq_binding->span : Span{},
                   "spherical and free joints cannot be prescribed")
          .hint = "prescribe rotations with revolute or universal joints in series";
      return;
    }
    std::vector<std::pair<int, const ModValue*>> items;
    if (q->eq_binding) items.push_back({-1, &*q->eq_binding});
    if (q->Modifiers().value) items.push_back({-1, &*q->Modifiers().value});
    for (auto& [k, mv] : q->eq_elem_binding) items.push_back({k, &mv});
    for (auto [k, mv] : items) {
      Span where;
      Value v = eval_.EvalModValue(*mv, &where);
      if (!v.valid) continue;
      bool ok = k >= 0    ? v.shape.empty()
                : nq == 1 ? v.shape.empty()
                          : v.elements.size() == static_cast<size_t>(nq);
      if (!ok) {
        diags_.Error(DiagCode::SizeMismatch, where, "prescribed motion of '" + q->Path() + "' has the wrong size");
        continue;
      }
      for (size_t e = 0; e < v.elements.size(); ++e) {
        if (pool.DependsOnState(v.elements[e])) {
          diags_.Error(DiagCode::BadEquation, where,
                       "prescribed motion of '" + q->Path() + "' must depend on time and parameters only")
              .hint = "to drive a joint with a force law, write '" + n->Path() + ".tau = ...' instead";
          break;
        }
        j.prescribed[static_cast<size_t>(k >= 0 ? k : static_cast<int>(e))] = v.elements[e];
      }
    }
  }

  void EmitLineForce(Node* n, const flat::SourceLoc& loc) {
    flat::LineForce l;
    l.name = n->Path();
    l.frame_a = FrameOf(n, "frame_a");
    l.frame_b = FrameOf(n, "frame_b");
    l.k = AsScalar(Field(n, "c", {}));
    l.d = AsScalar(Field(n, "d", {}));
    l.s0 = AsScalar(Field(n, "s_unstretched", {}));
    l.loc = loc;
    m_->line_forces.push_back(std::move(l));
  }

  void EmitWrench(Node* n, const flat::SourceLoc& loc) {
    flat::Wrench w;
    w.name = n->Path();
    w.frame = FrameOf(n, "frame_b");
    w.force = AsVec3(Field(n, "force", {3}));
    w.torque = AsVec3(Field(n, "torque", {3}));
    w.resolve_in_world = Boolean(n, "resolve_in_world", true);
    w.loc = loc;
    m_->wrenches.push_back(std::move(w));
  }

  void EmitContact(Node* n, const flat::SourceLoc& loc) {
    flat::Contact c;
    c.name = n->Path();
    if (n->prim_kind == "rolling_disk") c.type = flat::ContactType::RollingDisk;
    else if (n->prim_kind == "rolling_sphere") c.type = flat::ContactType::RollingSphere;
    else if (n->prim_kind == "knife_edge") c.type = flat::ContactType::KnifeEdge;
    else if (n->prim_kind == "plane") c.type = flat::ContactType::Plane;
    else diags_.Error(DiagCode::BadPrimitive, n->cls ? n->cls->name_span : Span{}, "unknown contact kind");
    c.frame = FrameOf(n, "frame_a");
    if (c.type == flat::ContactType::Plane) {  // unilateral: n . x = d, an impact law
      c.plane_normal = AsVec3(Field(n, "n", {3}));
      c.offset = AsScalar(Field(n, "d", {}));
      c.restitution = AsScalar(Field(n, "restitution", {}));
      c.loc = loc;
      m_->contacts.push_back(std::move(c));
      return;
    }
    c.axis = AsVec3(Field(n, "axis", {3}));
    c.radius = c.type == flat::ContactType::KnifeEdge ? pool.Constant(0) : AsScalar(Field(n, "radius", {}));
    c.plane_normal = AsVec3(Field(n, "n", {3}));
    c.plane_point = AsVec3(Field(n, "p", {3}));
    c.loc = loc;
    m_->contacts.push_back(std::move(c));
  }

  // Springs and dampers on flanges act on the coordinates of the joints whose drive
  // flanges they are connected to.
  // The joint whose drive flange `s`'s flange `name` is connected to, into *joint (-1: the
  // ground, a support flange, or nothing); false with an error.
  bool DriveJoint(Node* s, const char* name, int* joint) {
    *joint = -1;
    Node* f = s->Child(name);
    if (!f || f->prim != Prim::Flange) {
      diags_.Error(DiagCode::BadPrimitive, s->cls ? s->cls->name_span : Span{}, "'" + s->Path() + "' lacks the flange '" + name + "'");
      return false;
    }
    const int set = sets_.flange_set[static_cast<size_t>(f->prim_index)];
    int found = 0;
    for (size_t i = 0; i < tree_.flanges.size(); ++i) {
      if (sets_.flange_set[i] != set) continue;
      Node* g = tree_.flanges[i];
      if (!g->parent || g->parent->prim != Prim::Joint) continue;
      if (g->name == "drive" && found++ == 0) *joint = g->parent->prim_index;
    }
    if (found > 1) {
      diags_.Error(DiagCode::BadConnect, s->decl ? s->decl->name_span : Span{},
                   "'" + f->Path() + "' is connected to the drive flanges of more than one joint");
      return false;
    }
    return true;
  }

  void SpringsOnFlanges() {
    for (Node* s : springs) {
      struct End {
        int joint = -1;  // -1 = ground (a support flange, or nothing)
      };
      auto end_of = [&](const char* name, End* out) { return DriveJoint(s, name, &out->joint); };
      End a, b;
      if (!end_of("flange_a", &a) || !end_of("flange_b", &b)) continue;
      if (a.joint < 0 && b.joint < 0) {
        diags_.Warning(DiagCode::UnconnectedFrame, s->decl ? s->decl->name_span : Span{},
                       "'" + s->Path() + "' is not connected to any joint's drive flange; it does nothing");
        continue;
      }
      for (int j : {a.joint, b.joint}) {
        if (j < 0) continue;
        const auto& jt = m_->joints[static_cast<size_t>(j)];
        if (jt.nu() != 1) {
          diags_.Error(DiagCode::BadConnect, s->decl ? s->decl->name_span : Span{},
                       "springs on flanges need one-coordinate joints; '" + jt.name + "' has " +
                           std::to_string(jt.nu()));
          j = -2;
        }
      }
      if (a.joint == -2 || b.joint == -2) continue;
      auto q_of = [&](int j) {
        return j < 0 ? pool.Constant(0) : pool.State(m_->AddStateRef({flat::StateKind::JointQ, j, 0}));
      };
      auto u_of = [&](int j) {
        return j < 0 ? pool.Constant(0) : pool.State(m_->AddStateRef({flat::StateKind::JointU, j, 0}));
      };
      ExprId c = AsScalar(Field(s, "c", {}));
      ExprId d = AsScalar(Field(s, "d", {}));
      ExprId phi0 = AsScalar(Field(s, "phi_rel0", {}));
      // Eq. (S1): T = c (phi_b - phi_a - phi_rel0) + d (w_b - w_a), acting -T on b, +T on a.
      ExprId rel = pool.Binary(Op::Sub, pool.Binary(Op::Sub, q_of(b.joint), q_of(a.joint)), phi0);
      ExprId rate = pool.Binary(Op::Sub, u_of(b.joint), u_of(a.joint));
      ExprId T = pool.Binary(Op::Add, pool.Binary(Op::Mul, c, rel), pool.Binary(Op::Mul, d, rate));
      if (b.joint >= 0) tau_extra[static_cast<size_t>(b.joint)].push_back(pool.Unary(Op::Neg, T));
      if (a.joint >= 0) tau_extra[static_cast<size_t>(a.joint)].push_back(T);
    }
    for (size_t j = 0; j < tau_extra.size(); ++j) {
      for (ExprId t : tau_extra[j]) {
        auto& slot = m_->joints[j].tau[0];
        slot = slot == flat::kNoExpr ? t : pool.Binary(Op::Add, slot, t);
      }
    }
  }

  // Inputs of the top-level model, made here so that Mechanism::inputs is in declaration
  // order, whatever order the equations read them in (Evaluator::InputValue).
  void Inputs(Node* root) {
    for (auto& c : root->children)
      if (c->enabled && c->kind == Node::kVar && c->causality == ast::Causality::Input)
        eval_.GetVar(c.get(), c->decl ? c->decl->name_span : Span{});
  }

  // Joint couplings: flange_a on the leader's drive, flange_b on the follower's, both
  // joints with one coordinate (the compiler checks their kinds: K319).
  void CouplingsOnFlanges() {
    for (Node* s : couplings) {
      flat::JointCoupling c;
      if (!DriveJoint(s, "flange_a", &c.leader) || !DriveJoint(s, "flange_b", &c.follower)) continue;
      const Span at = s->decl ? s->decl->name_span : Span{};
      if (c.leader < 0 || c.follower < 0 || c.leader == c.follower) {
        auto& d = diags_.Error(DiagCode::BadConnect, at,
                               "'" + s->Path() + "' must join the drive flanges of two different joints");
        d.hint = "connect(leader.drive, " + s->Path() + ".flange_a); connect(follower.drive, " + s->Path() + ".flange_b);";
        continue;
      }
      c.name = s->Path();
      c.ratio = AsScalar(Field(s, "ratio", {}));
      c.offset = AsScalar(Field(s, "offset", {}));
      c.loc = places_.Loc(places_.UserSpan(s));
      m_->couplings.push_back(std::move(c));
    }
  }

  // Outputs of the top-level model.
  void Outputs(Node* root) {
    for (auto& c : root->children) {
      if (!c->enabled || c->kind != Node::kVar || c->causality != ast::Causality::Output) continue;
      const Value& v = eval_.GetVar(c.get(), c->decl ? c->decl->name_span : Span{});
      if (!v.valid) continue;
      if (v.type == VType::String) {
        diags_.Error(DiagCode::TypeMismatch, c->decl->name_span, "outputs must be numbers");
        continue;
      }
      for (size_t k = 0; k < v.elements.size(); ++k) {
        flat::Output o;
        o.name = c->Path() + (v.elements.size() > 1 ? "[" + std::to_string(k + 1) + "]" : "");
        o.expr = v.elements[k];
        o.loc = places_.Loc(c->decl->name_span);
        m_->outputs.push_back(std::move(o));
      }
    }
  }

  // Every parameter, even unused ones, for `kanesim check` and sweeps.
  void EveryParameter(Node* n) {
    if (!n->enabled || diags_.Full()) return;
    if (n->kind == Node::kVar) {
      bool in_primitive = n->parent && n->parent->prim != Prim::None;
      // A primitive's parameter without a value is optional (a joint's q_min: no stop); the
      // primitive reports it where it needs one.
      if (in_primitive && n->variability == ast::Variability::Parameter && !Bound(n)) return;
      if (n->variability == ast::Variability::Parameter || !in_primitive)
        eval_.GetVar(n, n->decl ? n->decl->name_span : Span{});
      return;
    }
    for (auto& e : n->elems) EveryParameter(e.get());
    for (auto& c : n->children) EveryParameter(c.get());
  }

  // Frame state references now point at canonical frames.
  void RetargetFrameStates() {
    for (auto& r : m_->state_refs) {
      if (r.kind == flat::StateKind::JointQ || r.kind == flat::StateKind::JointU) continue;
      if (r.target >= 0 && static_cast<size_t>(r.target) < sets_.frame.size())
        r.target = sets_.frame[static_cast<size_t>(r.target)];
    }
  }

  InstanceTree& tree_;
  const Connections& sets_;
  const std::vector<PendingWhen>& whens_;
  Evaluator& eval_;
  const SourcePlaces& places_;
  flat::ExprPool& pool;
  Diagnostics& diags_;
  flat::Mechanism* m_;
  VarVisitor* visitor_;
  std::vector<Node*> springs;                  // rotational springs and dampers found by Walk
  std::vector<Node*> couplings;                // joint couplings found by Walk
  std::vector<std::vector<ExprId>> tau_extra;  // per joint: generalized forces of springs on flanges
  const Value invalid_ = Value::Invalid();     // what Field returns for a missing or ill-sized field
};

}  // namespace

void Emit(InstanceTree& tree, const Connections& sets, const std::vector<PendingWhen>& whens, Evaluator& eval,
          const SourcePlaces& places, Diagnostics& diags, flat::Mechanism* m, VarVisitor* visitor) {
  Node* root = tree.root.get();
  Emitter(tree, sets, whens, eval, places, diags, m, visitor).Run(root);
}

// The experiment annotation: StartTime, StopTime, Tolerance, Interval.
void EmitExperiment(const ast::Modification& ex, const ast::ClassDef* top, Node* root, Evaluator& eval,
                    Diagnostics& diags, flat::Mechanism* m) {
  static const std::vector<std::string> kKnown{"StartTime", "StopTime", "Tolerance", "Interval"};
  Ctx ctx{root, nullptr};
  auto& x = m->experiment;
  for (const auto& a : ex.args) {
    if (a.path.size() != 1 || !a.mod || !a.mod->value) continue;
    const std::string& key = a.path[0];
    if (std::find(kKnown.begin(), kKnown.end(), key) == kKnown.end()) {
      auto& d =
          diags.Warning(DiagCode::UnknownModifier, a.name_span, "unknown experiment setting '" + key + "' (ignored)");
      std::string best = ClosestName(key, kKnown);
      if (!best.empty()) d.hint = "did you mean '" + best + "'?";
      continue;
    }
    double v = 0;
    if (!eval.Structural(eval.Eval(*a.mod->value, ctx), a.mod->value->span, &v, key.c_str())) continue;
    if (key == "StartTime") x.start_time = v, x.has_start = true;
    else if (key == "StopTime") x.stop_time = v, x.has_stop = true;
    else if (key == "Tolerance") x.tolerance = v, x.has_tolerance = true;
    else x.interval = v, x.has_interval = true;
  }
  if (x.stop_time <= x.start_time)
    diags.Error(DiagCode::BadValue, top->name_span, "experiment StopTime must be after StartTime");
  if (x.tolerance <= 0 || x.tolerance >= 1)
    diags.Error(DiagCode::BadValue, top->name_span, "experiment Tolerance must be in (0, 1)");
  if (x.has_interval && x.interval <= 0)
    diags.Error(DiagCode::BadValue, top->name_span, "experiment Interval must be positive");
}

void EmitSpeeds(const ast::Modification& sp, Diagnostics& diags, flat::Mechanism* m) {
  static const std::vector<std::string> kKnown{"kind", "order"};
  auto& x = m->experiment;
  for (const auto& a : sp.args) {
    if (a.path.size() != 1 || !a.mod || !a.mod->value) continue;
    const std::string& key = a.path[0];
    const ast::Expr& v = *a.mod->value;
    if (key == "kind") {
      if (v.kind != ast::ExprKind::String || (v.text != "joint" && v.text != "diagonal")) {
        diags.Error(DiagCode::BadValue, v.span, "speeds kind must be \"joint\" or \"diagonal\"");
        continue;
      }
      x.diagonal_speeds = v.text == "diagonal";
    } else if (key == "order") {
      x.speed_order.clear();
      const bool array = v.kind == ast::ExprKind::Array;
      for (size_t i = 0; array && i < v.args.size(); ++i) {
        const ast::Expr& e = *v.args[i];
        const bool known = e.kind == ast::ExprKind::String &&
                           std::any_of(m->joints.begin(), m->joints.end(), [&](const flat::Joint& j) { return j.name == e.text; });
        if (!known) {
          diags.Error(DiagCode::BadValue, e.span, "speeds order: " + (e.kind == ast::ExprKind::String ? "no joint named '" + e.text + "'" : std::string("a joint's name in quotes")));
          continue;
        }
        x.speed_order.push_back(e.text);
      }
      if (!array) diags.Error(DiagCode::BadValue, v.span, "speeds order must be an array of joint names: {\"j1\", \"j2\"}");
    } else {
      auto& d = diags.Warning(DiagCode::UnknownModifier, a.name_span, "unknown speeds setting '" + key + "' (ignored)");
      std::string best = ClosestName(key, kKnown);
      if (!best.empty()) d.hint = "did you mean '" + best + "'?";
    }
  }
}

}  // namespace kanesim::lang::elab
