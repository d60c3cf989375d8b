// Compile stage: force elements and outputs lowered to tapes, and the choice of
// solution path and integrator for the scene.
#include <cmath>
#include <sstream>

#include "runtime/compile/compile_internal.h"

namespace kanesim::rt {

using flat::kNoExpr;

namespace {


// Rates above this (1/s) in a force element make the scene stiff for an explicit or
// Adams method: a pendulum of 0.5 m is ~4 1/s, a 1e6 N/m spring on 1 kg is 1000 1/s.
constexpr double kStiffRate = 1e3;

}  // namespace

void CompileForcesAndOutputs(Program& p, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  std::vector<std::string> pn, sn;
  for (const auto& x : m.params) pn.push_back(x.name);
  for (const auto& r : m.state_refs) sn.push_back(m.StateRefName(r));
  TapeBuilder forces(m.exprs, p.param_values);
  auto scalar = [&](flat::ExprId id, const std::string& label) {
    Scalar s;
    if (id == kNoExpr) return s;
    if (forces.Fold(id, &s.value)) return s;
    s.root = forces.AddRoot(id, label, m.exprs.ToString(id, &pn, &sn));
    return s;
  };
  auto placed = [&](int frame) {
    return frame >= 0 && static_cast<size_t>(frame) < p.frames.size() && p.frames[static_cast<size_t>(frame)].body >= -1;
  };

  const flat::World& w = m.worlds[0];
  for (int k = 0; k < 3; ++k) {
    double g = 0.0;
    if (w.gravity[static_cast<size_t>(k)] != kNoExpr && !forces.Fold(w.gravity[static_cast<size_t>(k)], &g))
      errors->push_back(Msg(flat::DiagCode::NotFixed, "gravity must not depend on time or state", w.loc));
    p.gravity_W[k] = g;
  }
  p.has_gravity = p.gravity_W.squaredNorm() > 0.0;

  p.joint_tau.assign(static_cast<size_t>(p.nu_all), Scalar{});
  for (const TreeJoint& j : p.joints) {
    const flat::Joint& fj = m.joints[static_cast<size_t>(j.flat_index)];
    for (int k = 0; k < j.nu && static_cast<size_t>(k) < fj.tau.size(); ++k)
      p.joint_tau[static_cast<size_t>(j.u0 + k)] =
          scalar(fj.tau[static_cast<size_t>(k)],
                 std::string("force of joint '").append(j.name).append("' tau").append(j.nu > 1 ? Index1(k) : ""));
  }
  for (const auto& lf : m.line_forces) {
    if (!placed(lf.frame_a) || !placed(lf.frame_b)) {
      errors->push_back(Msg(flat::DiagCode::NotAttached, "line force '" + lf.name + "' is not connected to the mechanism", lf.loc));
      continue;
    }
    LineForceModel l;
    l.name = lf.name;
    l.frame_a = lf.frame_a;
    l.frame_b = lf.frame_b;
    l.k = scalar(lf.k, "stiffness of '" + lf.name + "'");
    l.d = scalar(lf.d, "damping of '" + lf.name + "'");
    l.s0 = scalar(lf.s0, "free length of '" + lf.name + "'");
    p.line_forces.push_back(l);
  }
  for (const auto& wr : m.wrenches) {
    if (!placed(wr.frame)) {
      errors->push_back(Msg(flat::DiagCode::NotAttached, "force '" + wr.name + "' is not connected to the mechanism", wr.loc));
      continue;
    }
    WrenchModel x;
    x.name = wr.name;
    x.frame = wr.frame;
    x.in_world = wr.resolve_in_world;
    for (int k = 0; k < 3; ++k) {
      x.force[k] = scalar(wr.force[static_cast<size_t>(k)], std::string("force").append(Index1(k)).append(" of '").append(wr.name).append("'"));
      x.torque[k] = scalar(wr.torque[static_cast<size_t>(k)], std::string("torque").append(Index1(k)).append(" of '").append(wr.name).append("'"));
    }
    p.wrenches.push_back(x);
  }
  p.force_tape = forces.Finish();

  TapeBuilder outputs(m.exprs, p.param_values);
  for (const auto& o : m.outputs) outputs.AddRoot(o.expr, "output '" + o.name + "'", m.exprs.ToString(o.expr, &pn, &sn));
  p.output_tape = outputs.Finish();

  // State refs read by each tape; joint refs must name articulated joints.
  auto collect = [&](const Tape& t, std::vector<int>* refs) {
    for (const auto& [ref, reg] : t.state_regs) {
      const flat::StateRef& r = m.state_refs[static_cast<size_t>(ref)];
      bool ok = true;
      if (r.kind == flat::StateKind::JointQ || r.kind == flat::StateKind::JointU)
        ok = r.target >= 0 && static_cast<size_t>(r.target) < p.joint_of_flat.size() &&
             p.joint_of_flat[static_cast<size_t>(r.target)] >= 0;
      else
        ok = placed(r.target);
      if (!ok) errors->push_back(Msg(flat::DiagCode::NotSimulated, std::string("'").append(m.StateRefName(r)).append("' is not a simulated quantity"), {}));
      refs->push_back(ref);
    }
  };
  collect(p.force_tape, &p.state_refs_forces);
  collect(p.output_tape, &p.state_refs_outputs);
}

// The solution path, from bench/rhs_chain (docs/benchmarks.md, "Cost of one right-hand
// side"; CPU time per evaluation, medians of 5, all paths and Pinocchio's aba in one run):
// the recursive elimination (runtime/kane/kane_tree.cpp) is the cheapest path for every open
// tree measured, at every size:
//   chains    N = 1: recursive 0.21 us, dense 0.23;  N = 5: 1.21, dense 1.52, sparse 7.0;
//             N = 100: 25.2, dense 122, sparse 152;  N = 1000: 255, sparse 1601; 0.81-0.85x aba
//   mixed trees (all joint types)  N = 4: 1.07 vs dense 1.18;  N = 14: 5.9 vs 9.6;  N = 70: 29.5 vs 189
// so auto never takes dense or sparse for a tree. Closed loops and rolling contacts keep
// the dense path reduced to the constrained basis (AssembleLoops overrides this choice).
void ChooseSolver(Program& p) {
  std::ostringstream why;
  if (p.options.solver != SolverPath::Auto) {
    p.solver = p.options.solver;
    why << "forced by --solver";
  } else {
    p.solver = SolverPath::Recursive;
    why << "open tree, " << p.nu
        << " free speeds: recursive elimination leaves to root, cost linear in bodies (measured the cheapest "
           "path for trees at every size: 0.8-0.9x dense at 1-5 bodies, 3-6x cheaper than sparse)";
  }
  p.solver_reason = why.str();
}

// The integrator, from the work-precision benchmark (docs/benchmarks.md, "Choosing the
// path"):
// - a scene whose force elements have a rate above kStiffRate (or a stiffness given by
//   an expression, which the compiler cannot bound) is stiff and gets IDA (BDF): on the
//   1e8 N/m stress scene IDA takes 130 steps where explicit RK needs 182 050;
// - a smooth non-stiff scene gets our DOP853 (runtime/sim/integrator_dop853.cpp): on
//   every tree problem of the benchmark (double pendulum, chains of 5-100 links, 1-10 s)
//   it reached every error level (1e-3, 1e-6, 1e-9) in less time than ARKODE's Fehlberg
//   8(7) and CVODE's Adams (0.3-0.9x the better of the two; e.g. the 10-chain over 1 s at
//   1e-6: 0.90 ms, ARKODE 2.15 ms, CVODE 1.87 ms), at short horizons and loose
//   tolerances as well as long and tight ones; it keeps energy like ARKODE (16 rtol of
//   drift over 10 s of the double pendulum at rtol 1e-8);
// - and so does every other non-stiff scene: closed loops, rolling contacts, joint
//   friction and force laws that read speeds. Measured against CVODE (Adams), error at
//   the end against a CVODE run at rtol 1e-13, median of 3 (docs/integrators.md):
//   four-bar 10 s at rtol 1e-8: DOP853 1.1e-6 in 27.6 ms, CVODE 2.0e-5 in 31.9 ms;
//   sphere on an incline, rolling disk, Chaplygin sleigh: 10-2000x smaller errors in
//   0.3-0.9x the time at rtol 1e-4 ... 1e-10; the damped driven pendulum's tanh(u/0.01)
//   friction: 3.7e-10 in 2.3 ms against 1.3e-9 in 7.6 ms at 1e-10; the cart with Coulomb
//   friction on two rails: 0.3-0.9x the time; the parallelogram through its change
//   points on both forms: energy within 3.6e-7 of E at rtol 1e-8. (ARKODE's Fehlberg
//   8(7), measured before DOP853 existed, lost to Adams on the friction and stopped on
//   the sleigh; DOP853 does neither.)
// CVODE and ARKODE remain for --integrator.
void ChooseIntegrator(Program& p) {
  std::ostringstream iw;
  double max_rate = 0.0;
  std::string stiffest;
  bool unknown = false;
  auto mass_at = [&](int frame) {
    int b = p.frames[static_cast<size_t>(frame)].body;
    return b >= 0 ? p.bodies[static_cast<size_t>(b)].mass : INFINITY;
  };
  for (const auto& l : p.line_forces) {
    if (l.k.root >= 0 || l.d.root >= 0) {
      unknown = true;
      stiffest = l.name;
      continue;
    }
    double mm = std::min(mass_at(l.frame_a), mass_at(l.frame_b));
    if (!std::isfinite(mm)) continue;
    double rate = mm > 0.0 ? std::max(std::sqrt(std::fabs(l.k.value) / mm), std::fabs(l.d.value) / mm) : INFINITY;
    if (rate > max_rate) {
      max_rate = rate;
      stiffest = l.name;
    }
  }

  if (p.options.integrator != IntegratorKind::Auto) {
    p.integrator = p.options.integrator;
    iw << "forced by --integrator";
  } else if (unknown) {
    p.integrator = IntegratorKind::IDA;
    iw << "line force '" << stiffest << "' has a stiffness or damping given by an expression (rate unknown): IDA (BDF)";
  } else if (max_rate >= kStiffRate) {
    p.integrator = IntegratorKind::IDA;
    iw << "line force '" << stiffest << "' has rate max(sqrt(k/m), d/m) = " << max_rate << " 1/s >= " << kStiffRate
       << " 1/s: stiff, IDA (BDF)";
  } else {
    iw << "non-stiff ODE";
    if (max_rate > 0.0) iw << " (fastest force-element rate " << max_rate << " 1/s < " << kStiffRate << " 1/s)";
    p.integrator = IntegratorKind::DOP853;
    iw << ": DOP853 (8th-order Runge-Kutta; the fastest at every error level on the tree benchmark and on the "
          "examples with loops, contacts and friction)";
  }
  p.integrator_reason = iw.str();
}

}  // namespace kanesim::rt
