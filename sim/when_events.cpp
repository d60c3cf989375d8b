// When clauses as events (sim/when_events.h). A reinit of speed k is the jump
// du = M^-1 J^T lambda, J the rows of the reinit'ed speeds (and of the resting contacts, held
// by EndStopEvents::HeldJump), lambda such that those speeds take their new values: the
// generalized impulse acts on the reinit'ed joints only, so every other joint's generalized
// momentum p_j = (M u)_j is unchanged across the jump.
//
// Accumulation (Zeno): a clause whose event intervals d_k shrink geometrically, d_k = r d_{k-1}
// with r < 1 (a ball written as `when h < 0 then reinit(v, -e * pre(v))`, r = e), fires
// infinitely often before the accumulation point of the series,
//   t_inf = t_k + d_k r / (1 - r)                                                    (1)
// where no integrator resolves the events (a step-size underflow, or a crossing missed and
// the ball falling through). kRatios consecutive ratios in (0, kMaxRatio) agreeing within
// kRatioSpread make the series geometric; the run then stops (exit 2, naming the clause and
// t_inf) at the event where less than kZenoTimes rtol max(1, |t|) is left to t_inf, or where
// the ratio breaks off close to t_inf (the events no longer resolved: within kZenoFraction of
// the geometric stretch's length). t_inf is (1) at the last event whose ratio changed by less
// than kRatioSteady: as the intervals shrink the events' location and integration errors, not
// the motion, move the ratio (CVODE-BDF at rtol 1e-12: t_inf 1.5e-6 off from the last ratio).
#include "sim/when_events.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "runtime/program/program.h"  // Program::whens
#include "sim/friction_impulse.h"
#include "sim/impulse.h"

namespace kanesim::sim {

namespace {
constexpr size_t kRatios = 4;          // consecutive interval ratios that make a series geometric
constexpr double kMaxRatio = 0.99;     // above: events slowing down, not accumulating
constexpr double kRatioSpread = 0.02;  // relative change of the ratio from one interval to the next
constexpr double kRatioSteady = 2e-3;  // t_inf from the last ratio this steady (later ones: the events' error)
constexpr double kZenoFraction = 1e-3;
}  // namespace

WhenEvents::WhenEvents(const rt::Program& program) : program_(program) {
  nq_ = rt::NumQ(program);
  nu_ = rt::NumU(program);
  friction_ = HasFrictionImpulses(program);
  for (size_t c = 0; c < program.whens.size(); ++c)
    for (int root : program.whens[c].indicators) {
      clause_of_.push_back(static_cast<int>(c));
      root_of_.push_back(root);
    }
  history_.resize(program.whens.size());
}

std::string WhenEvents::Accumulation(int c, double t) {
  History& h = history_[static_cast<size_t>(c)];
  h.times.push_back(t);
  if (h.times.size() > kRatios + 2) h.times.erase(h.times.begin());
  const size_t n = h.times.size();
  if (n < 3) return "";
  auto interval = [&](size_t k) { return h.times[k] - h.times[k - 1]; };  // k >= 1
  auto agree = [](double r, double before) {
    return r > 0.0 && r < kMaxRatio && std::abs(r - before) <= kRatioSpread * before;
  };
  const double d = interval(n - 1), r = d / interval(n - 2);
  const double scale = std::max(1.0, std::abs(t));
  char buf[400];
  auto stop = [&](double t_inf) {
    std::snprintf(buf, sizeof buf,
                  ": its events accumulate (Zeno): the intervals between them shrink geometrically (ratio %.6g) "
                  "to an accumulation point at t = %.15g (estimated from the geometric series), which no "
                  "integrator passes; a when clause cannot rest there: write the contact as a PlaneContact or an "
                  "end stop (q_min, q_max with restitution), which pass to rest at the accumulation point",
                  h.ratio, t_inf);
    return program_.whens[static_cast<size_t>(c)].name + buf;
  };
  if (h.geometric) {
    if (agree(r, h.ratio)) {
      if (std::abs(r - h.ratio) <= kRatioSteady * h.ratio) h.t_inf = t + d * r / (1.0 - r);  // (1)
      h.ratio = r;
      return h.t_inf - t <= kZenoTimes * rtol_ * scale ? stop(h.t_inf) : "";
    }
    if (h.t_inf - t <= kZenoFraction * (h.t_inf - h.since)) return stop(h.t_inf);  // no longer resolved
    h.geometric = false;  // the motion changed: a new series may start
    return "";
  }
  if (n < kRatios + 2) return "";
  for (size_t k = 3; k < n; ++k)
    if (!agree(interval(k) / interval(k - 1), interval(k - 1) / interval(k - 2))) return "";
  h.geometric = true;
  h.since = h.times.front();
  h.ratio = r;
  h.t_inf = t + d * r / (1.0 - r);
  return h.t_inf - t <= kZenoTimes * rtol_ * scale ? stop(h.t_inf) : "";
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
  if (std::string why = Accumulation(clause_of_[static_cast<size_t>(i)], t); !why.empty()) {
    error_ = why;
    return -1;
  }
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
    std::vector<double> F;  // the jump's generalized impulse: the contacts' normal impulses follow
    const int s = solve       ? solve(rows, targets, du.data(), &F)
                  : friction_ ? FrictionSpeedJump(program_, ws, t, y, rows, targets, du.data(), &stuck, &why, &F)
                              : SpeedJump(program_, ws, t, y, rows, targets, du.data(), &F);
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
    // A rolling contact whose impulse would pull: the run stops at the event (the rows before kept).
    if (F.size() == du.size()) {
      int status = 0;
      if (std::string pull = PullingContact(program_, ws, t, y, du, F, &status); !pull.empty()) {
        error_ = w.name + ": " + pull;
        return status != 0 ? status : -1;
      }
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
