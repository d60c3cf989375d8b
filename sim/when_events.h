// When clauses as events (docs/events.md): each condition's indicator h (positive where the
// condition holds) gives the event function g = -h, so a clause fires where g crosses zero
// downwards like an end stop's gap; the clause then sets its coordinates, jumps its speeds by
// an impulse through the mass matrix (sim/impulse.h) and may end the run.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/simulate.h"

namespace kanesim::sim {

class WhenEvents {
 public:
  explicit WhenEvents(const rt::Program& program);
  // The run's relative tolerance: the accumulation of a clause's events is taken as reached
  // when less than kZenoTimes of it (times max(1, |t|)) is left to the accumulation point.
  void SetTolerance(double rtol) { rtol_ = rtol; }
  static constexpr double kZenoTimes = 100.0;
  bool Active() const { return !clause_of_.empty(); }
  int Count() const { return static_cast<int>(clause_of_.size()); }
  // g_i = -h_i for every indicator of every clause, in order. 0, or Derivative's codes.
  int Functions(rt::Workspace& ws, double t, const double* y, double* g);
  // The speeds' jump du (nu entries) that changes the free speeds `rows` by `targets`:
  // 0, Derivative's codes, or -1 when it has no unique solution.
  using JumpSolver = std::function<int(const std::vector<int>& rows, const std::vector<double>& targets, double* du,
                                       std::vector<double>* F)>;
  // Indicator i crossed at (t, y): its clause's reinits, every value taken at the left limit;
  // coordinates set, then the speeds by one impulse: `solve` (null: SpeedJump, the impulse
  // on those speeds alone, with Coulomb friction impulses where a joint has mu: FrictionSpeedJump; EndStopEvents::HeldJump also holds the resting contacts). y jumps
  // in place.
  int Event(rt::Workspace& ws, double t, double* y, int i, const JumpSolver& solve = nullptr);
  // The entries of y that indicator i's clause sets (coordinates and speeds).
  std::vector<int> States(int i) const;
  // Indicator i's clause: "when (file.mech:12)".
  const std::string& Name(int i) const;
  // terminate(...) fired: the run ends at the event (its message).
  bool Terminated() const { return terminated_; }
  const std::string& Message() const { return message_; }
  // The record of the last Event (element, kind).
  const EventRecord& Last() const { return last_; }
  // Why the last Event's speed jump had no solution ("" when it had).
  const std::string& Error() const { return error_; }

 private:
  std::string SingularJump(const std::string& clause) const;
  // Clause c fires at t: "" or why the run stops there (its events accumulate).
  std::string Accumulation(int c, double t);
  // Per clause: its last fire times and, once they shrink geometrically, the ratio and the
  // accumulation point of the series (sim/when_events.cpp "Accumulation").
  struct History {
    std::vector<double> times;
    bool geometric = false;
    double ratio = 0.0, t_inf = 0.0, since = 0.0;  // since: the first time of the geometric stretch
  };
  std::vector<History> history_;
  double rtol_ = 1e-6;
  const rt::Program& program_;
  std::vector<int> clause_of_, root_of_;  // per indicator: its clause, its tape root
  int nq_ = 0, nu_ = 0;
  bool friction_ = false;  // a joint with mu: the jump takes friction impulses (sim/friction_impulse.h)
  bool terminated_ = false;
  std::string message_, error_;
  EventRecord last_;
};

}  // namespace kanesim::sim
