// The equations with their events for an outside integrator (sim/hybrid_ode.h): the run's
// EngineOde with the event sources Simulate gives it, and its start.
#include "sim/hybrid_ode.h"

#include <cmath>

#include "runtime/program/program.h"  // Program::whens
#include "sim/engine_ode.h"
#include "sim/held_outputs.h"
#include "sim/input_table.h"

namespace kanesim::sim {

using WorkspacePtr = std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)>;

struct HybridOde::Impl {
  Impl(std::shared_ptr<const rt::Program> p, double rtol, double atol)
      : program(std::move(p)),
        inputs(rt::NumInputs(*program)),
        ws(rt::MakeWorkspace(*program)),
        stops(*program, rtol, atol),
        lift(*program),
        stick(*program),
        whens(std::make_unique<WhenEvents>(*program)),
        ode(*program, *ws, /*row_energy=*/false),
        run_rtol(rtol),
        run_atol(atol) {
    whens->SetTolerance(rtol);
    rt::SetInputSource(*ws, &inputs);
    ode.SetInputs(&inputs);
    if (stops.Active()) ode.SetStops(&stops);
    if (lift.Active()) ode.SetLiftOff(&lift);
    if (stick.Active()) ode.SetStickSlip(&stick);
    if (whens->Active()) ode.SetWhens(whens.get());
    g.resize(static_cast<size_t>(ode.NumEvents()));
  }
  std::shared_ptr<const rt::Program> program;
  ConstantInputs inputs;  // what every workspace reads
  WorkspacePtr ws;        // the right-hand side's and the events'
  EndStopEvents stops;    // end stops and plane contacts
  LiftOffGuard lift;      // rolling contacts' normal forces
  StickSlipEvents stick;  // exact stick-slip friction
  std::unique_ptr<WhenEvents> whens;  // remade by SetModes (a terminate is final in it)
  detail::EngineOde ode;
  std::vector<double> g;  // every event function, the graze guards too (scratch)
  std::vector<EventRecord> start_events;  // Start's, with their jumps
  double run_rtol;                        // the when clauses' accumulation test
  double run_atol;                        // the stops' (HeldOutputs, with run_rtol)
  std::unique_ptr<HeldOutputs> held;      // ForOutputs' held rows (made at its first call)
};

HybridOde::HybridOde(std::shared_ptr<const rt::Program> program, double rtol, double atol)
    : impl_(std::make_unique<Impl>(std::move(program), rtol, atol)) {}
HybridOde::~HybridOde() = default;

// Every event function, the graze guards last (EngineOde::Paired: minus an end stop's or
// plane contact's gap rate, crossing where the gap has a minimum). A master whose root
// finding brackets the guard's crossing also brackets a gap that dipped below zero and back
// inside its step, which the gap's signs at the step's ends do not show.
int HybridOde::NumIndicators() const { return impl_->ode.NumEvents(); }

std::vector<std::string> HybridOde::IndicatorNames() const {
  const Impl& m = *impl_;
  std::vector<std::string> names;
  if (m.stops.Active()) {
    for (int i = 0; i < m.stops.Count(); ++i) names.push_back(m.stops.Describe(i));
  } else if (m.lift.Active()) {
    for (const std::string& c : m.lift.Names()) names.push_back("normal force of contact '" + c + "'");
  }
  if (m.stick.Active())  // after the stops (sim/engine_ode.h NumStops)
    for (const std::string& j : m.stick.JointNames()) names.push_back("exact friction of joint '" + j + "'");
  for (const rt::WhenModel& w : m.program->whens)
    for (size_t k = 0; k < w.indicators.size(); ++k) names.push_back("condition of " + w.name);
  if (m.stops.Active())
    for (int i = 0; i < m.stops.Count(); ++i) names.push_back("graze guard of " + m.stops.Describe(i));
  if (m.stick.Active())
    for (const std::string& j : m.stick.JointNames()) names.push_back("graze guard of exact friction of joint '" + j + "'");
  return names;
}

void HybridOde::SetInputs(const std::vector<double>& values) {
  for (size_t i = 0; i < values.size() && i < impl_->inputs.values.size(); ++i) impl_->inputs.values[i] = values[i];
}

std::string HybridOde::Start(double t0, double* y0) {
  Impl& m = *impl_;
  const std::vector<double> given(y0, y0 + rt::StateSize(*m.program));
  if (std::string why = StartModes(t0, y0); !why.empty()) return why;
  // The start's events with what they changed, as a run logs them (sim/simulate.cpp).
  m.start_events.assign(m.stops.Log().begin(), m.stops.Log().end());
  m.start_events.insert(m.start_events.end(), m.stick.Log().begin(), m.stick.Log().end());
  if (!m.start_events.empty())
    AddChanges(rt::StateNames(*m.program), given.data(), y0, &m.start_events.front(), &m.start_events.back());
  return "";
}

std::string HybridOde::StartModes(double t0, double* y0) {
  Impl& m = *impl_;
  if (m.stops.Active()) {
    if (std::string why = m.stops.CheckStart(*m.ws, t0, y0); !why.empty()) return why;
    if (m.stops.Start(*m.ws, t0, y0) != 0) return "contacts at the start: " + rt::ErrorMessage(*m.ws);
  }
  if (m.lift.Active())
    if (std::string why = m.lift.Cause(t0, y0, -1); !why.empty()) return why;
  if (m.stick.Active() && m.stick.Start(*m.ws, t0, y0) != 0)
    return "friction at the start: " + (m.stick.Error().empty() ? rt::ErrorMessage(*m.ws) : m.stick.Error());
  return "";
}

int HybridOde::Derivatives(double t, const double* y, double* ydot) { return impl_->ode.Rhs(t, y, ydot); }

int HybridOde::Indicators(double t, const double* y, double* z) {
  Impl& m = *impl_;
  if (m.g.empty()) return 0;
  const int s = m.ode.EventFunctions(t, y, m.g.data());
  if (s != 0) return s;
  std::copy(m.g.begin(), m.g.end(), z);
  return 0;
}

int HybridOde::Event(double t, double* y, int i) {
  Impl& m = *impl_;
  if (i < 0 || i >= NumIndicators()) return 0;
  if (const int p = m.ode.Paired(i); p >= 0) {
    // A graze guard: the gap's minimum. Above the contact nothing happens; at or below it the
    // gap's own event (an impact), where the run's solvers also place it when they cannot
    // bracket the gap's crossing before the minimum.
    if (const int s = m.ode.EventFunctions(t, y, m.g.data()); s != 0) return s;
    if (m.g[static_cast<size_t>(p)] > 0.0) return 0;
    i = p;
  }
  return m.ode.Event(t, y, i);
}

bool HybridOde::Terminated(std::string* why) const { return impl_->ode.Terminated(why); }

std::string HybridOde::FailureCause() const { return impl_->ode.FailureCause(); }

std::vector<double> HybridOde::Modes() const {
  std::vector<double> modes = impl_->stops.Resting();
  const std::vector<double> stick = impl_->stick.Modes();
  modes.insert(modes.end(), stick.begin(), stick.end());
  return modes;
}

bool HybridOde::SetModes(const std::vector<double>& modes) {
  Impl& m = *impl_;
  const size_t n_stops = m.stops.Resting().size();
  if (modes.size() != n_stops + m.stick.Modes().size()) return false;
  // Values from outside (a master's serialized state): a side rests or not, accumulates
  // until a finite time, a joint slides either way, sticks with a finite force or is held by
  // resting stops or plane contacts (2) (and a leader: -1 or a joint's index,
  // StickSlipEvents::Modes).
  const size_t per = StickSlipEvents::kModeValues;
  const auto n_joints = static_cast<double>((modes.size() - n_stops) / per);
  for (size_t i = 0; i < modes.size(); ++i) {
    const double v = modes[i];
    const bool flag = i < n_stops ? i % 2 == 0 : (i - n_stops) % per == 0;
    const bool leader = i >= n_stops && (i - n_stops) % per == 2;
    if (!std::isfinite(v) || (flag && i < n_stops && v != 0.0 && v != 1.0) ||
        (flag && i >= n_stops && v != 0.0 && v != 1.0 && v != -1.0 && v != 2.0) ||
        (leader && (v != std::floor(v) || v < -1.0 || v >= n_joints)))
      return false;
  }
  m.stops.SetResting(std::vector<double>(modes.begin(), modes.begin() + static_cast<long>(n_stops)));
  m.stick.SetModes(std::vector<double>(modes.begin() + static_cast<long>(n_stops), modes.end()));
  m.whens = std::make_unique<WhenEvents>(*m.program);  // no terminate fired in the restored state
  m.whens->SetTolerance(m.run_rtol);
  if (m.whens->Active()) m.ode.SetWhens(m.whens.get());
  return true;
}

OdeSystem& HybridOde::System() { return impl_->ode; }

std::vector<EventRecord> HybridOde::StartEvents() const { return impl_->start_events; }

const std::vector<EventRecord>& HybridOde::Events() const { return impl_->ode.Events(); }

std::string HybridOde::ForOutputs(rt::Workspace& ws, double t, double* y, bool snap) {
  Impl& m = *impl_;
  if (snap && m.stops.AnyResting()) m.stops.SnapResting(y);
  if (!m.stops.Active() && !m.stick.Active()) return "";
  if (!m.held) m.held = std::make_unique<HeldOutputs>(*m.program, m.run_rtol, m.run_atol);
  if (m.held->Prepare(&m.stops, &m.stick, ws, t, y) == 0) return "";
  const std::string why = m.held->Error().empty() ? rt::ErrorMessage(ws) : m.held->Error();
  return why.empty() ? "the held contacts' reactions could not be evaluated" : why;
}

}  // namespace kanesim::sim
