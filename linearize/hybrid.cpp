// Hybrid operating points (hybrid.h).
#include "linearize/hybrid.h"

#include "sim/lift_off.h"

namespace kanesim::lin {

bool Hybrid::Present(const rt::Program& p) {
  return sim::EndStopEvents(p, kTol, kTol).Active() || sim::StickSlipEvents(p).Active();
}

Status Hybrid::Init(const rt::Program& p, const OperatingPoint& op, const std::vector<double>& w0) {
  p_ = &p;
  held_.clear();
  names_.clear();
  auto ws = rt::MakeWorkspace(p);
  if (!w0.empty()) rt::SetInputValues(*ws, w0.data());
  if (sim::LiftOffGuard lift(p); lift.Active())
    if (std::string why = lift.Cause(op.t, op.y.data(), -1); !why.empty())
      return {2, why + ": no linear model of a contact that pulls"};
  stops_ = std::make_unique<sim::EndStopEvents>(p, kTol, kTol);
  if (stops_->Active()) {
    bool bad = false;
    if (std::string why = stops_->SettleAt(*ws, op.t, op.y.data(), kTol, &bad); !why.empty())
      return {bad ? 1 : 2, why};
    for (const auto& [speed, plane] : stops_->HeldRows()) held_.push_back({speed, plane});
    names_ = stops_->HeldNames();
  } else {
    stops_.reset();
  }
  stick_ = std::make_unique<sim::StickSlipEvents>(p);
  if (stick_->Active()) {
    stick_->SetStops(stops_.get());  // a joint resting on its stop is held by the stop's row alone
    if (std::string why = stick_->SettleAt(*ws, op.t, op.y.data(), kTol); !why.empty()) return {2, why};
    for (int u : stick_->StuckSpeeds()) held_.push_back({u, -1});
    for (const std::string& n : stick_->StuckNames()) names_.push_back(n);
  } else {
    stick_.reset();
  }
  return {};
}

int Hybrid::Derivative(rt::Workspace& ws, double t, const double* y, double* ydot) {
  int s = stick_ ? stick_->Rhs(ws, t, y, ydot) : rt::Derivative(*p_, ws, t, y, ydot);  // stick_: stops held
  if (s == 0 && stops_ && !stick_) s = stops_->Hold(ws, t, y, ydot);
  if (s != 0 || (!stops_ && !stick_)) return s;
  // The held rows' reactions for the output signals EvalSignals reads next on ws (C and D).
  const std::vector<int> stuck = stick_ ? stick_->StuckSpeeds() : std::vector<int>{};
  if (stops_)
    stops_->LoadSignals(ws, stuck);
  else
    rt::SetHeldLoads(*p_, ws, nullptr, {}, stuck);
  return 0;
}

}  // namespace kanesim::lin
