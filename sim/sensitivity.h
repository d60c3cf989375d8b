// Forward parameter sensitivities of a run (`kanesim run --sensitivity p1,p2`; issue 44,
// docs/integrators.md "Parameter sensitivities"): for every written signal y and every
// parameter p, the column d(y)/d(p) beside y.
//
// The method: the variational equations integrated with the motion ("internal
// differentiation"). With the state y' = f(y, p) and s_k = dy/dp_k,
//     s_k' = (df/dy) s_k + df/dp_k,    s_k(t0) = dy0/dp_k,
// integrated by the same integrator in one state [y, s_1, ..., s_m], so its error test
// controls the sensitivities too. Both terms by central differences: (df/dy) s_k along
// s_k in y (a step scaled to |y| and |s_k|), df/dp_k between the programs at p_k +/- delta
// (the caller rebinds them; sim sees no compiler). Outputs the same way:
// dg/dp_k = (dg/dy) s_k + dg/dp_k. Cost: 1 + 4m evaluations of f per evaluation.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/csv.h"
#include "sim/simulate.h"

namespace kanesim::sim {

// One parameter: the program with it at value +/- delta, every other value the same. A start
// value (start_value: "j.q.start") moves only the start, s_k(t0) = dy0/dp_k, and df/dp_k = 0:
// its programs are read for their assembled start only.
// plus2 / minus2 (at +/- 2 delta, may be null) give the differences' error estimates
// (SimStats::sensitivity, `--stats`).
struct SensitivityParam {
  std::string name;
  double delta = 0.0;
  std::shared_ptr<const rt::Program> plus, minus;
  bool start_value = false;
  std::shared_ptr<const rt::Program> plus2, minus2;
};

// The column name of dy/dp: "d(y)/d(p)".
std::string SensitivityColumn(const std::string& signal, const std::string& param);

// The inverse: "d(y)/d(p)" -> y, p; false for any other name.
bool SplitSensitivityColumn(const std::string& column, std::string* signal, std::string* param);

// The parameter step for a value p: cbrt(eps) max(|p|, 1e-3) (the central difference's
// truncation and round-off errors balanced for a derivative of order one).
double SensitivityStep(double p);

// Simulate with the sensitivities: the sink receives the signals, then for every signal
// (in order) its derivative by every parameter (in order). Models with end stops are refused
// (a usage error): the jump conditions of the sensitivities at events are not implemented.
// The energy guard is not applied (the augmented state is not a conservative system's).
SimResult SimulateSensitivities(const rt::Program& program, const std::vector<SensitivityParam>& params,
                                const SimOptions& options, SignalSink& sink);

}  // namespace kanesim::sim
