// End stops as events (sim/end_stops.h). An impact on joint k's stop changes the speeds by
// du = M^-1 e_k lambda (Kane's impulsive form M du = J^T lambda with the stop's row J = e_k^T),
// lambda chosen so that the joint's speed after is -e times its speed before (Newton); the
// joints resting on their stops keep zero speed through it (their rows join J). Resting, a
// joint's acceleration is held at zero by its stop's reaction the same way.
#include "sim/end_stops.h"

#include "sim/impulse.h"  // SolveSmall

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace kanesim::sim {

namespace {

std::string SideName(bool upper) { return upper ? "q_max" : "q_min"; }

}  // namespace

EndStopEvents::EndStopEvents(const rt::Program& program, double rtol, double atol)
    : program_(program), stops_(rt::EndStops(program)), rtol_(rtol), atol_(atol) {
  nq_ = rt::NumQ(program);
  nu_ = rt::NumU(program);
  for (size_t s = 0; s < stops_.size(); ++s) {
    if (std::isfinite(stops_[s].q_min)) sides_.push_back({static_cast<int>(s), false, false});
    if (std::isfinite(stops_[s].q_max)) sides_.push_back({static_cast<int>(s), true, false});
  }
  ydot_.resize(static_cast<size_t>(nq_ + nu_));
  a_.resize(static_cast<size_t>(nu_));
}

double EndStopEvents::Limit(const Side& s) const {
  const rt::EndStop& st = stops_[static_cast<size_t>(s.stop)];
  return s.upper ? st.q_max : st.q_min;
}

std::string EndStopEvents::CheckStart(const double* y0) const {
  for (const Side& s : sides_) {
    const rt::EndStop& st = stops_[static_cast<size_t>(s.stop)];
    const double q = y0[st.q], lim = Limit(s);
    if (s.upper ? q > lim : q < lim) {
      char buf[300];
      std::snprintf(buf, sizeof buf, "joint '%s' starts at q = %.17g, past its stop %s = %.17g", st.joint.c_str(), q,
                    SideName(s.upper).c_str(), lim);
      return buf;
    }
  }
  return {};
}

int EndStopEvents::Impulse(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                           const std::vector<double>& targets, double* du, std::vector<double>* c) {
  const size_t m = rows.size(), nu = static_cast<size_t>(nu_);
  x_.resize(m * nu);
  for (size_t j = 0; j < m; ++j)
    if (int s = rt::InverseMassColumn(program_, ws, t, y, rows[j], x_.data() + j * nu); s != 0) return s;
  std::vector<double> A(m * m);
  for (size_t r = 0; r < m; ++r)
    for (size_t j = 0; j < m; ++j) A[r * m + j] = x_[j * nu + static_cast<size_t>(rows[r])];
  if (!SolveSmall(A, targets, c)) return -1;
  for (size_t i = 0; i < nu; ++i) {
    double d = 0.0;
    for (size_t j = 0; j < m; ++j) d += x_[j * nu + i] * (*c)[j];
    du[i] = d;
  }
  return 0;
}

int EndStopEvents::Reactions(rt::Workspace& ws, double t, const double* y, std::vector<double>* lambda,
                             double* a_held) {
  lambda->assign(sides_.size(), 0.0);
  std::vector<int> rows;
  std::vector<size_t> which;
  for (size_t i = 0; i < sides_.size(); ++i)
    if (sides_[i].resting) rows.push_back(stops_[static_cast<size_t>(sides_[i].stop)].u), which.push_back(i);
  if (int s = rt::Derivative(program_, ws, t, y, ydot_.data()); s != 0) return s;
  const double* a = ydot_.data() + nq_;
  std::vector<double> targets(rows.size()), c;
  for (size_t j = 0; j < rows.size(); ++j) targets[j] = -a[rows[j]];
  std::vector<double> da(static_cast<size_t>(nu_), 0.0);
  if (!rows.empty()) {
    std::copy(a, a + nu_, a_.begin());  // Impulse's Derivative calls overwrite ydot_
    if (int s = Impulse(ws, t, y, rows, targets, da.data(), &c); s != 0) return s;
    for (size_t j = 0; j < rows.size(); ++j) (*lambda)[which[j]] = c[j];
    a = a_.data();
  }
  if (a_held)
    for (int i = 0; i < nu_; ++i) a_held[i] = a[i] + da[static_cast<size_t>(i)];
  return 0;
}

int EndStopEvents::Hold(rt::Workspace& ws, double t, const double* y, double* ydot) {
  bool any = false;
  for (const Side& s : sides_) any = any || s.resting;
  if (!any) return 0;
  std::vector<double> lambda;
  if (int s = Reactions(ws, t, y, &lambda, ydot + nq_); s != 0) return s;
  for (const Side& s : sides_) {
    if (!s.resting) continue;
    const rt::EndStop& st = stops_[static_cast<size_t>(s.stop)];
    ydot[st.q] = 0.0;
    ydot[nq_ + st.u] = 0.0;
  }
  return 0;
}

std::string EndStopEvents::CheckRow(double t, const double* y) const {
  for (const Side& s : sides_) {
    const rt::EndStop& st = stops_[static_cast<size_t>(s.stop)];
    const double q = y[st.q], lim = Limit(s);
    const double past = s.upper ? q - lim : lim - q;
    // Root finding leaves the state within the tolerance of the stop; a row farther past it
    // went through the stop.
    if (past > kPastRows * (atol_ + rtol_ * std::max(1.0, std::fabs(lim)))) {
      char buf[400];
      std::snprintf(buf, sizeof buf,
                    "joint '%s' is past its stop %s = %.9g by %.3g at time %.9g: an impact was missed "
                    "(accumulating impacts, a Zeno sequence, or two crossings within one step are not "
                    "handled yet)",
                    st.joint.c_str(), SideName(s.upper).c_str(), lim, past, t);
      return buf;
    }
  }
  return "";
}

int EndStopEvents::Functions(rt::Workspace& ws, double t, const double* y, double* g) {
  bool any = false;
  for (const Side& s : sides_) any = any || s.resting;
  std::vector<double> lambda;
  if (any)
    if (int s = Reactions(ws, t, y, &lambda, nullptr); s != 0) return s;
  for (size_t i = 0; i < sides_.size(); ++i) {
    const Side& s = sides_[i];
    const double q = y[stops_[static_cast<size_t>(s.stop)].q];
    g[i] = s.resting ? Reaction(s, lambda[i]) : (s.upper ? Limit(s) - q : q - Limit(s));
  }
  return 0;
}

int EndStopEvents::Event(rt::Workspace& ws, double t, double* y, int i) {
  if (i < 0 || i >= Count()) return 0;
  Side& side = sides_[static_cast<size_t>(i)];
  const rt::EndStop& st = stops_[static_cast<size_t>(side.stop)];
  const std::string where = SideName(side.upper);
  if (side.resting) {  // the reaction would pull: the joint leaves its stop
    side.resting = false;
    log_.push_back({t, st.joint, "leaves " + where});
    return 0;
  }
  y[st.q] = Limit(side);  // the root is located to round-off in t; the joint stands on the stop
  double* u = y + nq_;
  const double v = u[st.u];
  const bool into = side.upper ? v > 0.0 : v < 0.0;
  const double e = st.restitution;
  const bool rest = !into || e * std::abs(v) <= kRestSpeeds * (atol_ + rtol_ * std::abs(v));
  // The joint's speed change, the resting joints' held at zero.
  std::vector<int> rows = {st.u};
  std::vector<double> targets = {rest ? -v : -(1.0 + e) * v};
  for (const Side& s : sides_)
    if (s.resting) rows.push_back(stops_[static_cast<size_t>(s.stop)].u), targets.push_back(0.0);
  std::vector<double> du(static_cast<size_t>(nu_)), c;
  if (int s = Impulse(ws, t, y, rows, targets, du.data(), &c); s != 0) return s;
  for (int k = 0; k < nu_; ++k) u[k] += du[static_cast<size_t>(k)];
  u[st.u] = rest ? 0.0 : -e * v;  // exactly Newton's law (du's round-off aside)
  for (const Side& s : sides_)
    if (s.resting) u[stops_[static_cast<size_t>(s.stop)].u] = 0.0;
  char buf[120];
  std::snprintf(buf, sizeof buf, "impact at %s, speed %.17g -> %.17g", where.c_str(), v, u[st.u]);
  log_.push_back({t, st.joint, buf});
  if (!rest) return 0;
  // At rest on the stop: held while the stop pushes; pulled away, it leaves at once.
  side.resting = true;
  std::vector<double> lambda;
  if (int s = Reactions(ws, t, y, &lambda, nullptr); s != 0) return s;
  if (Reaction(side, lambda[static_cast<size_t>(i)]) > 0.0)
    log_.push_back({t, st.joint, "rests on " + where});
  else
    side.resting = false;
  return 0;
}

int EndStopEvents::Start(rt::Workspace& ws, double t0, double* y0) {
  for (int i = 0; i < Count(); ++i) {
    const Side& s = sides_[static_cast<size_t>(i)];
    const rt::EndStop& st = stops_[static_cast<size_t>(s.stop)];
    const double v = y0[nq_ + st.u];
    if (y0[st.q] == Limit(s) && (s.upper ? v >= 0.0 : v <= 0.0))
      if (int r = Event(ws, t0, y0, i); r != 0) return r;
  }
  return 0;
}

}  // namespace kanesim::sim
