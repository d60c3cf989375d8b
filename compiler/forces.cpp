// Compile stage: force elements and outputs lowered to tapes, and the choice of
// solution path and integrator for the scene.
#include <cmath>
#include <sstream>

#include "compiler/compile_internal.h"
#include "compiler/compiler.h"

namespace kanesim::rt {

using flat::kNoExpr;

namespace {


// Rates above this (1/s) in a force element make the scene stiff for an explicit or
// Adams method: a pendulum of 0.5 m is ~4 1/s, a 1e6 N/m spring on 1 kg is 1000 1/s.
constexpr double kStiffRate = 1e3;

}  // namespace

void CompileForcesAndOutputs(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  auto text = [&](flat::ExprId id) { return m.ExprText(id); };  // of a force or output
  TapeBuilder forces = TapeBuilder::SharingFolds(folder);
  auto scalar = [&](flat::ExprId id, const std::string& label) {
    Scalar s;
    if (id == kNoExpr) return s;
    if (forces.Fold(id, &s.value)) return s;
    s.root = forces.AddRoot(id, label, text(id));
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

  TapeBuilder outputs = TapeBuilder::SharingFolds(folder);
  for (const auto& o : m.outputs) outputs.AddRoot(o.expr, "output '" + o.name + "'", text(o.expr));
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

// The solution path. For an open tree the recursive elimination (runtime/kane/kane_tree.cpp)
// is the cheapest path at every size measured, chains and mixed trees with every joint type
// (bench/rhs_chain; docs/benchmarks.md, "Cost of one right-hand side" and "Choosing the
// path"), so auto never takes dense or sparse for a tree. Closed loops and rolling contacts
// keep the dense path reduced to the constrained basis (AssembleLoops overrides this choice).
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

// The integrator (docs/integrators.md, "The automatic choice", with the measurements; the
// work-precision benchmark in docs/benchmarks.md):
// - a scene whose force elements have a rate above kStiffRate (or a stiffness given by
//   an expression, which the compiler cannot bound) is stiff and gets IDA (BDF);
// - every other scene gets our DOP853 (sim/integrator_dop853.cpp), trees as well
//   as closed loops, rolling contacts, joint friction and force laws that read speeds: it
//   reached every error level measured in less time than CVODE's Adams and ARKODE, at
//   short horizons and loose tolerances as well as long and tight ones.
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

  if (p.options.integrator != Integrator::Auto) {
    p.integrator = p.options.integrator;
    iw << "forced by --integrator";
  } else if (unknown) {
    p.integrator = Integrator::IDA;
    iw << "line force '" << stiffest << "' has a stiffness or damping given by an expression (rate unknown): IDA (BDF)";
  } else if (max_rate >= kStiffRate) {
    p.integrator = Integrator::IDA;
    iw << "line force '" << stiffest << "' has rate max(sqrt(k/m), d/m) = " << max_rate << " 1/s >= " << kStiffRate
       << " 1/s: stiff, IDA (BDF)";
  } else {
    iw << "non-stiff ODE";
    if (max_rate > 0.0) iw << " (fastest force-element rate " << max_rate << " 1/s < " << kStiffRate << " 1/s)";
    p.integrator = Integrator::Dop853;
    iw << ": DOP853 (8th-order Runge-Kutta; the fastest at every error level on the tree benchmark and on the "
          "examples with loops, contacts and friction)";
  }
  p.integrator_reason = iw.str();
}

}  // namespace kanesim::rt
