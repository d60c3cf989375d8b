// When clauses as events (sim/when_events.h). A reinit of speed k is the jump
// du = M^-1 J^T lambda, J the rows of the reinit'ed speeds (and of the resting contacts, held
// by EndStopEvents::HeldJump), lambda such that those speeds take their new values: the
// generalized impulse acts on the reinit'ed joints only, so every other joint's generalized
// momentum p_j = (M u)_j is unchanged across the jump.
#include "sim/when_events.h"

#include <algorithm>
#include <cstdio>

#include "runtime/program/program.h"  // Program::whens
#include "sim/friction_impulse.h"
#include "sim/impulse.h"

namespace kanesim::sim {

WhenEvents::WhenEvents(const rt::Program& program) : program_(program) {
  nq_ = rt::NumQ(program);
  nu_ = rt::NumU(program);
  friction_ = HasFrictionImpulses(program);
  for (size_t c = 0; c < program.whens.size(); ++c)
    for (int root : program.whens[c].indicators) {
      clause_of_.push_back(static_cast<int>(c));
      root_of_.push_back(root);
    }
}

int WhenEvents::Functions(rt::Workspace& ws, double t, const double* y, double* g) {
  if (int s = rt::EvalEventTape(program_, ws, t, y); s != 0) return s;
  for (size_t i = 0; i < root_of_.size(); ++i) g[i] = -rt::EventRoot(program_, ws, root_of_[i]);
  return 0;
}

// A jump whose rows' block of M^-1 is singular: the speeds set and the contacts held have
// dependent rows (a speed is set once per clause: E226).
std::string WhenEvents::SingularJump(const std::string& clause) const {
  return clause + ": the reinit's speed jump has no unique solution: the speeds it sets and the contacts held at "
                  "rest (or the closed loops' rows) constrain the same motion";
}

const std::string& WhenEvents::Name(int i) const {
  return program_.whens[static_cast<size_t>(clause_of_[static_cast<size_t>(i)])].name;
}

std::vector<int> WhenEvents::States(int i) const {
  std::vector<int> out;
  if (i < 0 || i >= Count()) return out;
  for (const rt::WhenReinit& r : program_.whens[static_cast<size_t>(clause_of_[static_cast<size_t>(i)])].reinits)
    out.push_back(r.state);
  return out;
}

int WhenEvents::Event(rt::Workspace& ws, double t, double* y, int i, const JumpSolver& solve) {
  if (i < 0 || i >= Count()) return 0;
  const rt::WhenModel& w = program_.whens[static_cast<size_t>(clause_of_[static_cast<size_t>(i)])];
  last_ = EventRecord(t, w.name, w.terminate ? "terminate: " + w.message : "fires");
  if (int s = rt::EvalEventTape(program_, ws, t, y); s != 0) return s;
  std::vector<double> value;
  for (const rt::WhenReinit& r : w.reinits) value.push_back(rt::EventRoot(program_, ws, r.root));
  for (size_t k = 0; k < w.reinits.size(); ++k)
    if (!w.reinits[k].speed) y[w.reinits[k].state] = value[k];
  // Closed loops, rolling contacts: the jump keeps A u = 0, so the state is first put on the
  // constraints (else the integrator's drift off them, ~tolerance, would stay in the right limit).
  if (!program_.rows.empty() && !w.reinits.empty()) {
    std::vector<double> z(static_cast<size_t>(nq_ + nu_));
    if (rt::ProjectByPartition(program_, ws, t, y, z.data()) == 0) std::copy(z.begin(), z.end(), y);
  }
  std::vector<int> rows;
  std::vector<double> targets;
  for (size_t k = 0; k < w.reinits.size(); ++k)
    if (w.reinits[k].speed) rows.push_back(w.reinits[k].state - nq_), targets.push_back(value[k] - y[w.reinits[k].state]);
  if (!rows.empty()) {
    std::vector<double> du(static_cast<size_t>(nu_));
    const std::string said = rt::ErrorMessage(ws);  // a new message: a column's reason (a dead point)
    std::vector<int> stuck;  // joints whose friction impulse stops them (sim/friction_impulse.h)
    std::string why;
    const int s = solve       ? solve(rows, targets, du.data())
                  : friction_ ? FrictionSpeedJump(program_, ws, t, y, rows, targets, du.data(), &stuck, &why)
                              : SpeedJump(program_, ws, t, y, rows, targets, du.data());
    if (s != 0 && !why.empty()) {
      error_ = w.name + ": " + why;
      return s;
    }
    if (s != 0) {
      if (s == -1)
        error_ = rt::ErrorMessage(ws) != said && !rt::ErrorMessage(ws).empty() ? w.name + ": " + rt::ErrorMessage(ws)
                                                                               : SingularJump(w.name);
      return s;
    }
    for (int k = 0; k < nu_; ++k) y[nq_ + k] += du[static_cast<size_t>(k)];
    for (size_t k = 0; k < w.reinits.size(); ++k)  // exactly the values written (du's round-off aside)
      if (w.reinits[k].speed) y[w.reinits[k].state] = value[k];
    for (int f : stuck) y[nq_ + f] = 0.0;  // at rest exactly (du's round-off aside)
  }
  if (w.terminate) {
    terminated_ = true;
    message_ = w.message;
  }
  return 0;
}

}  // namespace kanesim::sim
