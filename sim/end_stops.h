// End stops as events (docs/integrators.md "End stops"): the stop's gap as an event function,
// the impact as a jump of the speeds by a generalized impulse through the mass matrix, and a
// joint resting on its stop held there by the stop's reaction until that reaction would pull.
#pragma once

#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/simulate.h"

namespace kanesim::sim {

class EndStopEvents {
 public:
  // rtol, atol: the run's; a rebound slower than kRestSpeeds of them rests on the stop.
  EndStopEvents(const rt::Program& program, double rtol, double atol);
  bool Active() const { return !sides_.empty(); }
  int Count() const { return static_cast<int>(sides_.size()); }
  // Why the start state cannot run ("" when it can): a joint past its stop.
  std::string CheckStart(const double* y0) const;
  // Why an output row cannot be trusted ("" when it can): a joint past its stop by more than
  // the tolerance's reach, which an event missed (accumulating impacts, a graze inside one
  // step). The run then stops (exit 2) rather than write a motion through the stop.
  std::string CheckRow(double t, const double* y) const;
  // The start on a stop: a joint at its limit moving into it, or at rest pressed onto it,
  // handled as an event at t0 (no rows).
  int Start(rt::Workspace& ws, double t0, double* y0);
  // ydot (from rt::Derivative at (t, y)) with the resting joints held: their accelerations
  // made zero by their stops' reactions. 0, or Derivative's status codes.
  int Hold(rt::Workspace& ws, double t, const double* y, double* ydot);
  // g_i: a free side's gap (q - q_min, q_max - q), a resting one's reaction (pushing: > 0).
  int Functions(rt::Workspace& ws, double t, const double* y, double* g);
  // Event function i crossed zero at (t, y): an impact (or the joint comes to rest), or a
  // resting joint leaves its stop. y jumps in place.
  int Event(rt::Workspace& ws, double t, double* y, int i);
  const std::vector<EventRecord>& Log() const { return log_; }
  // The free speeds of the joints resting on their stops (held at zero).
  std::vector<int> RestingSpeeds() const {
    std::vector<int> out;
    for (const Side& s : sides_)
      if (s.resting) out.push_back(stops_[static_cast<size_t>(s.stop)].u);
    return out;
  }

  // A rebound speed at most this many times (atol + rtol |speed before|) ends in rest.
  static constexpr double kRestSpeeds = 100.0;
  // An output row past a stop by more than this many (atol + rtol max(1, |limit|)) stops the run.
  static constexpr double kPastRows = 10.0;

 private:
  struct Side {
    int stop = 0;
    bool upper = false;  // q_max (else q_min)
    bool resting = false;
  };
  double Limit(const Side& s) const;
  // Speeds' jump du = X c with (X c)_k = target for the speeds `rows` (X = M^-1 columns):
  // the impulse that sets those joints' speed changes. 0, or Derivative's codes.
  int Impulse(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
              const std::vector<double>& targets, double* du, std::vector<double>* c);
  // Resting sides' reactions at (t, y) (in the order of sides_, 0 where not resting) and
  // the held accelerations (nu, may be null).
  int Reactions(rt::Workspace& ws, double t, const double* y, std::vector<double>* lambda, double* a_held);
  double Reaction(const Side& s, double lambda) const { return s.upper ? -lambda : lambda; }

  const rt::Program& program_;
  std::vector<rt::EndStop> stops_;
  std::vector<Side> sides_;
  int nq_ = 0, nu_ = 0;
  double rtol_ = 0.0, atol_ = 0.0;
  std::vector<double> ydot_, x_, a_;  // scratch
  std::vector<EventRecord> log_;
};

}  // namespace kanesim::sim
