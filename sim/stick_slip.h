// Exact Coulomb friction on joints as events (stdlib `friction_exact = true`; docs/stdlib.md
// "Revolute"): a joint slides with the friction force -(mu r N + C) sign(u) (no
// regularization speed; C the constant friction, friction_torque / friction_force), and where
// its speed reaches zero it sticks: its speed held at zero by a friction force tau (one more
// row) as long as |tau| <= mu_s r N + C_s; when the needed force would pass that bound it
// slides again, in the direction the force pulls it. Each joint's switch is an event
// function: s u while sliding in direction s, mu_s r N + C_s - |tau| while stuck.
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "runtime/runtime.h"
#include "sim/simulate.h"

namespace kanesim::sim {

class EndStopEvents;

class StickSlipEvents {
 public:
  explicit StickSlipEvents(const rt::Program& program);
  bool Active() const { return !joints_.empty(); }
  // End stops in the same model (constant friction only; compiler/plane_contacts.cpp): every
  // evaluation holds their resting sides too (EndStopEvents::Hold), so the stuck joints'
  // forces and the stops' reactions are solved together; a joint resting on its stop is held
  // by the stop alone (its friction 0, not a second row on the same speed), until the pull
  // away passes its static friction (sim/end_stops.cpp (3)): then it slides away.
  void SetStops(EndStopEvents* stops) { stops_ = stops; }
  // After an impact or a rest on a stop took y_before to y at t: a joint the impulse set moving
  // faster than v_rest slides that way (a stuck one slower stays stuck, its speed zeroed), one
  // now resting on its stop is the stop's, one stopped by it decides (stick or slip); a joint
  // whose speed the event left alone keeps its law.
  int Refresh(rt::Workspace& ws, double t, double* y, const double* y_before, double v_rest);
  int Count() const { return static_cast<int>(joints_.size()); }
  // The stuck joints' forces solved again at (t, y) (after a jump changed the speeds).
  int Resolve(rt::Workspace& ws, double t, const double* y) { return Solve(ws, t, y, nullptr); }
  // The joints of `laws` (free speed, law: 0 held by its resting stop, +1 / -1 sliding that
  // way off it) set so, and the stuck joints' forces solved again at (t, y): one trial of
  // EndStopEvents::ReleaseTogether (sim/stop_releases.cpp).
  int AtStops(rt::Workspace& ws, double t, const double* y, const std::vector<std::pair<int, int>>& laws);
  // The start: a joint moving slides that way; at rest it sticks or slides (the stick test).
  int Start(rt::Workspace& ws, double t0, double* y0);
  // ydot at (t, y) with every exact joint's law applied: sliding ones by their sign, stuck
  // ones held (their friction forces solved so that their accelerations vanish). Replaces
  // Derivative's ydot. 0, or Derivative's codes.
  int Rhs(rt::Workspace& ws, double t, const double* y, double* ydot);
  int Functions(rt::Workspace& ws, double t, const double* y, double* g);
  // The graze guards of the last Functions' evaluation (OdeSystem::Paired): a sliding joint's
  // -s udot, crossing where its speed s u has a minimum (a dip below zero and back inside
  // one step, which the speed's signs at the step's ends do not show); 1 for the others
  // (and beside constraint rows, where a dependent speed's rate is not solved).
  void Guards(double* g) const;
  // Joint i stopped (sliding) or its needed force reached mu_s r N (stuck); y jumps in place.
  // Then the laws at rest are made consistent together (CheckLaws): -1 with Error() where
  // none is (Painleve-type).
  int Event(rt::Workspace& ws, double t, double* y, int i);
  // With constant friction (direct_) and end stops, in a tree: every speed at rest, the
  // stuck and sliding joints' and the joints' on their stops (resting or not), decided as the
  // one box LCP (6) of stick_slip_laws.cpp, the stops' sides and the friction laws set from
  // it where they then meet (5) and no resting side pulls beyond its margin (*solved, the
  // changes logged; y's speeds set resting are zeroed); else all left as they were. After an
  // event whose sequential settling left a side at rest accelerating into its stop.
  int LawsWithStops(rt::Workspace& ws, double t, double* y, bool* solved);
  // The friction laws of the run into another workspace (the output rows').
  void Sync(rt::Workspace& ws) const;
  const std::vector<EventRecord>& Log() const { return log_; }
  // Why the last call failed where the equations could be evaluated ("" otherwise).
  const std::string& Error() const { return error_; }
  // Joint i's free speed and its mode (+1 / -1 sliding that way, 0 stuck).
  int SpeedOf(int i) const { return joints_[static_cast<size_t>(i)].f.u; }
  int ModeOf(int i) const { return joints_[static_cast<size_t>(i)].mode; }
  // Joint i's own law watches it (Functions): not a passenger, not resting on its stop.
  bool Watched(int i) const {
    const Joint& j = joints_[static_cast<size_t>(i)];
    return j.leader < 0 && !HeldByStop(j, RestingSpeeds());
  }
  // Some exact joint's friction follows its normal force (mu N): Rhs iterates (OdeSystem::IteratedRhs).
  bool ReadsNormalForce() const { return reads_N_; }
  bool AnyStuck() const {
    for (const Joint& j : joints_)
      if (j.mode == 0) return true;
    return false;
  }
  // linearize's operating point (docs/linearize.md): a joint moving (|u| > tol) slides that
  // way, one at rest sticks; "" when that holds, else why not (a joint at rest whose needed
  // friction passes mu_s r N slips at once: no smooth state).
  std::string SettleAt(rt::Workspace& ws, double t, const double* y, double tol);
  // Per joint its mode (+1, -1 sliding that way, 0 stuck, 2 held by resting stops or plane
  // contacts through the rows: MarkHeldByStops), holding force, leader (-1: none) and ratio
  // (Joint), kModeValues numbers a joint: what a saved state and the output rows' held solve
  // (sim/held_outputs.cpp) need (sim/hybrid_ode.h).
  static constexpr size_t kModeValues = 4;
  std::vector<double> Modes() const {
    std::vector<double> m;
    for (const Joint& j : joints_)
      m.insert(m.end(), {j.by_stops ? 2.0 : static_cast<double>(j.mode), j.tau, static_cast<double>(j.leader), j.ratio});
    return m;
  }
  void SetModes(const std::vector<double>& m) {
    grouped_ = false;
    for (size_t i = 0; i < joints_.size() && kModeValues * i + kModeValues - 1 < m.size(); ++i) {
      const double* v = m.data() + kModeValues * i;
      joints_[i].by_stops = v[0] == 2.0;
      joints_[i].mode = joints_[i].by_stops ? 0 : static_cast<int>(v[0]);
      joints_[i].tau = v[1];
      const int leader = static_cast<int>(v[2]);
      joints_[i].leader =
          leader >= 0 && leader < Count() && joints_[i].mode == 0 && !joints_[i].by_stops ? leader : -1;
      joints_[i].ratio = v[3];
      grouped_ = grouped_ || joints_[i].leader >= 0;
    }
  }
  std::vector<std::string> JointNames() const {
    std::vector<std::string> names;
    for (const Joint& j : joints_) names.push_back(j.f.joint);
    return names;
  }
  // The stuck joints' free speeds and names.
  std::vector<int> StuckSpeeds() const;
  std::vector<std::string> StuckNames() const;

 private:
  struct Joint {
    rt::FrictionJoint f;
    int index = 0;     // among the program's friction joints (rt::FrictionJoints)
    int mode = 0;      // +1 / -1 sliding that way, 0 stuck
    // stuck: the friction force holding it (last solved); a leader's: its group's, reflected
    // onto it (T of stick_slip.cpp (4)), which Applied shares out
    double tau = 0.0;
    bool by_stops = false;  // at rest with its motion fixed by resting stops through the rows
    // A stuck joint whose speed the rows tie to another stuck joint's (a passenger): that
    // joint's index in joints_ (its leader, whose row holds both), else -1; ratio: the
    // passenger's u = ratio u_leader (stick_slip.cpp (4)).
    int leader = -1;
    double ratio = 0.0;
    long stamp = 0;  // the Decide that last set its law (Refresh and Start decide each joint once)
    double slipped_at = -HUGE_VAL;  // when its needed force last passed its bound (Switch)
  };
  // The stuck joints' friction forces at (t, y) (Newton on their accelerations, which are
  // affine in them), the modes applied to ws; ydot (may be null) the held motion.
  int Solve(rt::Workspace& ws, double t, const double* y, double* ydot);
  // (2) of stick_slip.cpp without stops: the stuck speeds' rows from one factorization; a (nu)
  // the free accelerations, made the held ones; *dtau the forces' increments.
  int HoldSpeeds(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds, double* a,
                 std::vector<double>* dtau);
  // (1) of stick_slip.cpp (a friction mu N): Newton on the stuck accelerations; out the held motion.
  int SolveNewton(rt::Workspace& ws, double t, const double* y, double* out, const std::vector<Joint*>& stuck);
  void Apply(rt::Workspace& ws) const;
  // The stuck joint's bound mu_s r N + C_s, N from ws's last evaluation.
  double StaticBound(const rt::Workspace& ws, const Joint& j) const;
  // A leader's group bound B_g of (4) in stick_slip.cpp (StaticBound without passengers).
  double GroupBound(const rt::Workspace& ws, const Joint& leader) const;
  // The force Apply gives stuck joint j: its tau, or its share of its group's (4).
  double Applied(const rt::Workspace& ws, const Joint& j) const;
  bool Leads(const Joint& j) const;
  // Passengers whose leader no longer holds them (it slid, or rests on a stop) lose it.
  void Ungroup();
  // The group of leader l (l and its passengers) slides the way l's mode says (each passenger
  // the way its ratio takes it) or stays stuck; logs each member whose law changed from
  // `before` (modes per joint), j (the joint that decided, null: none) whatever it was.
  void SettleGroup(const rt::Workspace& ws, double t, Joint& l, const std::vector<int>& before, const Joint* j);

  // X of (1) in stick_slip.cpp at (t, y) for the stuck joints, a0 their accelerations (ydot).
  int MakeX(rt::Workspace& ws, double t, const double* y, const std::vector<Joint*>& stuck, const double* a0);
  // rt::Derivative with the stops' resting sides held.
  int Eval(rt::Workspace& ws, double t, const double* y, double* ydot);
  bool HeldByStop(const Joint& j, const std::vector<int>& resting) const;
  // Beside rows: the stuck joints' rows (leaders') and the resting stops' hold every degree of
  // freedom, and nothing is prescribed: u = 0 is the motion, all of it. A decision that
  // sticks then sets every speed to 0 exactly (StopOnRows leaves the others' round-off, which
  // the multiplier form's projection spread to the stuck speed: 5e-11, before). The rates are
  // left as solved (their round-off, 1e-17): f exactly 0 made DOP853 in the stepping API step
  // over a narrow slip window (HeldStep.ANarrowSlipWindowIsFoundInsideLargeStepsOfTheSimulator).
  bool AllHeld() const;
  std::vector<int> RestingSpeeds() const;
  // Event's own switch of joint i's law.
  int Switch(rt::Workspace& ws, double t, double* y, int i);
  // At rest (u = 0): stuck when the force that holds it is within mu_s r N, else sliding.
  int Decide(rt::Workspace& ws, double t, double* y, Joint& j);
  // After decisions at rest (the start, a slip, a stop, a jump): the laws of the joints at
  // rest consistent together ((5) of stick_slip_laws.cpp: stuck ones within their bounds,
  // sliding ones accelerating their way), else enumerated; the decisions since `from`
  // (Joint::stamp) first; `slipped`, whose needed force has just passed its bound (its event),
  // is not stuck again. -1 with error_ where no choice is consistent (Painleve-type).
  int CheckLaws(rt::Workspace& ws, double t, double* y, long from, const Joint* slipped = nullptr);
  // With constant friction (direct_): the laws of at_rest as the one box LCP (6) of
  // stick_slip_laws.cpp, set and logged where they meet (5) (*solved), else left to the caller
  // (before: the modes to log against). 0, or an evaluation's status.
  int LawsAtRestTogether(rt::Workspace& ws, double t, double* y, const std::vector<Joint*>& at_rest,
                         const Joint* slipped, const std::vector<int>& before, bool* solved);
  // (5)'s violators among at_rest under the laws as they are (*status: Solve's).
  std::vector<Joint*> Inconsistent(rt::Workspace& ws, double t, double* y, const std::vector<Joint*>& at_rest,
                                   int* status);
  // Constraint rows (closed loops, couplings, rolling contacts): X is the constrained inverse
  // mass of the stuck speeds, which the rows may make singular. The stuck joints, j among
  // them, and the sliding ones the rows tie to them are grouped by (4) of stick_slip.cpp (a
  // sliding joint tied to stuck ones is at rest with them: it joins). 0 when grouped, 1 when
  // j alone cannot be held (a dead point: the rows move it), -1 with error_ where a speed is
  // tied to several groups' (their shares not solved) or a stuck joint's is fixed by the rows.
  int CheckRows(rt::Workspace& ws, double t, const double* y, const Joint& j);
  // Beside rows with stops or plane contacts resting: marks the joints at rest (|u| <= v_rest)
  // whose motion they fix through the rows (a gear's follower when its leader rests): held by the
  // stops as a stop's own joint is, their friction force not determined, so zero.
  int MarkHeldByStops(rt::Workspace& ws, double t, const double* y, double v_rest);
  // Beside rows: j's evaluated speed to zero by the jump that keeps the rows (stick_slip.cpp).
  int StopOnRows(rt::Workspace& ws, double t, double* y, const Joint& j);
  // Refresh in a tree: the free speeds `moving` (stuck joints at a rest speed) brought to
  // rest by impulses on them, the other stuck joints and the speeds `resting` (held by their
  // stops) kept at rest: energy taken, never added, as zeroing them alone could.
  int BackToRest(rt::Workspace& ws, double t, double* y, const std::vector<int>& moving,
                 const std::vector<int>& resting);

  const rt::Program& program_;
  bool grouped_ = false;            // some joint is a passenger (Joint::leader)
  long decisions_ = 0;              // Decide's count (Joint::stamp)
  bool rows_ = false;               // constraint rows: CheckRows at each stick decision
  int dof_ = 0;                     // the degrees of freedom (rt::ProgramSummary::dof)
  bool scleronomic_ = false;        // no prescribed motion: held rows leave u = 0 the only motion
  EndStopEvents* stops_ = nullptr;  // SetStops (null: none)
  std::vector<Joint> joints_;
  int nq_ = 0, nu_ = 0;
  bool reads_N_ = false;  // some exact joint's friction mu N follows its normal force
  bool direct_ = true;  // constant friction on a tree: (2) of stick_slip.cpp, else Newton (1)
  std::vector<double> ydot_, col_;  // scratch (col_: MakeX's evaluations)
  // Beside rows: each joint's speed as the last plain evaluation of the state solved it
  // (NoteSpeeds). The workspace's speeds after the stops' holding columns are those
  // columns' own (a unit speed: robot sweep 29, trial 3, read Panda's finger, at rest, at
  // 1 m/s and its slip's StopOnRows set both fingers moving at -1 m/s, +0.015 J).
  std::vector<double> u_eval_;
  void NoteSpeeds(const rt::Workspace& ws);
  std::vector<double> x_;     // X of the stuck set x_ids_ (friction joint indices), m x m row-major
  std::vector<int> x_ids_;
  std::vector<EventRecord> log_;
  std::string error_;
};

}  // namespace kanesim::sim
