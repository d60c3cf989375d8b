// `kanesim run --units-in-header`: each CSV column's unit, from the flat mechanism (joint
// types, the outputs' checked units, the kinds of frame and body signals), appended to its
// name in the header: `hinge.q [rad]`. A column of no unit (a residual) keeps its name.
#pragma once

#include <string>
#include <vector>

#include "flat/flat.h"
#include "sim/sim.h"

namespace kanesim::cli {

// The unit of signal `name` ("rad/s", "N.m", "1"), or "" when it has none or is not known.
std::string SignalUnit(const flat::Mechanism& m, const std::string& name);

// Passes everything to `inner`, the header's names with their units.
class UnitsInHeader final : public sim::SignalSink {
 public:
  UnitsInHeader(const flat::Mechanism& m, sim::SignalSink& inner) : m_(m), inner_(inner) {}
  bool Begin(const std::vector<std::string>& names) override;
  bool Row(double t, const double* values, size_t count) override { return inner_.Row(t, values, count); }
  bool End() override { return inner_.End(); }

 private:
  const flat::Mechanism& m_;
  sim::SignalSink& inner_;
};

}  // namespace kanesim::cli
