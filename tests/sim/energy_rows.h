// The energy guard's measure computed again from written rows, for tests that check it or
// bound a run's energy error with it.
#pragma once

#include <algorithm>
#include <cmath>

#include "sim/csv.h"

namespace kanesim::sim {

// max |E - E0| over the rows, relative to the largest T + |V - V0| so far (the guard's
// measure of the motion: sim/energy_guard.cpp); columns 0 and 1 are T and V.
inline double RelativeEnergyError(const MemorySink& s) {
  const double e0 = s.rows[0][0] + s.rows[0][1], v0 = s.rows[0][1];
  double motion = 0.0, worst = 0.0;
  for (const auto& row : s.rows) {
    motion = std::max(motion, row[0] + std::abs(row[1] - v0));
    if (motion > 0.0) worst = std::max(worst, std::abs(row[0] + row[1] - e0) / motion);
  }
  return worst;
}

}  // namespace kanesim::sim
