// Unilateral contacts as events (docs/integrators.md "End stops"; docs/stdlib.md
// "PlaneContact"): end stops (q_min / q_max of Revolute and Prismatic) and plane contacts, each
// a gap g >= 0 with a row J (dg/dt = J u). A gap closing is an event; the impact is a jump of
// the speeds by a generalized impulse through the mass matrix (Kane's impulsive form
// M du = J^T lambda, Newton's restitution); a contact at rest is held by its reaction (one
// more row) until that reaction would pull; bounces that accumulate (Zeno) pass to rest at
// their accumulation time.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "runtime/runtime.h"
#include "sim/simulate.h"

namespace kanesim::sim {

class StickSlipEvents;

class EndStopEvents {
 public:
  // rtol, atol: the run's; a rebound slower than kRestSpeeds of them rests on the stop.
  EndStopEvents(const rt::Program& program, double rtol, double atol);
  bool Active() const { return !sides_.empty(); }
  int Count() const { return static_cast<int>(sides_.size()); }
  // Why the start state cannot run ("" when it can): a joint past its stop, a point below its plane.
  std::string CheckStart(rt::Workspace& ws, double t0, const double* y0);
  // Why an output row cannot be trusted ("" when it can): a gap negative by more than the
  // tolerance's reach, which an event missed (a graze inside one step). The run then stops
  // (exit 2) rather than write a motion through the stop or the plane.
  std::string CheckRow(rt::Workspace& ws, double t, const double* y);
  // Why the state after an event cannot go on ("" when it can): a free side at rest on its
  // contact (gap within the tolerance's reach, rate a rest speed) whose gap accelerates into
  // it under ydot (the laws the event left, every stuck force solved): its event function
  // starts at 0 and falls, a crossing the root finding never sees (a joint let go from its
  // stop with its friction that slides back into it). ydot null: "?" where some free side is
  // at rest on its contact (ydot is needed), else "".
  std::string Unseen(rt::Workspace& ws, double t, const double* y, const double* ydot);
  // The start on a contact: a gap closed and closing, or at rest pressed shut, handled as an
  // event at t0 (no rows).
  int Start(rt::Workspace& ws, double t0, double* y0);
  // ydot (from rt::Derivative at (t, y)) with the resting contacts held: their gaps'
  // accelerations made zero by their reactions. 0, or Derivative's status codes.
  int Hold(rt::Workspace& ws, double t, const double* y, double* ydot);
  // Hold with more rows: the free speeds `speeds` (joints stuck by their friction) held at zero
  // acceleration by generalized forces on them (*forces, their increments over the forces in
  // ydot), solved with the resting contacts' reactions as one system from one factorization
  // of the inverse mass (M udot = f + A^T lambda, A udot = b).
  int HoldWith(rt::Workspace& ws, double t, const double* y, double* ydot, const std::vector<int>& speeds,
               std::vector<double>* forces);
  // g_i: a free side's gap, a resting one's reaction (pushing: > 0), an accumulating one's
  // time left to its accumulation point. guards (may be null): a free side's graze guard,
  // minus its gap's rate (crossing zero downwards where the gap has a minimum); 1 for the others.
  int Functions(rt::Workspace& ws, double t, const double* y, double* g, double* guards = nullptr);
  // Event function i crossed zero at (t, y): an impact (or the contact comes to rest), a
  // resting contact leaves, or accumulated bounces end. y jumps in place.
  int Event(rt::Workspace& ws, double t, double* y, int i);
  // After the forces outside the stops changed at (t, y) (a joint's exact friction slipped or
  // stuck): the resting set made consistent as after an event (a joint slipping into the stop
  // it sits on rests there; a resting side now pulled leaves). y jumps in place.
  // `before`: the resting set to log the changes against (RestingSet() before the change).
  int Resettle(rt::Workspace& ws, double t, double* y, const std::vector<char>& before) {
    released_.clear();
    return Settle(ws, t, y, before);
  }
  // The joint of free speed u started to slide in direction dir (+1 / -1) from rest: on the
  // stop it slides into (its gap within the tolerance) it rests at once (Resettle then).
  // (Where its static and sliding friction are equal it slips with zero acceleration, whose
  // sign Settle's test would leave to round-off; the gap, from exactly 0, would then close
  // without a crossing for the root finding.)
  int RestOn(rt::Workspace& ws, double t, double* y, int u, int dir);
  // The same beside constraint rows, for every closed stop the slide moves (sim/end_stops.cpp).
  int RestOnRows(rt::Workspace& ws, double t, double* y, int u, int dir);
  std::vector<char> RestingSet() const;
  // The laws at rest solved together (StickSlipEvents::LawsWithStops): the stops' sides at
  // rest at (t, y), resting ones and free ones on their stop (the gap within kPastRows of the
  // tolerance, the joint's speed a rest speed, as Unseen reads them). False where a plane
  // contact or an accumulation of bounces takes part (their rows are not one speed's).
  struct StopAtRest {
    int side = -1, u = -1;  // the side, its joint's free speed
    bool upper = false, resting = false;
  };
  bool StopsAtRest(double t, const double* y, std::vector<StopAtRest>* out) const;
  // The sides rest as `resting` says (per side) from t, each change logged with `why` (null:
  // not logged); a side set resting has its joint's speed 0 and its coordinate on the stop
  // where it was past it.
  void SetRestingSides(double t, double* y, const std::vector<char>& resting, const char* why);
  // A speed this small after an event is a rest (kRestSpeeds (atol)).
  double RestSpeed() const { return kRestSpeeds * atol_; }
  // A when clause's jump at (t, y) (sim/when_events.h, docs/events.md "Statements"): the
  // contacts whose motion it sets leave their rest (a stop whose joint's coordinate or speed
  // is in `states`, indices into y; a plane contact whose row has only speeds it sets, or
  // every plane contact when it sets a coordinate); `jump()` moves y (its speeds through
  // HeldJump); then the resting set is made consistent (Settle): a released contact moving
  // into its stop or plane strikes it (its restitution), one set at rest there rests again, a
  // side the jump made pull leaves. `clause` names the clause in the error of a jump that
  // sets a contact past its stop or plane.
  int Jump(rt::Workspace& ws, double t, double* y, const std::string& clause, const std::vector<int>& states,
           const std::function<int()>& jump);
  // A when clause's speed jump du at (t, y): the free speeds `speeds` change by `targets`, the
  // resting contacts' gap rates held at zero by impulses that push; one whose impulse would
  // pull leaves its rest (the Settle after the jump logs it). 0, Derivative's codes, or -1
  // (Error(): the rows are dependent).
  // F (non-null): the jump's generalized impulse on the free speeds (PullingContact's input).
  int HeldJump(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds,
               const std::vector<double>& targets, double* du, std::vector<double>* F = nullptr);
  const std::vector<EventRecord>& Log() const { return log_; }
  // Why the last impulse or reaction had no solution ("" after one that had).
  const std::string& Error() const { return error_; }
  bool AnyResting() const {
    for (const Side& s : sides_)
      if (s.resting && s.stop >= 0) return true;
    return false;
  }
  // A stop or a plane contact at rest.
  bool AnyHeld() const {
    for (const Side& s : sides_)
      if (s.resting) return true;
    return false;
  }
  // The resting sides' reactions of the last Hold / HoldWith into ws for its output signals
  // (rt::SetHeldLoads), with the free `speeds` (stuck joints') held too.
  void LoadSignals(rt::Workspace& ws, std::vector<int> speeds) const;
  // An output row's state: the joints resting on their stops at speed 0 (the integrator holds
  // them so; its interpolant between steps may miss by an ulp), exactly on the stop where they
  // rest on it to round-off or past it. A joint that came to rest short of its stop by the tolerance's
  // reach rests there (OntoStop), and its rows say so.
  void SnapResting(double* y) const {
    for (const Side& s : sides_)
      if (s.resting && s.stop >= 0) {
        const rt::EndStop& st = stops_[static_cast<size_t>(s.stop)];
        const double limit = s.upper ? st.q_max : st.q_min;
        const double short_by = s.upper ? limit - y[st.q] : y[st.q] - limit;
        if (short_by <= 16.0 * std::numeric_limits<double>::epsilon() * (1.0 + std::abs(limit))) y[st.q] = limit;
        y[nq_ + st.u] = 0.0;
      }
  }
  // What function i watches: "joint 'hinge' at q_min", "contact 'foot' at the plane".
  std::string Describe(int i) const {
    const Side& s = sides_[static_cast<size_t>(i)];
    return Who(s) + " at " + Where(s);
  }
  // The free speeds of the joints resting on their stops (held at zero).
  std::vector<int> RestingSpeeds() const {
    std::vector<int> out;
    for (const Side& s : sides_)
      if (s.resting && s.stop >= 0) out.push_back(stops_[static_cast<size_t>(s.stop)].u);
    return out;
  }
  // linearize's operating point (docs/linearize.md "End stops, contacts and friction"): the
  // sides closed at (t, y) (gap within tol of its scale) rest from now and are held; "" when
  // that is a smooth state, else why not: a side past its stop (*bad set), closed and moving
  // (an impact or a lift-off instant), or held by a reaction that would pull.
  std::string SettleAt(rt::Workspace& ws, double t, const double* y, double tol, bool* bad);
  // The resting sides' rows: (the joint's free speed, -1) for a stop, (-1, index) for a plane
  // contact; their elements ("j1 on q_min").
  std::vector<std::pair<int, int>> HeldRows() const;
  std::vector<std::string> HeldNames() const;
  // Per side, whether its joint rests on it (the stepping core's state, sim/simulator.h).
  // Per side: 1 when it rests, and where accumulated bounces end (2 numbers a side).
  std::vector<double> Resting() const {
    std::vector<double> r;
    for (const Side& s : sides_) {
      r.push_back(s.resting ? 1.0 : 0.0);
      r.push_back(s.accumulates_at);
    }
    return r;
  }
  void SetResting(const std::vector<double>& r) {
    pinned_for_.clear();  // (computed again for the state restored)
    for (size_t i = 0; i < sides_.size() && 2 * i + 1 < r.size(); ++i) {
      sides_[i].resting = r[2 * i] != 0.0;
      sides_[i].accumulates_at = r[2 * i + 1];
    }
  }

  // A rebound speed at most this many times (atol + rtol |speed before|) ends in rest.
  static constexpr double kRestSpeeds = 100.0;
  static constexpr double kLiftRoundoffs = 64.0;  // Side::lift (the gap's noise measured: ~6)
  // An output row past a stop by more than this many (atol + rtol max(1, |limit|)) stops the run.
  static constexpr double kPastRows = 10.0;
  // Bounces accumulate (Zeno) when the next flight's height v^2 / (2 |a|) (rebound speed v,
  // the gap's free acceleration a towards the contact) is at most this many (atol + rtol
  // max(1, |limit|)): lower flights are not resolved by the root finding.
  static constexpr double kZenoHeights = 100.0;
  // A side leaving its contact (lifted off by an impulse, or its rebound) rests at once when
  // its flight's height is at most this many (atol + rtol max(1, |limit|)) (Unresolved): the
  // gap's own error. (Not kZenoHeights: a lifted joint's real flight of 0.019 s and some 1e-4
  // rad in EndStopEvents.ChainUnderArkodeAgreesWithDop853AtEveryTolerance was lost at 1e-5.)
  static constexpr double kUnresolvedHeights = 1.0;
  // The joints a Settle took off their stops with their friction at its static bound (a
  // pull beyond it; sim/end_stops.cpp (3)): (free speed, the direction
  // it slides, +1 / -1). Cleared by the call; StickSlipEvents::Refresh sets them sliding.
  std::vector<std::pair<int, int>> TakeReleased() {
    std::vector<std::pair<int, int>> r;
    r.swap(released_);
    return r;
  }
  // While on: Settle keeps the joints held at their stops with their friction (releases none
  // of them): after a jump, the other joints' friction laws are stale until
  // StickSlipEvents::Refresh has set them (sim/engine_ode.h settles again then).
  void DeferFrictionReleases(bool on) { defer_ = on; }
  // Exact friction beside the stops (set by the engine, sim/engine_ode.h): Settle then
  // releases the joints held at their stops with their friction together, each choice with
  // the stuck joints' forces solved for it (ReleaseTogether). Null: one at a time.
  void SetStickSlip(StickSlipEvents* stick) { stick_ = stick; }
  bool HoldsWithFriction() const {  // a stop whose joint has exact (static) friction
    return std::any_of(friction_of_.begin(), friction_of_.end(), [](int f) { return f >= 0; });
  }
  // A resting side leaves where its reaction pulls by more than this many round-offs (plus
  // rtol) of the terms it is computed from (ReactionNoise): a reaction that is zero in exact
  // arithmetic (a floating robot in free fall on its stops) has a sign set by round-off and
  // the state's error, and leaving on it made the joint leave and strike again every step.
  static constexpr double kLeaveRoundoffs = 100.0;
  // A row whose residual against the resting rows is below this part of its norm is pinned.
  static constexpr double kPinnedRows = 1e-8;

 private:
  struct Side {
    int stop = -1;       // end stop (index into stops_), or -1
    int plane = -1;      // plane contact (index into planes_), or -1
    bool upper = false;  // a stop's q_max (else q_min)
    bool resting = false;
    double accumulates_at = 0.0;  // resting through accumulated bounces until then (0: not)
    // After a rebound the state is a round-off from the contact (a plane's gap is a function
    // of all coordinates: -2e-14 .. 2e-14 at |n . x| ~ 0.35 where the impact left it), and the
    // gap's own noise over the next 1e-14 s is as large as its change. Otherwise a flight
    // shorter than one step (late bounces: an explicit method steps over a free fall's
    // parabola in one step) begins and ends below zero and its impact is missed, or the
    // noise makes a crossing at once. So the event function is gap + lift, the lift from
    // `lift` at `lift_at` (the gap's deficit and kLiftRoundoffs round-offs of its terms) to 0
    // over `lift_for` (the time the rebound takes to rise twice the lift): positive from the
    // rebound on, and exactly the gap once the flight is on its way (no offset kept).
    double lift = 0.0, lift_at = 0.0, lift_for = 0.0;
  };
  // Side i's gap, row J (nu) and bias c (d2g/dt2 = J udot + c) at (t, y).
  int Row(rt::Workspace& ws, double t, const double* y, const Side& s, double* gap, double* J, double* c);
  // A side struck together with the impact's own (Impact): its gap rate and logged speed
  // before, and whether it rests after.
  struct Strike {
    int side = -1;
    double v = 0.0, before = 0.0;
    bool rest = false;
    // Its gap rate after the impact (Newton's -e v, 0 for a rest; 0 for a side Complementary
    // brings in because the others' blow would press it through its contact).
    double after = 0.0;
  };
  // Impact's parts: the sides striking with side i, the complementary impulse, the
  // companions' speeds after and their log entries (sim/end_stops.cpp).
  int Companions(rt::Workspace& ws, double t, const double* y, int i, double t_inf, std::vector<Strike>* with);
  int Complementary(rt::Workspace& ws, double t, const double* y, std::vector<int>* rows, std::vector<double>* targets,
                    std::vector<Strike>* with, std::vector<double>* du, std::vector<int>* left,
                    bool join_closing);
  int StruckWith(rt::Workspace& ws, double t, const double* y, const std::vector<Strike>& with,
                 std::vector<EventRecord>* struck);
  // Moves side s's joint onto its stop if it is past it (sim/end_stops.cpp).
  void OntoStop(const Side& s, double* y) const;
  // The kinetic energy's change by the speeds' jump du at (t, y), and the scale of its terms.
  int KineticChange(rt::Workspace& ws, double t, const double* y, const std::vector<double>& du, double* dT,
                    double* ref);
  // A flight leaving the contact at gap rate v > 0 under the gap acceleration a < 0 rises
  // v^2 / (2 |a|): at most kUnresolvedHeights of the tolerance, within the gap's own error,
  // the root finding cannot resolve it.
  bool Unresolved(const Side& s, double v, double a) const {
    return v > 0.0 && a < 0.0 && v * v / (2.0 * -a) <= kUnresolvedHeights * (atol_ + rtol_ * Scale(s));
  }
  void Lift(Side& s, double t, double gap, double rate);  // Side::lift after a rebound at t
  static double LiftAt(const Side& s, double t);         // its value at t
  double Restitution(const Side& s) const;
  std::string SingularRows(const std::vector<int>& rows) const;  // error_ of a singular impulse
  double Scale(const Side& s) const;  // the gap's length scale for the tolerances
  std::string Element(const Side& s) const;
  std::string Who(const Side& s) const { return (s.plane >= 0 ? "contact '" : "joint '") + Element(s) + "'"; }
  std::string Where(const Side& s) const;  // "q_min", "q_max", "the plane"
  // Speeds' jump du = X c with J_r du = target_r for the rows: e_k for each k in `speeds`
  // (first), then the sides `rows` (X = M^-1 J^T columns, the speed rows' from one
  // factorization). Dependent rows take the least impulses (SolveHeld) where the targets
  // agree to `slack` (their round-off: a jump's is the speeds' kRestSpeeds atol). 0, or
  // Derivative's codes.
  int Impulse(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds, const std::vector<int>& rows,
              const std::vector<double>& targets, double* du, std::vector<double>* c, double slack = 0.0);
  // Resting sides' reactions at (t, y) (in the order of sides_, 0 where not resting) and
  // the held accelerations (nu, may be null).
  int Reactions(rt::Workspace& ws, double t, const double* y, std::vector<double>* lambda, double* a_held,
                std::vector<double>* noise = nullptr);
  // Reactions from the free accelerations a (nu) at (t, y), with the rows of `speeds` first
  // (HoldWith; *forces their forces, may be null when there are none; noise only without them).
  int Held(rt::Workspace& ws, double t, const double* y, const double* a, const std::vector<int>& speeds,
           std::vector<double>* lambda, double* a_held, std::vector<double>* noise, std::vector<double>* forces);
  // *noise: per resting side (rows, their biases), the round-off scale of its reaction; uses
  // Impulse's last columns (x_, Jrows_) and the accelerations in a_.
  int ReactionNoise(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                    const std::vector<double>& bias, std::vector<double>* noise);
  // The impact of side i at (t, y) with gap rate v < 0 (the bounce, a rest, or the
  // accumulation of the bounces); y jumps in place. `settle`: then Settle the resting set.
  int Impact(rt::Workspace& ws, double t, double* y, int i, double v, bool settle);
  // The resting set made consistent at (t, y) (a complementarity problem, solved by
  // principal pivoting): resting sides pull (lambda <= 0) -> they leave; sides on their
  // contact at rest (gap, gap rate within the tolerances) whose gap would close -> they rest
  // (their gap rate zeroed by an impulse, the others held). Logs the changes since `before`.
  int Settle(rt::Workspace& ws, double t, double* y, const std::vector<char>& before);
  // The resting plane contacts' gap rates set to 0 at (t, y) by one impulse (the others
  // resting held with them; Settle's last step, so at every event): the held rows keep the
  // gap accelerations at 0, not the rates, and a rate the integration left in a row when it
  // came to rest would otherwise stay and move the gap through the plane at that rate for
  // the whole rest (a velocity projection in the mass metric, as Simbody projects u onto its
  // constraints; here at the restarts only, where the rows change). No friction mu N (its
  // impulse is a friction law's, not a projection's).
  int ZeroRestingRates(rt::Workspace& ws, double t, double* y);
  // pinned_ for the resting set at (t, y) (Functions computes it where the set changed).
  int Pinned(rt::Workspace& ws, double t, const double* y);
  bool PinnedFor() const {  // pinned_ is the current resting set's (RestingSet() == pinned_for_)
    if (pinned_for_.size() != sides_.size()) return false;
    for (size_t i = 0; i < sides_.size(); ++i)
      if ((sides_[i].resting ? 1 : 0) != pinned_for_[i]) return false;
    return true;
  }
  // Side i's gap acceleration at (t, y) were it free (the other resting sides held).
  int GapAcceleration(rt::Workspace& ws, double t, const double* y, int i, double* a);
  // With Coulomb friction mu N (sim/end_stops_friction.cpp): the resting sides'
  // reactions c (rows, targets as Reactions builds them) and the held accelerations a (nu),
  // by the tree's fixed point with the reactions included; an impulse on the sides' rows with
  // the friction joints' impulses (sim/friction_impulse.h).
  int ReactionsMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                  const std::vector<double>& bias, std::vector<double>* c, double* a);
  int ImpulseMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                const std::vector<double>& targets, double* du, std::vector<double>* c);
  int HeldJumpMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds,
                 const std::vector<double>& targets, double* du, std::vector<double>* F);
  // Held at the stop (sim/end_stops.cpp (3)): the static friction mu_s r N + C_s of the
  // side's joint with exact friction (N from ws's last evaluation), the most it adds to the
  // stop's reaction against a pull; 0 without. A resting side's margin before it leaves: that
  // bound and its reaction's round-off noise (a pull exactly at the bound holds).
  double StaticFriction(const rt::Workspace& ws, const Side& s) const;
  double LeaveMargin(const rt::Workspace& ws, const Side& s, double noise) const { return StaticFriction(ws, s) + noise; }
  // Side i stops resting; one held with its friction slides away from it (released_).
  void Leave(rt::Workspace& ws, int i);
  // Settle's release of the joints held at their stops with their friction (sim/
  // stop_releases.cpp): the set released decided together, consistent with every stuck
  // force solved for it, left (Leave; *released). *released false where no set is
  // consistent or the sides are too many (Settle lets them go one at a time). 0, or the
  // status of an evaluation that failed.
  int ReleaseTogether(rt::Workspace& ws, double t, const double* y, bool* released);
  // A held side with friction (its joint's exact friction holds it beside the stop).
  bool HeldWithFriction(const Side& s) const {
    return s.stop >= 0 && friction_of_[static_cast<size_t>(s.stop)] >= 0;
  }
  bool Released(const Side& s) const;  // its joint in released_
  // The sides `rows` appended as FrictionJump's rows J and their own normal impulses.
  int JumpRows(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows, std::vector<double>* J,
               std::vector<double>* row_normals);

  const rt::Program& program_;
  std::vector<rt::EndStop> stops_;
  std::vector<rt::PlaneContact> planes_;
  std::vector<Side> sides_;
  int nq_ = 0, nu_ = 0;
  double rtol_ = 0.0, atol_ = 0.0;
  std::vector<double> ydot_, x_, a_, J_, Jrows_, M_, cols_;  // scratch
  std::vector<size_t> nonzero_;  // Impulse: the nonzero entries of each row of J (scratch)
  std::vector<double> impulse_F_;  // Impulse(Mu)'s generalized impulse on the free speeds (PullingContact)
  std::vector<EventRecord> log_;
  std::vector<double> held_lambda_;  // the last HoldWith's reactions per side (empty: none resting)
  bool mu_ = false;  // friction joints with mu (sim/friction_impulse.h)
  std::vector<int> opening_;  // RestOnRows: closed sides the slide opens (not joined by the next Settle)
  std::vector<rt::FrictionJoint> frictions_;  // the program's (rt::FrictionJoints)
  std::vector<int> friction_of_;              // per stop: its joint's exact friction (index), or -1
  std::vector<std::pair<int, int>> released_;  // TakeReleased
  // Per side: its row is in the span of the resting sides' rows (Pinned), for the resting
  // set pinned_for_: its gap rate is held at 0 with theirs, its graze guard constant 1.
  std::vector<char> pinned_, pinned_for_;
  bool defer_ = false;                          // DeferFrictionReleases
  bool plastic_tail_ = false;                   // Settle's second round: every restitution 0
  StickSlipEvents* stick_ = nullptr;            // SetStickSlip (not owned; null: none)
  std::string error_;
};

}  // namespace kanesim::sim
