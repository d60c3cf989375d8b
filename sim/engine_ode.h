// Internal to sim: the engine's equations of motion as an OdeSystem, shared by Simulate (one
// run, sim/simulate.cpp) and the stepping core (sim/simulator.h). Not part of the public API.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/change_point_bridge.h"
#include "sim/end_stops.h"
#include "sim/lift_off.h"
#include "sim/stick_slip.h"
#include "sim/when_events.h"
#include "sim/integrator.h"

namespace kanesim::sim::detail {

// The engine's equations of motion as an ODE: y = [q, u], y' = rt::Derivative.
class EngineOde final : public OdeSystem {
 public:
  EngineOde(const rt::Program& program, rt::Workspace& ws, bool row_energy)
      : program_(program), ws_(ws) {
    bridge_ = MakeChangePointBridge(program);
    // Closed loops on the multiplier form: P maps onto the state manifold, of dimension
    // (nq - nu) + 2 dof (OdeSystem::NewtonRank).
    if (bridge_ && !CanProject()) {
      const rt::ProgramSummary s = rt::Summarize(program);
      newton_rank_ = s.nq - s.nu + 2 * s.dof;
    }
    // Rows checked against the energy: closed loops (where change points are) in a model
    // that conserves T + V.
    if (row_energy && bridge_ && rt::NonConservativeCause(program).empty()) {
      std::string error;
      energy_plan_ = rt::PlanSignals(program, {"kinetic_energy", "potential_energy"}, &error);
    }
  }
  int Size() const override { return rt::StateSize(program_); }
  int Rhs(double t, const double* y, double* ydot) override {
    from_monitor_ = false;
    // Exact friction's evaluations hold the resting stops themselves (StickSlipEvents::SetStops).
    int s = stick_ ? stick_->Rhs(ws_, t, y, ydot) : rt::Derivative(program_, ws_, t, y, ydot);
    if (stops_ && !stick_ && s == 0) s = stops_->Hold(ws_, t, y, ydot);
    if (fault_ && s == 0) fault_(t, y, ydot);
    return s;
  }
  // The model's inputs (rt::InputSource; not owned) on every workspace this system evaluates
  // on: the right-hand side's, the bridge's and the ones it makes aside.
  void SetInputs(const rt::InputSource* inputs) {
    inputs_ = inputs;
    rt::SetInputSource(ws_, inputs);
    if (bridge_ && bridge_->ws) rt::SetInputSource(*bridge_->ws, inputs);
    if (aside_) rt::SetInputSource(*aside_, inputs);
    if (energy_ws_) rt::SetInputSource(*energy_ws_, inputs);
    if (lift_) lift_->SetInputs(inputs);
  }
  // End stops and plane contacts (sim/end_stops.h), or rolling contacts' normal forces
  // (sim/lift_off.h; the compiler never lets both in one model): their events; none without.
  void SetStops(EndStopEvents* stops) {
    stops_ = stops;
    if (stick_) stick_->SetStops(stops_);
    if (stops_) stops_->SetStickSlip(stick_);
    state_names_ = rt::StateNames(program_);
  }
  void SetLiftOff(LiftOffGuard* lift) {
    lift_ = lift;
    if (lift_ && inputs_) lift_->SetInputs(inputs_);
  }
  // Exact stick-slip friction (sim/stick_slip.h): its laws in the right-hand side, its events.
  void SetStickSlip(StickSlipEvents* stick) {
    stick_ = stick;
    if (stick_) stick_->SetStops(stops_);
    if (stops_) stops_->SetStickSlip(stick_);
    state_names_ = rt::StateNames(program_);
  }
  // When clauses (sim/when_events.h): their events after those above.
  void SetWhens(WhenEvents* whens) {
    whens_ = whens;
    state_names_ = rt::StateNames(program_);
  }
  // The first events: the stops' and plane contacts' or lift-off's (never both in one model),
  // then stick-slip's (with stops: constant friction only); then the when clauses'.
  int NumStops() const { return FirstStick() + (stick_ ? stick_->Count() : 0); }
  // Then the stops' and plane contacts' graze guards (OdeSystem::Paired): minus each gap's rate;
  // then exact friction's: minus each sliding joint's acceleration along its slide.
  int NumEvents() const override { return FirstStickGuard() + (stick_ ? stick_->Count() : 0); }
  bool Holding() const override {
    return (stick_ && stick_->AnyStuck()) || (stops_ && stops_->AnyResting());
  }
  void HeldEvents(std::vector<int>* events) const override {
    events->clear();
    if (stops_) {
      const std::vector<char> resting = stops_->RestingSet();
      for (size_t i = 0; i < resting.size(); ++i)
        if (resting[i]) events->push_back(static_cast<int>(i));
    }
    for (int k = 0; stick_ && k < stick_->Count(); ++k)
      if (stick_->ModeOf(k) == 0) events->push_back(FirstStick() + k);
  }
  bool IteratedRhs() const override { return stick_ && stick_->ReadsNormalForce(); }
  int Paired(int i) const override {
    if (stick_ && i >= FirstStickGuard()) return FirstStick() + i - FirstStickGuard();
    return stops_ && i >= FirstGuard() ? i - FirstGuard() : -1;
  }
  int EventFunctions(double t, const double* y, double* g) override {
    if (stick_) {  // first: it solves the stuck joints' forces the stops' reactions read
      if (const int s = stick_->Functions(ws_, t, y, g + FirstStick()); s != 0) return s;
      stick_->Guards(g + FirstStickGuard());
    }
    if (FirstStick() > 0) {
      const int s = stops_ ? stops_->Functions(ws_, t, y, g, g + FirstGuard()) : lift_->Functions(t, y, g);
      if (s != 0) return s;
    }
    return whens_ ? whens_->Functions(ws_, t, y, g + NumStops()) : 0;
  }
  int Event(double t, double* y, int i) override {
    if (i < FirstStick() && !stops_) {
      event_cause_ = lift_->Cause(t, y, i);  // a rolling contact would pull: the run stops
      return -1;
    }
    std::vector<double> before(y, y + Size());
    const size_t first = events_.size();
    int s = 0;
    if (i < FirstStick()) {
      const size_t logged = stops_->Log().size(), logged_stick = stick_ ? stick_->Log().size() : 0;
      stops_->DeferFrictionReleases(stick_ != nullptr);
      s = stops_->Event(ws_, t, y, i);
      stops_->DeferFrictionReleases(false);
      if (stick_ && s == 0)  // an impulse sets stuck joints moving; a rest takes its joint
        s = stick_->Refresh(ws_, t, y, before.data(), stops_->RestSpeed());
      if (stick_ && s == 0) s = SettleHeldAtStops(t, y);
      events_.insert(events_.end(), stops_->Log().begin() + static_cast<long>(logged), stops_->Log().end());
      if (stick_)
        events_.insert(events_.end(), stick_->Log().begin() + static_cast<long>(logged_stick), stick_->Log().end());
    } else if (i < NumStops()) {
      const size_t logged = stick_->Log().size(), logged_stops = stops_ ? stops_->Log().size() : 0;
      s = stick_->Event(ws_, t, y, i - FirstStick());
      if (stops_ && s == 0) {  // a slip into the stop the joint sits on rests there; a pulled stop leaves
        std::vector<char> was = stops_->RestingSet();  // (each pass logs its own changes)
        const int k = i - FirstStick();
        if (stick_->ModeOf(k) != 0) s = stops_->RestOn(ws_, t, y, stick_->SpeedOf(k), stick_->ModeOf(k));
        // The stop's joint freed of its friction, then settled; again while the laws the last
        // pass left slide a joint at rest by its stop into it (robot sweep 22, trial 3: Panda's
        // joint6 reversed 1.5e-5 s after an impact had let joint3 go from q_min at 1.5e-6
        // rad/s, which then accelerated back into q_min: exit 2 "... without resting on it" in
        // all five integrators), as after a stop's event (SettleHeldAtStops).
        for (int pass = 0; s == 0 && (pass < 2 || (pass < kSettlePasses && !UnseenSide(t, y).empty())); ++pass) {
          const std::vector<double> settled(y, y + Size());
          // The resting stops' reactions with the stuck joints' forces solved under the new
          // law (as SettleHeldAtStops): with the forces from before it, a joint held at its
          // stop with friction was let go where the stop held it (issue 41: j1's reversal
          // released j[4] from q_max on a pull of -1.88 beyond 0.13; held, its margin is
          // +0.59), and it slid into the stop unseen.
          if (pass >= 1) s = stick_->Resolve(ws_, t, y);
          if (pass >= 1 && s == 0) s = stops_->Resettle(ws_, t, y, was);
          if (pass >= 1) was = stops_->RestingSet();
          if (s == 0) s = stick_->Refresh(ws_, t, y, settled.data(), stops_->RestSpeed());
        }
      }
      events_.insert(events_.end(), stick_->Log().begin() + static_cast<long>(logged), stick_->Log().end());
      if (stops_)
        events_.insert(events_.end(), stops_->Log().begin() + static_cast<long>(logged_stops), stops_->Log().end());
    } else {
      const int w = i - NumStops();
      const size_t logged = stops_ ? stops_->Log().size() : 0;
      if (!stops_) {
        s = whens_->Event(ws_, t, y, w, {});
        events_.push_back(whens_->Last());
      } else {  // the contacts it sets leave their rest, the others held (EndStopEvents::Jump, HeldJump)
        auto held = [&](const std::vector<int>& rows, const std::vector<double>& targets, double* du,
                        std::vector<double>* F) {
          return stops_->HeldJump(ws_, t, y, rows, targets, du, F);
        };
        stops_->DeferFrictionReleases(stick_ != nullptr);
        s = stops_->Jump(ws_, t, y, whens_->Name(w), whens_->States(w), [&]() {
          const int r = whens_->Event(ws_, t, y, w, held);
          events_.push_back(whens_->Last());
          return r;
        });
        stops_->DeferFrictionReleases(false);
      }
      if (stick_ && s == 0) {  // exact friction: a joint the jump set moving slides, one it stopped decides
        const size_t logged_stick = stick_->Log().size();
        s = stick_->Refresh(ws_, t, y, before.data(), stops_ ? stops_->RestSpeed() : 0.0);
        if (stops_ && s == 0) s = SettleHeldAtStops(t, y);
        events_.insert(events_.end(), stick_->Log().begin() + static_cast<long>(logged_stick), stick_->Log().end());
      }
      if (stops_)
        events_.insert(events_.end(), stops_->Log().begin() + static_cast<long>(logged), stops_->Log().end());
    }
    if (s == 0 && stops_ && stick_ && !UnseenSide(t, y).empty()) s = SettleTogether(t, y);
    if (s == 0 && stops_) s = CheckUnseen(t, y);
    if (s == 0 && i >= NumStops() && bridge_ && bridge_->monitor) rt::ForgetBranchReference(*bridge_->monitor);
    if (s == 0 && first < events_.size()) AddChanges(state_names_, before.data(), y, &events_[first], &events_.back());
    return s;
  }
  bool Terminated(std::string* why) const override {
    if (!whens_ || !whens_->Terminated()) return false;
    *why = whens_->Message();
    return true;
  }
  // The stops' and when clauses' events of the run, in time order, with their jumps.
  const std::vector<EventRecord>& Events() const { return events_; }
  void SetFault(std::function<void(double, const double*, double*)> f) { fault_ = std::move(f); }
  bool ChecksSteps() const override { return bridge_ != nullptr; }
  int StepAccepted(double t, const double* y) override {
    const int s = CheckStep(program_, *bridge_, t, y);
    from_monitor_ = s != 0;
    return s;
  }
  std::string FailureCause() const override {
    if (!event_cause_.empty()) return event_cause_;
    if (from_monitor_) return BridgeError(*bridge_);
    if (stops_ && !stops_->Error().empty()) return stops_->Error();  // an impulse or reaction without solution
    if (whens_ && !whens_->Error().empty()) return whens_->Error();
    if (stick_ && !stick_->Error().empty()) return stick_->Error();  // stuck joints the constraints make dependent
    const std::string& m = rt::ErrorMessage(ws_);
    return m.empty() ? "the equations of motion could not be evaluated" : m;
  }
  bool Bridge(double rtol, double atol, double* t_from, double* t_b, double* y_b) override {
    return bridge_ && BridgeChangePoint(program_, *bridge_, rtol, atol, t_from, t_b, y_b) == 0;
  }
  void BridgeState(double t, double* y) override { BridgedState(*bridge_, t, y); }
  bool InZone() const override { return hold_rows_ && bridge_ && bridge_->in_zone; }
  void SetHoldRows(bool on) { hold_rows_ = on; }
  void EnableEarlyBridge(double rtol, double atol, const BridgeSwitches& switches) {
    if (bridge_) {
      bridge_->switches = switches;
      sim::EnableEarlyBridge(*bridge_, rtol, atol);
    }
  }
  void PassageCounts(long* checked, long* unchecked) const {
    *checked = bridge_ ? bridge_->passages_checked : 0;
    *unchecked = bridge_ ? bridge_->passages_unchecked : 0;
  }
  bool CanProject() const override { return rt::StepProjectionAvailable(program_); }
  void EnableStepProjection() override { rt::SetStepProjection(ws_, true); }
  void HoldForJacobian(bool on) override { rt::HoldPartition(ws_, on); }
  bool ProjectedStates(std::vector<int>* states, double* diag) override {
    return rt::ProjectedStates(program_, ws_, states, diag);
  }
  int NewtonRank() const override { return newton_rank_; }
  int Project(double t, double* y) override { return rt::ProjectOntoConstraints(program_, ws_, t, y); }
  int ProjectAside(double t, double* y) override {
    // Closed loops on the reduced form only: the multiplier form's projection moves every
    // coordinate, and its state was not seen to drift (docs/constraints.md "A drifted state").
    if (bridge_ == nullptr || !CanProject()) return -1;
    if (!aside_) aside_ = Fresh();
    return rt::ProjectOntoConstraints(program_, *aside_, t, y);
  }
  bool HasEnergy() const override { return energy_plan_ != nullptr; }
  int Energy(double t, const double* y, double* T, double* V) override {
    if (!energy_ws_) energy_ws_ = Fresh();
    double v[2];
    const int s = rt::EvalSignals(program_, *energy_plan_, *energy_ws_, t, y, v);
    *T = v[0];
    *V = v[1];
    return s;
  }
  // Closed loops or rolling contacts on the multiplier form (CanProject: the reduced form).
  // Contacts without loops have no branch monitor, and CVODE-BDF's projection
  // (integrator_cvode.cpp ProjectStep) is needed there as much: without it the rolling
  // disk's lean grew from t = 1.8 at rtol 1e-5 (energy off by 6.1e-2) and the disk fell
  // flat at 1e-4.
  int ProjectAsideMultiplierForm(double t, double* y) override {
    if (CanProject()) return -1;
    if (multiplier_rows_ < 0) {
      const rt::ProgramSummary s = rt::Summarize(program_);
      multiplier_rows_ = s.solver == rt::SolverPath::Sparse && s.dof < s.nu ? 1 : 0;
    }
    if (multiplier_rows_ == 0) return -1;
    if (!aside_) aside_ = Fresh();
    return rt::ProjectOntoConstraints(program_, *aside_, t, y);
  }

 private:
  // After a jump and the friction laws it set (StickSlipEvents::Refresh): the joints held at
  // their stops with their friction (deferred in the jump's own Settle, which saw the old
  // laws) leave where the pull passes the static friction, with the stuck forces solved anew.
  // The laws that last Refresh decides may slide a joint at rest on its stop, not resting on
  // it, into it (friction sweep seed 9, trial 5: j[2], stopped by a plastic impact in a cascade
  // of three, could not stay stuck and slid back into q_min): the stops settle again under
  // those laws (it rests there), up to kSettlePasses times, while such a side is left.
  int SettleHeldAtStops(double t, double* y) {
    if (!stops_->HoldsWithFriction()) return 0;
    for (int pass = 0;; ++pass) {
      if (int s = stick_->Resolve(ws_, t, y); s != 0) return s;
      const std::vector<char> was = stops_->RestingSet();
      const std::vector<double> settled(y, y + Size());
      if (int s = stops_->Resettle(ws_, t, y, was); s != 0) return s;
      if (int s = stick_->Refresh(ws_, t, y, settled.data(), stops_->RestSpeed()); s != 0) return s;
      if (pass + 1 == kSettlePasses || UnseenSide(t, y).empty()) return 0;
    }
  }
  static constexpr int kSettlePasses = 4;
  // Where the settling above left a side at rest accelerating into its stop (the laws decided
  // in turns, friction's and the stops'), all of them as one problem, with constant friction
  // in a tree (StickSlipEvents::LawsWithStops); CheckUnseen then reads the laws it set.
  int SettleTogether(double t, double* y) {
    const size_t logged = stops_->Log().size(), logged_stick = stick_->Log().size();
    bool solved = false;
    const int s = stick_->LawsWithStops(ws_, t, y, &solved);
    events_.insert(events_.end(), stops_->Log().begin() + static_cast<long>(logged), stops_->Log().end());
    events_.insert(events_.end(), stick_->Log().begin() + static_cast<long>(logged_stick), stick_->Log().end());
    return s;
  }
  // A free side at rest on its contact accelerating into it under the present laws
  // (EndStopEvents::Unseen); the laws and forces are left as they are.
  // Its description, or "" (also where the motion cannot be evaluated there).
  std::string UnseenSide(double t, const double* y) {
    if (stops_->Unseen(ws_, t, y, nullptr).empty()) return "";  // (no side to check: no evaluation)
    std::vector<double> ydot(static_cast<size_t>(Size()));
    const std::vector<double> modes = stick_ ? stick_->Modes() : std::vector<double>{};
    const int st = Rhs(t, y, ydot.data());
    if (stick_) stick_->SetModes(modes);
    return st == 0 ? stops_->Unseen(ws_, t, y, ydot.data()) : std::string();
  }
  // After an event, under the laws it left: no free side at rest on its contact closing on
  // it (EndStopEvents::Unseen), whose crossing the root finding would never see; else -1
  // (the run stops with exit 2 at the event, naming the side). Where the motion cannot be
  // evaluated there, the fresh solver's first evaluation reports it. The stuck joints' laws
  // and forces are left as the event set them (the evaluation's warm start moved the rack
  // pair's stuck follower in LoopStopFriction.* to another path).
  int CheckUnseen(double t, const double* y) {
    event_cause_ = UnseenSide(t, y);
    return event_cause_.empty() ? 0 : -1;
  }
  int FirstGuard() const { return NumStops() + (whens_ ? whens_->Count() : 0); }
  int FirstStickGuard() const { return FirstGuard() + (stops_ ? stops_->Count() : 0); }
  int FirstStick() const { return stops_ ? stops_->Count() : lift_ ? lift_->Count() : 0; }
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> Fresh() const {
    auto ws = rt::MakeWorkspace(program_);
    rt::SetInputSource(*ws, inputs_);
    return ws;
  }

  const rt::Program& program_;
  const rt::InputSource* inputs_ = nullptr;  // SetInputs
  rt::Workspace& ws_;
  std::unique_ptr<ChangePointBridge> bridge_;  // closed loops: the branch monitor and the bridge
  EndStopEvents* stops_ = nullptr;             // end stops and plane contacts (null: none)
  LiftOffGuard* lift_ = nullptr;               // rolling contacts' normal forces (null: none)
  StickSlipEvents* stick_ = nullptr;           // exact stick-slip friction (null: none)
  std::string event_cause_;                    // why an event stopped the run ("" : none did)
  WhenEvents* whens_ = nullptr;                // when clauses (null: none)
  std::vector<std::string> state_names_;       // y's entries (rt::StateNames), for the events' changes
  std::vector<EventRecord> events_;            // stops', friction's and when clauses' events, in time order
  bool from_monitor_ = false;  // the last failure was the bridge's or the branch monitor's
  int newton_rank_ = -1;       // OdeSystem::NewtonRank
  int multiplier_rows_ = -1;   // the multiplier form with constraint rows: 1, 0; -1 not known yet
  bool hold_rows_ = true;      // TestHooks::hold_zone_rows
  std::function<void(double, const double*, double*)> fault_;  // TestHooks::rhs_fault
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> aside_{nullptr, [](rt::Workspace*) {}};  // ProjectAside's
  std::shared_ptr<const rt::SignalPlan> energy_plan_;  // T and V (null: rows not checked)
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> energy_ws_{nullptr, [](rt::Workspace*) {}};  // Energy's
};

}  // namespace kanesim::sim::detail
