// Exact Coulomb friction on joints as events (stdlib `friction_exact = true`; docs/stdlib.md
// "Revolute"): a joint slides with the friction force -(mu r N + C) sign(u) (no
// regularization speed; C the constant friction, friction_torque / friction_force), and where
// its speed reaches zero it sticks: its speed held at zero by a friction force tau (one more
// row) as long as |tau| <= mu_s r N + C_s; when the needed force would pass that bound it
// slides again, in the direction the force pulls it. Each joint's switch is an event
// function: s u while sliding in direction s, mu_s r N + C_s - |tau| while stuck.
#pragma once

#include <string>
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
  // The start: a joint moving slides that way; at rest it sticks or slides (the stick test).
  int Start(rt::Workspace& ws, double t0, double* y0);
  // ydot at (t, y) with every exact joint's law applied: sliding ones by their sign, stuck
  // ones held (their friction forces solved so that their accelerations vanish). Replaces
  // Derivative's ydot. 0, or Derivative's codes.
  int Rhs(rt::Workspace& ws, double t, const double* y, double* ydot);
  int Functions(rt::Workspace& ws, double t, const double* y, double* g);
  // Joint i stopped (sliding) or its needed force reached mu_s r N (stuck); y jumps in place.
  int Event(rt::Workspace& ws, double t, double* y, int i);
  // The friction laws of the run into another workspace (the output rows').
  void Sync(rt::Workspace& ws) const;
  const std::vector<EventRecord>& Log() const { return log_; }
  // Why the last call failed where the equations could be evaluated ("" otherwise).
  const std::string& Error() const { return error_; }
  // Joint i's free speed and its mode (+1 / -1 sliding that way, 0 stuck).
  int SpeedOf(int i) const { return joints_[static_cast<size_t>(i)].f.u; }
  int ModeOf(int i) const { return joints_[static_cast<size_t>(i)].mode; }
  bool AnyStuck() const {
    for (const Joint& j : joints_)
      if (j.mode == 0) return true;
    return false;
  }
  // linearize's operating point (docs/linearize.md): a joint moving (|u| > tol) slides that
  // way, one at rest sticks; "" when that holds, else why not (a joint at rest whose needed
  // friction passes mu_s r N slips at once: no smooth state).
  std::string SettleAt(rt::Workspace& ws, double t, const double* y, double tol);
  // Per joint its mode (+1, -1 sliding that way, 0 stuck, 2 held by resting stops through the
  // rows: MarkHeldByStops) and holding force, two numbers a joint: what a saved state and the
  // output rows' held solve (sim/held_outputs.cpp) need (sim/hybrid_ode.h).
  std::vector<double> Modes() const {
    std::vector<double> m;
    for (const Joint& j : joints_) m.insert(m.end(), {j.by_stops ? 2.0 : static_cast<double>(j.mode), j.tau});
    return m;
  }
  void SetModes(const std::vector<double>& m) {
    for (size_t i = 0; i < joints_.size() && 2 * i + 1 < m.size(); ++i) {
      joints_[i].by_stops = m[2 * i] == 2.0;
      joints_[i].mode = joints_[i].by_stops ? 0 : static_cast<int>(m[2 * i]);
      joints_[i].tau = m[2 * i + 1];
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
    double tau = 0.0;  // stuck: the friction force holding it (last solved)
    bool by_stops = false;  // at rest with its motion fixed by resting stops through the rows
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
  // X of (1) in stick_slip.cpp at (t, y) for the stuck joints, a0 their accelerations (ydot).
  int MakeX(rt::Workspace& ws, double t, const double* y, const std::vector<Joint*>& stuck, const double* a0);
  // rt::Derivative with the stops' resting sides held.
  int Eval(rt::Workspace& ws, double t, const double* y, double* ydot);
  bool HeldByStop(const Joint& j, const std::vector<int>& resting) const;
  std::vector<int> RestingSpeeds() const;
  // At rest (u = 0): stuck when the force that holds it is within mu_s r N, else sliding.
  int Decide(rt::Workspace& ws, double t, double* y, Joint& j);
  // Constraint rows (closed loops, couplings, rolling contacts): X is the constrained inverse
  // mass of the stuck speeds, which the rows may make singular. 0 when X is regular (it is
  // kept for Solve), 1 when j alone cannot be held (a dead point: the rows move it), -1 with
  // error_ when stuck joints' motions are dependent (their forces not unique).
  int CheckRows(rt::Workspace& ws, double t, const double* y, const Joint& j);
  // Beside rows with stops resting: marks the joints at rest (|u| <= v_rest) whose motion the
  // resting stops fix through the rows (a gear's follower when its leader rests): held by the
  // stops as a stop's own joint is, their friction force not determined, so zero.
  int MarkHeldByStops(rt::Workspace& ws, double t, const double* y, double v_rest);
  // Beside rows: j's evaluated speed to zero by the jump that keeps the rows (stick_slip.cpp).
  int StopOnRows(rt::Workspace& ws, double t, double* y, const Joint& j);

  const rt::Program& program_;
  bool rows_ = false;               // constraint rows: CheckRows at each stick decision
  EndStopEvents* stops_ = nullptr;  // SetStops (null: none)
  std::vector<Joint> joints_;
  int nq_ = 0, nu_ = 0;
  bool direct_ = true;  // constant friction on a tree: (2) of stick_slip.cpp, else Newton (1)
  std::vector<double> ydot_, col_;  // scratch (col_: MakeX's evaluations)
  std::vector<double> x_;     // X of the stuck set x_ids_ (friction joint indices), m x m row-major
  std::vector<int> x_ids_;
  std::vector<EventRecord> log_;
  std::string error_;
};

}  // namespace kanesim::sim
