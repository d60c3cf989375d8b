#include "fmi/dependencies.h"

#include <algorithm>
#include <iterator>
#include <numeric>

namespace kanesim::fmi {
namespace {

// A set of knowns, sorted and unique: state y index in [0, n), input i as n + i, time as
// n + n_inputs (Analysis::time_).
using Keys = std::vector<int>;

void Merge(Keys* into, const Keys& from) {
  if (from.empty()) return;
  Keys out;
  out.reserve(into->size() + from.size());
  std::set_union(into->begin(), into->end(), from.begin(), from.end(), std::back_inserter(out));
  into->swap(out);
}

// What each root of `tape` reads, traced through its registers (every instruction writes a
// register of its own): a state reference r as r, input i as n_refs + i, time as
// n_refs + n_inputs.
std::vector<Keys> RootReads(const rt::Tape& tape, int n_refs, int n_inputs) {
  std::vector<Keys> reg(static_cast<size_t>(tape.num_regs()));
  if (tape.time_reg >= 0) reg[static_cast<size_t>(tape.time_reg)] = {n_refs + n_inputs};
  for (const auto& [ref, r] : tape.state_regs) reg[static_cast<size_t>(r)] = {ref};
  for (const auto& [in, r] : tape.input_regs) reg[static_cast<size_t>(r)] = {n_refs + in};
  for (const rt::TapeInstr& in : tape.code) {
    Keys k;
    for (int a : {in.a, in.b, in.c})
      if (a >= 0) Merge(&k, reg[static_cast<size_t>(a)]);
    reg[static_cast<size_t>(in.dst)] = std::move(k);
  }
  std::vector<Keys> roots;
  for (int r : tape.roots) roots.push_back(reg[static_cast<size_t>(r)]);
  return roots;
}

class Analysis {
 public:
  explicit Analysis(const rt::Program& p);
  // der(q) of free coordinate i, with "constant" per known; der(u) of free speed i; output k.
  std::vector<std::pair<int, bool>> CoordinateRate(int i, bool* projects) const;
  const Keys& SpeedRate(int i) const { return group_rates_[Group(p_.joint_of_speed[size_t(p_.u_free[size_t(i)])])]; }
  const Keys& Output(size_t k) const { return outputs_[k]; }
  int time_key() const { return time_; }

 private:
  size_t Group(int body) const;
  void Unite(int a, int b);
  void Groups();
  void GroupStates();
  void GroupForces();
  void AddCoordinate(int full_q, Keys* k) const;  // a state, or what its prescribed motion reads
  void AddSpeed(int full_u, Keys* k) const;
  Keys TapeKeys(const Keys& reads) const;      // tape keys -> knowns
  Keys RefKeys(int ref) const;                 // what a state reference reads

  const rt::Program& p_;
  int n_ = 0, n_inputs_ = 0, time_ = 0, n_refs_ = 0;
  std::vector<int> parent_;            // union-find over bodies
  std::vector<char> projects_;         // per group root: its derivative projects onto constraint rows
  std::vector<Keys> group_states_;     // per group root: its states and its prescribed motions' reads
  std::vector<Keys> group_rates_;      // per group root: what its der(u) reads
  std::vector<int> q_free_of_;         // full coordinate -> free index, -1 prescribed
  std::vector<int> q_joint_;           // full coordinate -> tree joint
  std::vector<Keys> prescribed_;       // full coordinate -> what its prescribed motion reads
  std::vector<int> u_prescribed_;      // full speed -> full coordinate of its prescribed motion, -1
  std::vector<Keys> outputs_;
};

Analysis::Analysis(const rt::Program& p) : p_(p) {
  n_ = p.nq + p.nu;
  n_inputs_ = static_cast<int>(p.mech->inputs.size());
  time_ = n_ + n_inputs_;
  n_refs_ = static_cast<int>(p.mech->state_refs.size());
  q_free_of_.assign(size_t(p.nq_all), -1);
  for (int i = 0; i < p.nq; ++i) q_free_of_[size_t(p.q_free[size_t(i)])] = i;
  q_joint_.assign(size_t(p.nq_all), -1);
  for (size_t L = 0; L < p.joints.size(); ++L)
    for (int k = 0; k < p.joints[L].nq; ++k) q_joint_[size_t(p.joints[L].q0 + k)] = int(L);
  prescribed_.assign(size_t(p.nq_all), {});
  u_prescribed_.assign(size_t(p.nu_all), -1);
  const std::vector<Keys> motions = RootReads(p.prescribed_tape, n_refs_, n_inputs_);
  for (size_t i = 0; i < p.q_prescribed.size(); ++i) {
    prescribed_[size_t(p.q_prescribed[i])] = TapeKeys(motions[i]);
    Merge(&prescribed_[size_t(p.q_prescribed[i])], {time_});  // q(t): time even where folded
    u_prescribed_[size_t(p.prescribed_u[i])] = p.q_prescribed[i];
  }
  Groups();
  GroupStates();
  GroupForces();
  for (const Keys& reads : RootReads(p.output_tape, n_refs_, n_inputs_)) outputs_.push_back(TapeKeys(reads));
}

size_t Analysis::Group(int body) const {
  int b = body;
  while (parent_[size_t(b)] != b) b = parent_[size_t(b)];
  return size_t(b);
}

void Analysis::Unite(int a, int b) {
  if (a < 0 || b < 0) return;  // the world joins nothing
  const size_t ra = Group(a), rb = Group(b);
  if (ra != rb) parent_[std::max(ra, rb)] = int(std::min(ra, rb));
}

// Trees rooted at the world, merged where something couples their equations: a line force
// (both ends' positions), constraint rows (one projection and one reduced solve for all of
// them), and the solves shared by friction, end stops and plane contacts (their iterations
// and reactions are found together).
void Analysis::Groups() {
  const int K = static_cast<int>(p_.bodies.size());
  parent_.resize(size_t(K));
  std::iota(parent_.begin(), parent_.end(), 0);
  const auto body_of = [&](int frame) { return frame < 0 ? -1 : p_.frames[size_t(frame)].body; };
  for (int L = 0; L < K; ++L) Unite(L, p_.joints[size_t(L)].parent);
  for (const rt::LineForceModel& l : p_.line_forces) Unite(body_of(l.frame_a), body_of(l.frame_b));
  std::vector<int> rows, shared;
  for (const rt::LoopClosure& l : p_.loops) rows.insert(rows.end(), {body_of(l.frame_a), body_of(l.frame_b)});
  for (const rt::ContactModel& c : p_.contacts) rows.push_back(c.body);
  for (const rt::CouplingModel& c : p_.couplings) rows.insert(rows.end(), {c.leader, c.follower});
  for (int j : p_.friction_joints) shared.push_back(j);
  for (int j : p_.stop_joints) shared.push_back(j);
  for (const rt::PlaneContactModel& c : p_.plane_contacts) shared.push_back(c.body);
  rows.erase(std::remove_if(rows.begin(), rows.end(), [](int b) { return b < 0; }), rows.end());
  shared.erase(std::remove_if(shared.begin(), shared.end(), [](int b) { return b < 0; }), shared.end());
  for (size_t i = 1; i < rows.size(); ++i) Unite(rows[0], rows[i]);
  for (size_t i = 1; i < shared.size(); ++i) Unite(shared[0], shared[i]);
  projects_.assign(size_t(K), 0);
  if (!p_.rows.empty())
    for (int b : rows) projects_[Group(b)] = 1;
}

void Analysis::AddCoordinate(int full_q, Keys* k) const {
  const int i = q_free_of_[size_t(full_q)];
  if (i >= 0)
    Merge(k, {i});
  else
    Merge(k, prescribed_[size_t(full_q)]);
}

void Analysis::AddSpeed(int full_u, Keys* k) const {
  const int i = p_.u_free_of[size_t(full_u)];
  if (i >= 0)
    Merge(k, {p_.nq + i});
  else if (u_prescribed_[size_t(full_u)] >= 0)
    Merge(k, prescribed_[size_t(u_prescribed_[size_t(full_u)])]);
}

void Analysis::GroupStates() {
  group_states_.assign(p_.bodies.size(), {});
  for (size_t L = 0; L < p_.joints.size(); ++L) {
    const rt::TreeJoint& j = p_.joints[L];
    Keys& k = group_states_[Group(int(L))];
    for (int c = 0; c < j.nq; ++c) AddCoordinate(j.q0 + c, &k);
    for (int c = 0; c < j.nu; ++c) AddSpeed(j.u0 + c, &k);
  }
}

// der(u) of a group: its states (through M(q) and the velocity terms) and what the forces
// acting on it read.
void Analysis::GroupForces() {
  const std::vector<Keys> forces = RootReads(p_.force_tape, n_refs_, n_inputs_);
  group_rates_ = group_states_;
  const auto add = [&](int body, const rt::Scalar& s) {
    if (body >= 0 && s.root >= 0) Merge(&group_rates_[Group(body)], TapeKeys(forces[size_t(s.root)]));
  };
  for (int r = 0; r < p_.nu_all; ++r) add(p_.joint_of_speed[size_t(r)], p_.joint_tau[size_t(r)]);
  for (const rt::LineForceModel& l : p_.line_forces) {
    const int a = p_.frames[size_t(l.frame_a)].body, b = p_.frames[size_t(l.frame_b)].body;
    for (const rt::Scalar* s : {&l.k, &l.d, &l.s0}) add(a >= 0 ? a : b, *s);
  }
  for (const rt::WrenchModel& w : p_.wrenches)
    for (int c = 0; c < 3; ++c) {
      add(p_.frames[size_t(w.frame)].body, w.force[c]);
      add(p_.frames[size_t(w.frame)].body, w.torque[c]);
    }
}

Keys Analysis::TapeKeys(const Keys& reads) const {
  Keys k;
  for (int r : reads)
    if (r < n_refs_)
      Merge(&k, RefKeys(r));
    else if (r < n_refs_ + n_inputs_)
      Merge(&k, {n_ + (r - n_refs_)});
    else
      Merge(&k, {time_});
  return k;
}

// A joint's q or u is that state; a frame's pose reads the coordinates of its body's path
// to the world, its motion the speeds too; all of the group's states where it projects
// (the projection moves every coordinate of the group).
Keys Analysis::RefKeys(int ref) const {
  const flat::StateRef& r = p_.mech->state_refs[size_t(ref)];
  Keys k;
  const bool joint = r.kind == flat::StateKind::JointQ || r.kind == flat::StateKind::JointU;
  const int body = joint ? p_.joint_of_flat[size_t(r.target)] : p_.frames[size_t(r.target)].body;
  if (body < 0) return k;  // the world, or nothing the program moves
  if (projects_[Group(body)]) return group_states_[Group(body)];
  const rt::TreeJoint& j = p_.joints[size_t(body)];
  if (r.kind == flat::StateKind::JointQ) {
    AddCoordinate(j.q0 + r.k, &k);
    return k;
  }
  if (r.kind == flat::StateKind::JointU) {
    AddSpeed(j.u0 + r.k, &k);
    return k;
  }
  const bool motion = r.kind == flat::StateKind::FrameVelocity || r.kind == flat::StateKind::FrameAngVel;
  for (int L = body; L >= 0; L = p_.joints[size_t(L)].parent) {
    const rt::TreeJoint& P = p_.joints[size_t(L)];
    for (int c = 0; c < P.nq; ++c) AddCoordinate(P.q0 + c, &k);
    if (motion)
      for (int c = 0; c < P.nu; ++c) AddSpeed(P.u0 + c, &k);
  }
  return k;
}

// The joint-local coordinates and speeds rate c of joint j reads (rt::JointKinematicDifferential):
// qdot_c = u_c for every coordinate that is not a rotation's (constant factor); a
// quaternion's rate reads the other three components and the three speeds; Cardan and
// Euler angles' rates read the second and third angles and the speeds before them.
void KinematicReads(const rt::TreeJoint& j, int c, std::vector<int>* q, std::vector<int>* u, bool* constant) {
  const bool rotation = j.type == flat::JointType::Spherical || j.type == flat::JointType::Free;
  const int t = j.type == flat::JointType::Free ? 3 : 0;  // the free joint's translation comes first
  *constant = !rotation || c < t;
  if (*constant) {
    *u = {c};
    return;
  }
  const int r = c - t;
  if (j.rotation == flat::RotationCoords::Quaternion) {
    for (int k = 0; k < 4; ++k)
      if (k != r) q->push_back(t + k);
    *u = {t, t + 1, t + 2};
    return;
  }
  *q = r == 1 ? std::vector<int>{t + 2} : std::vector<int>{t + 1, t + 2};
  *u = r == 2 ? std::vector<int>{t, t + 1, t + 2} : std::vector<int>{t, t + 1};
}

std::vector<std::pair<int, bool>> Analysis::CoordinateRate(int i, bool* projects) const {
  const int full_q = p_.q_free[size_t(i)];
  const int J = q_joint_[size_t(full_q)];
  std::vector<std::pair<int, bool>> out;
  *projects = projects_[Group(J)] != 0;
  if (*projects) {
    for (int k : group_states_[Group(J)]) out.emplace_back(k, false);
    return out;
  }
  const rt::TreeJoint& j = p_.joints[size_t(J)];
  std::vector<int> q, u;
  bool constant = false;
  KinematicReads(j, full_q - j.q0, &q, &u, &constant);
  Keys k;
  for (int c : q) AddCoordinate(j.q0 + c, &k);
  Keys speeds;
  for (int c : u) AddSpeed(j.u0 + c, &speeds);
  for (int key : k) out.emplace_back(key, false);
  for (int key : speeds) out.emplace_back(key, constant && key < n_);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end(), [](auto& a, auto& b) { return a.first == b.first; }), out.end());
  return out;
}

}  // namespace

std::vector<UnknownDependencies> ModelDependencies(const rt::Program& p, const std::vector<Variable>& vars) {
  const Analysis a(p);
  const int n = p.nq + p.nu;
  std::vector<int> input_var(p.mech->inputs.size(), -1);
  for (size_t v = 0; v < vars.size(); ++v)
    if (vars[v].kind == VarKind::Input) input_var[size_t(vars[v].index)] = int(v);
  // Knowns as keys (states, inputs, time) -> the variable table's entries.
  const auto fill = [&](const std::vector<std::pair<int, bool>>& keys, UnknownDependencies* d) {
    for (const auto& [key, constant] : keys)
      if (key == a.time_key())
        d->time = true;
      else
        d->knowns.push_back({key < n ? key : input_var[size_t(key - n)], constant});
  };
  const auto plain = [](const Keys& keys) {
    std::vector<std::pair<int, bool>> out;
    for (int k : keys) out.emplace_back(k, false);
    return out;
  };
  std::vector<UnknownDependencies> deps(vars.size());
  for (size_t v = 0; v < vars.size(); ++v) {
    const Variable& x = vars[v];
    if (x.kind == VarKind::Derivative && x.index < p.nq) {
      bool projects = false;
      fill(a.CoordinateRate(x.index, &projects), &deps[v]);
      deps[v].parameters = projects;  // the constraints' geometry; N(q) has no parameter
    } else if (x.kind == VarKind::Derivative) {
      fill(plain(a.SpeedRate(x.index - p.nq)), &deps[v]);
      deps[v].parameters = true;
    } else if (x.kind == VarKind::Output) {
      fill(plain(a.Output(size_t(x.index))), &deps[v]);
      deps[v].parameters = true;
    }
  }
  return deps;
}

}  // namespace kanesim::fmi

namespace kanesim::fmi {

std::vector<ListedKnown> ListedKnowns(const StructureLists& s, size_t v, bool initial) {
  std::vector<ListedKnown> out;
  if (s.vars[v].kind == VarKind::State) {  // a calculated start: the parameters it is computed from
    for (int p : s.vars[v].start_params) out.push_back({size_t(p), false});
    return out;
  }
  const UnknownDependencies& d = s.deps[v];
  // At initialization a state whose start is calculated is no known: its parameters (every
  // tunable one is listed there) stand for it.
  for (const Dependency& k : d.knowns)
    if (!initial || !s.vars[size_t(k.var)].start_calculated) out.push_back({size_t(k.var), k.constant && !initial});
  if (initial || (s.version == 3 && d.parameters))
    for (size_t p = 0; p < s.vars.size(); ++p)
      if (s.vars[p].kind == VarKind::Parameter) out.push_back({p, false});
  if (s.version == 3 && d.time) out.push_back({s.vars.size(), false});  // `time`, listed last
  std::sort(out.begin(), out.end(), [](const ListedKnown& a, const ListedKnown& b) { return a.vr < b.vr; });
  return out;
}

// Runtime: states, inputs, FMI 3's parameters; initialization: inputs and every variable with
// initial="exact" (the constants' and the states' whose start is not calculated, FMI 3.0
// section 2.4.8); FMI 3's time in both.
std::vector<ListedKnown> AllKnowns(const StructureLists& s, bool initial) {
  std::vector<ListedKnown> out;
  for (size_t k = 0; k < s.vars.size(); ++k) {
    const VarKind kind = s.vars[k].kind;
    const bool exact_state = kind == VarKind::State && (!initial || !s.vars[k].start_calculated);
    if (exact_state || kind == VarKind::Input || (kind == VarKind::Parameter && (initial || s.version == 3)) ||
        (kind == VarKind::Fixed && initial))
      out.push_back({k, false});
  }
  if (s.version == 3) out.push_back({s.vars.size(), false});
  return out;
}

bool ListOmitted(const StructureLists& s, size_t v, bool initial) {
  const std::vector<ListedKnown> k = ListedKnowns(s, v, initial);
  if (std::any_of(k.begin(), k.end(), [](const ListedKnown& e) { return e.constant; })) return false;
  const size_t time_vr = s.vars.size();
  const auto without_time = [&](const std::vector<ListedKnown>& l) {
    return size_t(std::count_if(l.begin(), l.end(), [&](const ListedKnown& e) { return s.version == 2 || e.vr != time_vr; }));
  };
  return without_time(k) == without_time(AllKnowns(s, initial));
}

}  // namespace kanesim::fmi
